"""Where a cycle's time went: the runner's loop in phases, and the cycles that ran long.

TIA Portal shows a CPU's shortest, current and longest cycle; it does not say why the
longest was long. The runner (``engine/runner.py``) stamps each phase of its loop, and the
scan thread's processor time and its time waiting for a processor (Linux
``/proc/thread-self/schedstat``); this module turns the stamps of one cycle (start of a
scan to the start of the next) into a :class:`CycleBreakdown` and keeps the statistics:
per phase the longest and the mean, how many cycles ran long, the longest of them and the
last ones.

The phases, in the order they run (the table is the documentation; a breakdown's
``phases`` follow it):

"""

from __future__ import annotations

import itertools
from collections import deque
from collections.abc import Mapping
from dataclasses import dataclass, field

__all__ = [
    "LONG_MARGIN_NS",
    "PHASES",
    "PHASE_NAMES",
    "RECENT_LONG",
    "CycleBreakdown",
    "CycleProfile",
    "OpenCycle",
    "describe",
]

PHASES: tuple[tuple[str, str], ...] = (
    (
        "encode",
        "the instance DBs of the last staging the writer's encoder had not encoded"
        " in the idle part, encoded before the scan changes them (the second such staging in"
        " a row; the first is carried over to the next)",
    ),
    ("scan", "the scan: inputs, OBs (the program, the sequencers), the plant, outputs"),
    ("alarms", "the scan's message events appended to the alarm log"),
    ("edge", "after the scan: the bus, the view, the commands applied at the scan boundary"),
    (
        "stage",
        "the state's changes staged for the writer (the instance DBs encoded by its"
        " encoder in the idle part, committed off the scan thread)",
    ),
    ("gc", "the garbage collector, in the idle part of the cycle"),
    ("idle", "waiting for the next cycle to fall due (the wait asked for)"),
    ("late", "the next scan starting after it fell due (the wake-up, the interpreter's lock)"),
)
"""Each phase of the runner's loop and what runs in it."""
__doc__ = (__doc__ or "") + "\n".join(f"- ``{name}``: {what}" for name, what in PHASES) + "\n"

PHASE_NAMES = tuple(name for name, _ in PHASES)
_IDLE = PHASE_NAMES.index("idle")

LONG_MARGIN_NS = 2_000_000
"""A cycle is *long* when it exceeds the set cycle time by more than this (the jitter
target: p99.9 at most the cycle time + 2 ms)."""
RECENT_LONG = 16
"""How many of the last long cycles are kept with their breakdowns."""


@dataclass(frozen=True, slots=True)
class CycleBreakdown:
    """One cycle from the start of scan ``scan`` to the start of the next: ``phases`` in ns
    in the order of :data:`PHASES`; ``cpu_ns`` the scan thread's processor time in it;
    ``runq_ns`` how long the thread was ready to run but waited for a processor (``None``
    where the system does not say); ``at_ns`` the wall time (ns since the epoch) it began;
    ``overrun`` whether its work took longer than the set cycle time (no wait)."""

    scan: int
    at_ns: int
    cycle_ns: int
    phases: tuple[int, ...]
    cpu_ns: int
    runq_ns: int | None
    overrun: bool = False

    @property
    def busy_ns(self) -> int:
        """The cycle without the wait asked for: what the scan thread needed or waited for."""
        return max(0, self.cycle_ns - self.phases[_IDLE])

    @property
    def blocked_ns(self) -> int | None:
        """Time the scan thread had work but neither ran nor waited for a processor: it
        slept on a lock (the interpreter's, mostly), a page fault or other I/O."""
        if self.runq_ns is None:
            return None
        return max(0, self.busy_ns - self.cpu_ns - self.runq_ns)

    def phase(self, name: str) -> int:
        return self.phases[PHASE_NAMES.index(name)]

    def parts(self) -> dict[str, int]:
        """The phases by name, then ``cpu``, ``processor`` (waiting for one) and ``lock``
        (blocked) when known: ns."""
        out = dict(zip(PHASE_NAMES, self.phases, strict=True))
        out["cpu"] = self.cpu_ns
        if self.runq_ns is not None:
            out["processor"] = self.runq_ns
            out["lock"] = self.blocked_ns or 0
        return out

    def parts_ms(self) -> dict[str, float]:
        return {name: ns / 1e6 for name, ns in self.parts().items()}

    def describe(self) -> str:
        """One line (:func:`describe`)."""
        return describe(self.cycle_ns / 1e6, self.parts_ms())


def describe(cycle_ms: float, parts: Mapping[str, float]) -> str:
    """One line for a cycle of ``cycle_ms`` with its ``parts`` in ms (``CycleBreakdown
    .parts``): ``15.6 ms: scan 1.0, stage 0.3, edge 0.6, late 13.2 (ran 1.9, waited for a
    processor 12.1, blocked 1.6)`` — the phases of 0.05 ms or more, ``idle`` left out."""
    shown = [
        f"{name} {parts[name]:.1f}"
        for name in PHASE_NAMES
        if name != "idle" and parts.get(name, 0.0) >= 0.05
    ]
    text = f"{cycle_ms:.1f} ms: " + (", ".join(shown) or "nothing measured")
    if "processor" in parts:
        text += (
            f" (ran {parts.get('cpu', 0.0):.1f}, waited for a processor {parts['processor']:.1f},"
            f" blocked {parts.get('lock', 0.0):.1f})"
        )
    return text


@dataclass(slots=True)
class CycleProfile:
    """The cycles of one run: ``add`` each breakdown as it completes."""

    cycle_ns: int
    margin_ns: int = LONG_MARGIN_NS
    count: int = 0
    long: int = 0
    """Cycles longer than the set cycle time + ``margin_ns``."""
    max_ns: list[int] = field(default_factory=lambda: [0] * len(PHASES))
    total_ns: list[int] = field(default_factory=lambda: [0] * len(PHASES))
    longest: CycleBreakdown | None = None
    recent: deque[CycleBreakdown] = field(default_factory=lambda: deque(maxlen=RECENT_LONG))
    """The last long cycles, oldest first."""

    def add(self, cycle: CycleBreakdown) -> None:
        self.count += 1
        for i, ns in enumerate(cycle.phases):
            self.total_ns[i] += ns
            if ns > self.max_ns[i]:
                self.max_ns[i] = ns
        if self.longest is None or cycle.cycle_ns > self.longest.cycle_ns:
            self.longest = cycle
        if self.is_long(cycle):
            self.long += 1
            self.recent.append(cycle)

    def is_long(self, cycle: CycleBreakdown) -> bool:
        return cycle.cycle_ns > self.cycle_ns + self.margin_ns

    def mean_ns(self, name: str) -> float:
        return self.total_ns[PHASE_NAMES.index(name)] / self.count if self.count else 0.0

    def longest_ns(self, name: str) -> int:
        return self.max_ns[PHASE_NAMES.index(name)]

    def since(self, scan: int) -> list[CycleBreakdown]:
        """The kept long cycles that began at scan ``scan`` or later."""
        return [c for c in self.recent if c.scan >= scan]


@dataclass(slots=True)
class OpenCycle:
    """A cycle whose work is done, waiting for the next scan's start to close it: the
    runner's stamps (perf-counter ns: the scan's start, then the end of each phase from
    ``scan`` to ``gc``), and at the start the scan thread's processor time and time waited
    for a processor (``None``: the system does not say); ``idle_ns`` the wait asked for (0
    when the work overran the cycle: ``overrun``)."""

    scan: int
    at_ns: int
    stamps: list[int]
    cpu_ns: int
    runq_ns: int | None
    idle_ns: int
    overrun: bool

    def close(self, started: int, cpu_ns: int, runq_ns: int | None) -> CycleBreakdown:
        """The breakdown, the next scan having started at ``started`` with the thread's
        processor time ``cpu_ns`` and time waited ``runq_ns``: ``late`` is what the start
        came after the end of ``gc`` and the wait."""
        marks = self.stamps
        work = [b - a for a, b in itertools.pairwise(marks)]
        late = max(0, started - marks[-1] - self.idle_ns)
        waited = None if runq_ns is None or self.runq_ns is None else runq_ns - self.runq_ns
        return CycleBreakdown(
            scan=self.scan,
            at_ns=self.at_ns,
            cycle_ns=started - marks[0],
            phases=(*work, self.idle_ns, late),
            cpu_ns=cpu_ns - self.cpu_ns,
            runq_ns=waited,
            overrun=self.overrun,
        )
