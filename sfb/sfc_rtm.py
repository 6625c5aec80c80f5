"""Run-time meters: SFC2 SET_RTM, SFC3 CTRL_RTM, SFC4 READ_RTM, SFC101 RTM (docs/runtime.md, "The
block runtime"; STEP7 comprehensive guide vol. 2, ch. 12; Siemens' Program Design for S7-300/400).

The meters belong to the CPU (``engine.rtm``, ``cpu.meters``): they stop in STOP, keep their
value across MRES, resume after a hot restart. SFC2–4 address meters 0..7 with INT hours
(READ_RTM saturates at 32767); SFC101 meters 0..15 with DINT hours, MODE 0 read, 1 start,
2 stop, 4 set, 5 set and start, 6 set and stop. RET_VAL ``W#16#8080`` wrong NR, ``8081``
negative PV, ``8082`` SFC101 meter overflowed at 2^31 - 1 h, ``8091`` bad MODE ``[K]``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, cast

from s7graph.engine import blocks
from s7graph.engine.rtm import MAX_HOURS_16, MAX_HOURS_32
from s7graph.sfb.catalogue import OK, engine_sections, lookup, specific_error

if TYPE_CHECKING:
    from s7graph.engine.context import CallContext

WRONG_NR = 0x8080
NEGATIVE_PV = 0x8081
OVERFLOW = 0x8082
WRONG_MODE = 0x8091
METERS_16 = range(8)
METERS_32 = range(16)


def _declare(name: str, body: blocks.FCBody) -> blocks.FC:
    entry = lookup(name)
    sections, ret = engine_sections(entry)
    return blocks.sfc(entry.number, entry.name, RET=ret, **sections)(body)


def _raw(ctx: CallContext) -> int:
    return ctx.cpu.clock.now_ns()


def _set_rtm(ctx: CallContext, params: dict[str, object]) -> int:
    nr, pv = cast(int, params["NR"]), cast(int, params["PV"])
    if nr not in METERS_16:
        return specific_error(WRONG_NR)
    if pv < 0:
        return specific_error(NEGATIVE_PV)
    ctx.cpu.meters.set(nr, pv, _raw(ctx))
    return OK


def _ctrl_rtm(ctx: CallContext, params: dict[str, object]) -> int:
    nr = cast(int, params["NR"])
    if nr not in METERS_16:
        return specific_error(WRONG_NR)
    ctx.cpu.meters.control(nr, bool(params["S"]), _raw(ctx))
    return OK


def _read_rtm(ctx: CallContext, params: dict[str, object]) -> int:
    nr = cast(int, params["NR"])
    if nr not in METERS_16:
        return specific_error(WRONG_NR)
    meters = ctx.cpu.meters
    params["CQ"] = meters.running(nr)
    params["CV"] = min(meters.hours(nr, _raw(ctx)), MAX_HOURS_16)
    return OK


def _rtm(ctx: CallContext, params: dict[str, object]) -> int:
    nr, mode, pv = cast(int, params["NR"]), cast(int, params["MODE"]), cast(int, params["PV"])
    if nr not in METERS_32:
        return specific_error(WRONG_NR)
    if mode not in (0, 1, 2, 4, 5, 6):
        return specific_error(WRONG_MODE)
    meters, now = ctx.cpu.meters, _raw(ctx)
    if mode >= 4:
        if pv < 0:
            return specific_error(NEGATIVE_PV)
        meters.set(nr, pv, now)
    if mode in (1, 5):
        meters.control(nr, True, now)
    elif mode in (2, 6):
        meters.control(nr, False, now)
    hours = meters.hours(nr, now)
    params["CQ"] = meters.running(nr)
    params["CV"] = hours
    return specific_error(OVERFLOW) if hours >= MAX_HOURS_32 else OK


SFC2 = _declare("SET_RTM", _set_rtm)
SFC3 = _declare("CTRL_RTM", _ctrl_rtm)
SFC4 = _declare("READ_RTM", _read_rtm)
SFC101 = _declare("RTM", _rtm)
BLOCKS = (SFC2, SFC3, SFC4, SFC101)
