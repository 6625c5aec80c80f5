"""The deltas of a CPU's GRAPH FBs after a scan, step switches first.

:func:`publish_fbs` asks each FB's :class:`~web.bus.live.LiveGraph` for its update
(``LiveGraph.changed``: none when nothing a view sees changed) and hands it to the bus as it
is built (``BusPublisher.begin_scan``), so that a message leaves every ``PART`` changed FBs
while the scan thread builds the others. The FBs whose steps switched, were disturbed or
acknowledged in the scan — those with step events in the scan record — come first: what
an operator waits for (a step's colour) leaves before what only refreshes (a contact, a
value, a step time). Each FB's update is whole, so the order among FBs changes nothing a
view ends with.
"""

from __future__ import annotations

from collections.abc import Sequence

from s7graph.engine.record import ScanRecord
from s7graph.web.bus.deltas import PART
from s7graph.web.bus.live import LiveGraph
from s7graph.web.bus.protocol import StepStateUpdate
from s7graph.web.bus.publisher import BusPublisher

__all__ = ["publish_fbs"]


def publish_fbs(
    publisher: BusPublisher,
    lives: Sequence[LiveGraph],
    record: ScanRecord,
    *,
    part: int = PART,
) -> list[tuple[str, StepStateUpdate]]:
    """Publish the scan ``record`` of every FB in ``lives`` (each LiveGraph asked once, in
    the scan thread): those with step events in the scan first, in their order, then the
    others; a message every ``part`` changed FBs (0: one for the scan). Returns the FBs
    that changed, with their updates, in the order they went out."""
    cycle, t_ms = max(record.cycle, 0), max(record.t_ns // 1_000_000, 0)
    out = publisher.begin_scan(cycle, t_ms, part=part)
    later = []
    for live in lives:
        if live.events.of(record, live.graph.db_number):
            update = live.changed(record)
            if update is not None:
                out.add(live.fb, update)
        else:
            later.append(live)
    for live in later:
        update = live.changed(record)
        if update is not None:
            out.add(live.fb, update)
    changed = out.end()
    publisher.scanned(cycle, t_ms)
    return changed
