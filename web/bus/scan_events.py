"""The step events of one scan record, grouped by instance DB once per record.

A CPU with hundreds of GraphFBs has one :class:`~web.bus.live.LiveGraph` per FB, each
wanting the events of its own instance DB after every scan. :class:`ScanEvents` walks the
record's events once (the first time any of them asks about a record) and hands each its
share; every LiveGraph of a CPU shares one (``LiveGraph(events=...)``), in the scan thread.
"""

from __future__ import annotations

from s7graph.engine.record import ScanRecord
from s7graph.sequencer.fb import StepEvent
from s7graph.web.bus.protocol import EVENTS

__all__ = ["ScanEvents"]

_EVENTS = frozenset(EVENTS)
_NONE: list[tuple[str, int]] = []  # shared: an update's lists are never changed


class ScanEvents:
    """``of(record, db)``: the ``(event, step)`` pairs the FB of instance DB ``db`` raised in
    the scan ``record`` (the events a view shows: ``web.bus.protocol.EVENTS``), in order.
    ``groupings`` counts the records walked."""

    __slots__ = ("_by_db", "_record", "groupings")

    def __init__(self) -> None:
        self._record: ScanRecord | None = None
        self._by_db: dict[int, list[tuple[str, int]]] = {}
        self.groupings = 0

    def of(self, record: ScanRecord, db: int) -> list[tuple[str, int]]:
        if record is not self._record:
            self._group(record)
        return self._by_db.get(db) or _NONE

    def _group(self, record: ScanRecord) -> None:
        by_db: dict[int, list[tuple[str, int]]] = {}
        for e in record.events:
            if isinstance(e, StepEvent) and e.event in _EVENTS:
                pairs = by_db.get(e.db)
                if pairs is None:
                    by_db[e.db] = [(e.event, e.step)]
                else:
                    pairs.append((e.event, e.step))
        self._record, self._by_db = record, by_db
        self.groupings += 1
