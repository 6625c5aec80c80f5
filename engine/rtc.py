"""The CPU's real-time clock over the injected clock (docs/architecture.md, "The core is a
function"; STEP7 comprehensive guide vol. 2, ch. 12).

``date_and_time = epoch + (now_ns + offset)`` — never the wall clock. Setting the clock (SFC0
SET_CLK) changes only the offset, so the monotonic clock that drives scans, timers and cycle
monitoring is untouched; the RTC runs on in HOLD and survives MRES. Time-of-day interrupts OB10–OB17
fire on this clock.
"""

from __future__ import annotations

from datetime import datetime, timedelta

NS_PER_MS = 1_000_000
DT_MIN = datetime(1990, 1, 1)


def truncate_ms(dt: datetime) -> datetime:
    """``dt`` without time zone, cut to whole milliseconds (DATE_AND_TIME resolution)."""
    return dt.replace(microsecond=dt.microsecond // 1000 * 1000, tzinfo=None)


class RealTimeClock:
    """The CPU clock: ``epoch`` at injected time 0, moved by SET_CLK through an offset.

    ``version`` counts the settings, so a time-of-day scheduler can tell a jump from
    the clock running on.
    """

    def __init__(self, epoch: datetime = DT_MIN) -> None:
        self._epoch = truncate_ms(epoch)
        self._offset_ns = 0
        self.version = 0

    def read(self, now_ns: int) -> datetime:
        """The CPU date and time at injected time ``now_ns`` (ms resolution)."""
        ms = (now_ns + self._offset_ns) // NS_PER_MS
        return self._epoch + timedelta(milliseconds=ms)

    def set(self, value: datetime, now_ns: int) -> None:
        """Make ``read(now_ns)`` return ``value`` from now on."""
        target = truncate_ms(value) - self._epoch
        target_ns = (target // timedelta(milliseconds=1)) * NS_PER_MS
        self._offset_ns = target_ns - now_ns
        self.version += 1

    def snapshot(self) -> dict[str, object]:
        return {"epoch": self._epoch.isoformat(), "offset_ns": self._offset_ns}

    def restore(self, data: dict[str, object]) -> None:
        self._epoch = datetime.fromisoformat(str(data["epoch"]))
        self._offset_ns = int(str(data["offset_ns"]))
        self.version += 1
