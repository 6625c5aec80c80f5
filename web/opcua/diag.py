"""The CPU's diagnostic buffer in the face's address space (docs/opcua.md, "The address
space"): the folder ``<cpu>/DiagnosticBuffer`` with the newest ``DIAG_ENTRIES`` entries,
newest first, as STEP 7's "Diagnostic Buffer" lists them (number, time, event ID, OB and
priority class, text) — one line of text each in ``Entries`` and, index for index, one
array per column — and the buffer's ``Total`` and ``Capacity``.

:class:`DiagShown` holds the entries shown. It takes the CPU's ``diag`` answer whole
(:meth:`DiagShown.replace`) and each ``diag/new`` publication in front of them
(:meth:`DiagShown.merge`); a publication that does not follow the newest entry held — the
face missed one, or the CPU started again and counts anew — says so, and the face asks
``diag`` again.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from datetime import UTC, datetime
from typing import Final

from asyncua import ua

from s7graph.web.bus.protocol import DiagBuffer, DiagEvent
from s7graph.web.opcua.model import TEXT, UaType
from s7graph.web.opcua.nodes import GOOD, Nodes

__all__ = ["DIAG_ENTRIES", "NO_TIME", "DiagNodes", "DiagShown", "entry_line", "event_id_text"]

DIAG_ENTRIES: Final = 100
"""How many of the newest entries the face shows (the CPU's ``diag`` default)."""
NO_TIME: Final = datetime(1601, 1, 1, tzinfo=UTC)
"""OPC UA's earliest DateTime: an entry whose wall-clock time is not known."""
_UINT32: Final = UaType(ua.VariantType.UInt32, "int", 0, 0xFFFF_FFFF)
_UINT64: Final = UaType(ua.VariantType.UInt64, "int", 0, 2**64 - 1)
_BYTE: Final = UaType(ua.VariantType.Byte, "int", 0, 0xFF)
_TIME: Final = UaType(ua.VariantType.DateTime, "time")


def event_id_text(event_id: int) -> str:
    """The event ID as STEP 7 writes it: ``16#4302``."""
    return f"16#{event_id & 0xFFFF:04X}"


def _time(event: DiagEvent) -> datetime:
    if not event.wall_ms:
        return NO_TIME
    return datetime.fromtimestamp(event.wall_ms / 1000, UTC)


def _info(event: DiagEvent) -> str:
    """What the entry says: ``block @address: message``."""
    where = " ".join(p for p in (event.block, f"@{event.address}" if event.address else "") if p)
    return f"{where}: {event.info}" if where and event.info else where or event.info


def entry_line(event: DiagEvent) -> str:
    """``17 2026-12-05T05:14:24.123Z 16#4562 OB121/PC1 text: block @address: message``
    (the CPU clock's seconds when the wall-clock time is not known; ``-`` for no OB)."""
    if event.wall_ms:
        when = _time(event).strftime("%Y-%m-%dT%H:%M:%S.") + f"{event.wall_ms % 1000:03d}Z"
    else:
        when = f"CPU-clock {event.t_ms / 1000:.3f}s"
    ob = f"OB{event.ob}/PC{event.priority}" if event.ob else "-"
    info = _info(event)
    text = " ".join((f"{event.text}: {info}" if info else event.text).split())
    return f"{event.number} {when} {event_id_text(event.event_id)} {ob} {text}"


# The columns: name, type, description, the value of one entry.
_COLUMNS: Final[tuple[tuple[str, UaType, str, Callable[[DiagEvent], object]], ...]] = (
    ("Number", _UINT32, "the entry's number (the newest has the highest)", lambda e: e.number),
    ("Time", _TIME, "when, on the CPU's wall clock (1601-01-01: not known)", _time),
    (
        "EventId",
        TEXT,
        "the event ID as STEP 7 writes it: 16#4302",
        lambda e: event_id_text(e.event_id),
    ),
    ("OB", _BYTE, "the OB the event requests (0: none)", lambda e: e.ob),
    ("PriorityClass", _BYTE, "the priority class of that OB", lambda e: e.priority),
    ("Text", TEXT, "the event's text", lambda e: e.text),
    ("Info", TEXT, "what the entry says: block, address, message", _info),
)


@dataclass
class DiagShown:
    """The entries shown, newest first, and the buffer's total and capacity with them."""

    entries: list[DiagEvent] = field(default_factory=list)
    total: int = 0
    capacity: int = 0

    def replace(self, buffer: DiagBuffer) -> None:
        """Show ``buffer`` (the CPU's ``diag`` answer) instead of what was shown."""
        self.entries = list(buffer.entries[:DIAG_ENTRIES])
        self.total, self.capacity = buffer.total, buffer.capacity

    def merge(self, new: DiagBuffer) -> bool:
        """Put ``new`` (a ``diag/new`` publication) in front of the entries shown; False
        when it does not follow the newest of them (ask ``diag`` again). One already
        shown changes nothing."""
        if self.total - len(self.entries) <= new.total <= self.total:
            return True
        if new.total - len(new.entries) != self.total:
            return False
        self.entries = [*new.entries, *self.entries][:DIAG_ENTRIES]
        self.total, self.capacity = new.total, new.capacity or self.capacity
        return True


class DiagNodes:
    """The buffer's nodes under ``root`` (``nid`` makes a node id of a path below the
    CPU's), showing ``shown``."""

    def __init__(self, nodes: Nodes, nid: Callable[..., ua.NodeId], root: ua.NodeId) -> None:
        self.nodes = nodes
        self._nid = nid
        self._root = root
        self.shown = DiagShown()
        self._vars: dict[str, ua.NodeId] = {}

    def build(self) -> None:
        """The folder and its variables (added with the CPU's next flush)."""
        n, nid = self.nodes, self._nid
        folder = n.folder(
            self._root,
            nid("DiagnosticBuffer"),
            "DiagnosticBuffer",
            f"the CPU's diagnostic buffer: its newest {DIAG_ENTRIES} entries, newest first",
        )
        scalars = (
            ("Total", _UINT64, "the number of the newest entry: entries the CPU has held"),
            ("Capacity", _UINT32, "how many entries the CPU keeps"),
        )
        for name, t, text in scalars:
            self._vars[name] = n.var(
                folder, nid("DiagnosticBuffer", name), name, t, description=text
            )
        self._vars["Entries"] = n.var(
            folder,
            nid("DiagnosticBuffer", "Entries"),
            "Entries",
            TEXT,
            description="one line an entry: number, time, event ID, OB/priority class, text",
            array=True,
        )
        for name, t, text, _ in _COLUMNS:
            self._vars[name] = n.var(
                folder, nid("DiagnosticBuffer", name), name, t, description=text, array=True
            )

    async def write(self) -> None:
        """The entries shown into the variables (only what changed is written)."""
        now = datetime.now(UTC)
        n, v, held = self.nodes, self._vars, self.shown
        shown = held.entries
        await n.set(v["Total"], ua.Variant(held.total, ua.VariantType.UInt64), GOOD, now)
        await n.set(v["Capacity"], ua.Variant(held.capacity, ua.VariantType.UInt32), GOOD, now)
        lines = [entry_line(e) for e in shown]
        await n.set(v["Entries"], ua.Variant(lines, ua.VariantType.String), GOOD, now)
        for name, t, _, value in _COLUMNS:
            column = [value(e) for e in shown]
            await n.set(v[name], ua.Variant(column, t.variant), GOOD, now)
