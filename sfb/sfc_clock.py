"""SFC0 SET_CLK, SFC1 READ_CLK, SFC64 TIME_TCK over the injected clock (docs/architecture.md, "The
core is a function"; docs/runtime.md, "The block runtime").

The CPU's real-time clock is the injected clock plus a settable offset — never the wall clock:
``date_and_time = epoch + (now_ns + offset)``. SET_CLK changes only the offset, so the monotonic
clock that drives scans, timers and cycle monitoring is untouched (the RTC keeps running while
timers are frozen). DATE_AND_TIME has ms resolution and the range 1990-01-01 .. 2089-12-31 (Siemens'
Program Design for S7-300/400, appendix C); a date outside it gives RET_VAL ``W#16#8080``. TIME_TCK
is the injected clock in ms since its origin, wrapping from 2^31 - 1 to 0 (STEP7 comprehensive guide
vol. 2, ch. 12).
"""

from __future__ import annotations

from datetime import datetime
from typing import TYPE_CHECKING
from weakref import WeakKeyDictionary

from s7graph.engine import blocks
from s7graph.engine.rtc import RealTimeClock as RealTimeClock
from s7graph.engine.rtc import truncate_ms
from s7graph.sfb.catalogue import OK, PARAM_RANGE, engine_sections, lookup, specific_error

if TYPE_CHECKING:
    from s7graph.engine.context import CallContext

NS_PER_MS = 1_000_000
TICK_MODULUS = 2**31
DT_MIN = datetime(1990, 1, 1)  # == engine.rtc.DT_MIN
DT_MAX = datetime(2089, 12, 31, 23, 59, 59, 999_000)
RET_DT_RANGE = specific_error(PARAM_RANGE)


def set_clk(rtc: RealTimeClock, pdt: datetime, now_ns: int) -> int:
    """SFC0 SET_CLK(PDT): set the CPU date and time; RET_VAL 0 or W#16#8080 (out of range)."""
    if not DT_MIN <= truncate_ms(pdt) <= DT_MAX:
        return RET_DT_RANGE
    rtc.set(pdt, now_ns)
    return OK


def read_clk(rtc: RealTimeClock, now_ns: int) -> tuple[int, datetime]:
    """SFC1 READ_CLK: ``(RET_VAL, CDT)``."""
    return OK, rtc.read(now_ns)


def time_tck(now_ns: int) -> int:
    """SFC64 TIME_TCK: RET_VAL = ms of the injected clock, 0 .. 2^31 - 1 then back to 0."""
    return (now_ns // NS_PER_MS) % TICK_MODULUS


def tick_diff(now_ms: int, last_ms: int) -> int:
    """Elapsed ms between two TIME_TCK values across at most one wrap (STEP7 comprehensive guide
    vol. 2, ch. 12 pattern)."""
    return (now_ms - last_ms) % TICK_MODULUS


# --- Engine adapters: one RTC per CPU ------------------------------------------------------

_RTCS: WeakKeyDictionary[object, RealTimeClock] = WeakKeyDictionary()


def rtc_of(cpu: object) -> RealTimeClock:
    """The real-time clock of ``cpu``: ``cpu.rtc`` of an ``engine.cpu.Cpu``, else one kept in a
    weak table (created at DT#1990-01-01 on first use)."""
    own = getattr(cpu, "rtc", None)
    if isinstance(own, RealTimeClock):
        return own
    rtc = _RTCS.get(cpu)
    if rtc is None:
        rtc = _RTCS[cpu] = RealTimeClock()
    return rtc


def _raw_ns(ctx: CallContext) -> int:
    """The injected clock itself (the RTC runs on in HOLD while process time stops)."""
    return ctx.cpu.clock.now_ns()


def _set_clk(ctx: CallContext, params: dict[str, object]) -> int:
    pdt = params["PDT"]
    assert isinstance(pdt, datetime)
    return set_clk(rtc_of(ctx.cpu), pdt, _raw_ns(ctx))


def _read_clk(ctx: CallContext, params: dict[str, object]) -> int:
    ret, params["CDT"] = read_clk(rtc_of(ctx.cpu), _raw_ns(ctx))
    return ret


def _time_tck(ctx: CallContext, params: dict[str, object]) -> int:
    return time_tck(_raw_ns(ctx))


def _declare(name: str, body: blocks.FCBody) -> blocks.FC:
    entry = lookup(name)
    sections, ret = engine_sections(entry)
    return blocks.sfc(entry.number, entry.name, RET=ret, **sections)(body)


SFC0 = _declare("SET_CLK", _set_clk)
SFC1 = _declare("READ_CLK", _read_clk)
SFC64 = _declare("TIME_TCK", _time_tck)
BLOCKS = (SFC0, SFC1, SFC64)
