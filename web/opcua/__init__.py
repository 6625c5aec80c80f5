"""The OPC UA face: an OPC UA server (asyncua) that is a client of the bus, in a process
of its own like the view (``s7graph opcua``, ``s7graph run … --opcua``): the CPU, its FBs'
sequences and steps, the symbol table's operands; the control sequencer's commands as
methods; the message list as alarms and conditions (docs/opcua.md)."""
