"""The one trace format: what a scan did (docs/architecture.md, "The core is a function").

``ScanRecord`` is frozen and cheap (slots, tuples, no copies of memory); everybody — tests,
the web view, the bus, the recorder, persistence — reads the same record.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from s7graph.engine.modes import CpuMode


@dataclass(frozen=True, slots=True)
class DiagEntry:
    """One diagnostic-buffer entry: time, event id 16#xxxx, block, message (Siemens' Program Design
    for S7-300/400, ch. 10); ``ob`` and ``priority`` are the OB in which the event happened
    and its priority class (OB121/OB122: the faulting OB's class), 0 for an event of the
    operating system outside every OB; ``wall_ns`` the wall-clock time of the event (ns since
    the epoch; 0 when not known: a virtual clock, an entry of an older state file)."""

    t_ns: int
    event_id: int
    block: str = ""
    message: str = ""
    address: str = ""
    ob: int = 0
    priority: int = 0
    wall_ns: int = 0

    def __str__(self) -> str:
        where = f" {self.block}" if self.block else ""
        at = f" @{self.address}" if self.address else ""
        return f"{self.t_ns / 1e9:.3f}s 16#{self.event_id:04X}{where}{at}: {self.message}"


@dataclass(frozen=True, slots=True)
class ScanRecord:
    """What one scan (or a startup) did: cycle, time, mode, emitted events, changed PQ bytes."""

    cycle: int
    t_ns: int
    cycle_ns: int
    mode: CpuMode
    events: tuple[object, ...] = ()
    outputs: dict[str, int] = field(default_factory=dict)
    diagnostics: tuple[DiagEntry, ...] = ()
    alarms: tuple[object, ...] = ()
    ran: tuple[int, ...] = ()
    """Numbers of the OBs that ran in this scan, in order (OB1, OB35, OB80, ...)."""
