"""``s7graph sync --connect EP --cpu NAME [--fb FB]``: where the process stands in an FB's
chart (S7-GRAPH's synchronization; docs/semantics.md, "Synchronization"): the CPU judges
every step on the values of its next scan boundary, and the shell prints the steps that
fit — interlock held, no leaving transition held — the likely ones first (a transition
into them holds too), then the others with why not, a line each, the active steps marked.
``--json`` prints the :class:`~web.bus.protocol.SyncReport` as the bus carries it. A
read: no login; resuming at the steps found is ``s7graph set-steps N...`` in MAN.
"""

from __future__ import annotations

import sys

from s7graph.web.bus.client import BusClient
from s7graph.web.bus.protocol import SyncReport, encode
from s7graph.web.cli.net import NetOptions
from s7graph.web.cli.remote import ask, fb_to_read

__all__ = ["TIMEOUT_S", "sync_command", "sync_lines"]

TIMEOUT_S = 10.0
"""How long the shell waits for the CPU's next scan boundary."""


def sync_lines(report: SyncReport, cpu: str) -> list[str]:
    """A head line, then a line per step: the likely ones, the other fitting ones, then
    the rest, each group in chart order."""
    ordered = report.ordered()
    fits = sum(s.fits for s in ordered)
    head = (
        f"{report.fb} on {cpu} · cycle {report.cycle} · {report.state} · {report.mode} · "
        f"{fits} of {len(report.steps)} steps fit"
    )
    width = max((len(s.label) for s in ordered), default=0)
    lines = [head]
    for step in ordered:
        active = "  active" if step.active else ""
        lines.append(f"{step.label:<{width}}  seq {step.sequence}  {step.verdict}{active}")
    return lines


def _report(client: BusClient, fb: str | None) -> SyncReport | None:
    """The report of ``fb`` (default: the CPU's first FB); None when the CPU does not
    answer."""
    status = client.status()
    if status is None:
        return None
    name, why = fb_to_read(status, fb, without="this CPU runs no GRAPH FB: nothing to synchronize")
    if why:
        return SyncReport(error=why)
    return client.synchronization(name, timeout=TIMEOUT_S)


def sync_command(net: NetOptions, *, fb: str | None, as_json: bool = False) -> int:
    """Print where the process stands in ``fb`` (default: the CPU's first FB); 0, or 2
    when the CPU does not answer, runs no such FB or cannot judge it yet."""
    report = ask(net, lambda client: _report(client, fb))
    if isinstance(report, int):
        return report
    if report.error:
        print(f"s7graph: error: {report.error}", file=sys.stderr)
        return 2
    if as_json:
        print(encode(report).decode())
        return 0
    for line in sync_lines(report, net.cpu):
        print(line)
    return 0
