"""Run-time meters (operating-hours counters) of the CPU (STEP7 comprehensive guide vol. 2, ch. 12).

A meter counts whole hours of the injected clock while it is started *and* the CPU is not in STOP:
in STOP it stops, it keeps its value across MRES (Siemens' Program Design for S7-300/400); after a
warm or cold restart the program must start it again, after a hot restart it continues if it was
running. SFC2/3/4 see meters 0..7 as INT hours (0..32767, saturating), SFC101 RTM sees meters 0..15
as DINT hours, stopping at 2^31 - 1 (STEP7 comprehensive guide vol. 2, ch. 12).
"""

from __future__ import annotations

from dataclasses import dataclass

NS_PER_HOUR = 3_600_000_000_000
METERS = 16
MAX_HOURS_16 = 32767
MAX_HOURS_32 = 2**31 - 1


@dataclass(slots=True)
class RuntimeMeter:
    """One meter: accumulated ns, whether the program started it, and the counting mark."""

    acc_ns: int = 0
    started: bool = False
    mark_ns: int | None = None  # raw clock since which the meter counts (None: not counting)


class RuntimeMeters:
    """The CPU's meters; ``cpu_running`` is False while the CPU is in STOP."""

    def __init__(self, count: int = METERS) -> None:
        self.meters = [RuntimeMeter() for _ in range(count)]
        self.cpu_running = False

    def _settle(self, m: RuntimeMeter, now_ns: int) -> None:
        if m.mark_ns is not None:
            m.acc_ns = min(m.acc_ns + now_ns - m.mark_ns, MAX_HOURS_32 * NS_PER_HOUR)
            m.mark_ns = now_ns

    def hours(self, nr: int, now_ns: int) -> int:
        """Whole hours counted by meter ``nr`` (32-bit view)."""
        m = self.meters[nr]
        self._settle(m, now_ns)
        return m.acc_ns // NS_PER_HOUR

    def set(self, nr: int, hours: int, now_ns: int) -> None:
        """SFC2 SET_RTM / SFC101 modes 4-6: the meter's value in hours."""
        m = self.meters[nr]
        self._settle(m, now_ns)
        m.acc_ns = hours * NS_PER_HOUR

    def control(self, nr: int, start: bool, now_ns: int) -> None:
        """SFC3 CTRL_RTM(S) / SFC101 modes 1, 2: start or stop meter ``nr``."""
        m = self.meters[nr]
        self._settle(m, now_ns)
        m.started = start
        m.mark_ns = now_ns if start and self.cpu_running else None

    def running(self, nr: int) -> bool:
        """CQ: started (and so counting whenever the CPU is not in STOP)."""
        return self.meters[nr].started

    def stop_cpu(self, now_ns: int) -> None:
        """The CPU went to STOP: every meter stops counting and keeps its value."""
        for m in self.meters:
            self._settle(m, now_ns)
            m.mark_ns = None
        self.cpu_running = False

    def start_cpu(self, now_ns: int, *, hot: bool) -> None:
        """Startup: a hot restart resumes started meters, warm/cold leave them stopped."""
        self.cpu_running = True
        for m in self.meters:
            if not hot:
                m.started = False
            m.mark_ns = now_ns if m.started else None
