"""The bus between a CPU and its views: the typed messages, the key space, the CPU's
side (publisher, gate, force table, online change, the scan boundary) and the client."""
