"""``s7graph diag --connect EP --cpu NAME``: the CPU's diagnostic buffer, as STEP 7's
"Module Information → Diagnostic Buffer" lists it — newest first, one line each: its
place (1: the newest), its own number (``#N``: the N-th entry the CPU wrote, kept across
restarts), the time (the wall clock's, local; the CPU clock's when the entry
has none), the event ID as ``16#xxxx``, the OB it requests with its priority class, the
event's text and what the entry says (block, address, message). ``--json`` prints the
:class:`~web.bus.protocol.DiagBuffer` as the bus carries it; ``-n`` how many entries.
A read: no login.
"""

from __future__ import annotations

from s7graph.web.bus.client import BusClient
from s7graph.web.bus.protocol import encode
from s7graph.web.cli.diag_text import event_line, when
from s7graph.web.cli.net import NetOptions
from s7graph.web.cli.remote import ask

__all__ = ["diag_command"]


def diag_command(net: NetOptions, *, n: int = 100, as_json: bool = False) -> int:
    """Print the newest ``n`` entries of ``net.cpu``'s diagnostic buffer (``n`` from 1 to
    ``web.bus.protocol.MAX_DIAG_ENTRIES``: the command line refuses another, as it does any
    number out of its option's range); 0, or 2 when the CPU does not answer."""
    buffer = ask(net, lambda client: BusClient.diag(client, n))
    if isinstance(buffer, int):
        return buffer
    if as_json:
        print(encode(buffer).decode())
        return 0
    if not buffer.entries:
        print(f"the diagnostic buffer of {net.cpu} is empty")
        return 0
    held = f"{len(buffer.entries)} of {min(buffer.total, buffer.capacity)}"
    print(f"Diagnostic buffer of {net.cpu} ({held} entries, newest first)")
    for no, event in enumerate(buffer.entries, 1):
        print(f"{no:>3}  {'#' + str(event.number):<7}  {when(event):<23}  {event_line(event)}")
    return 0
