"""Interrupt SFCs: time-of-day SFC28–31, delay SFC32–34, DIS_AIRT/EN_AIRT SFC41/42
(docs/runtime.md, "The block runtime"; STEP7 comprehensive guide vol. 2, ch. 12).

The schedules live in the CPU (``engine.timed``: ``cpu.tod``, ``cpu.delays``); these are the thin
SFC adapters. Time of day is the CPU's real-time clock on the injected clock (``cpu.rtc``), delays
run on the process time (frozen in HOLD). STATUS of QRY_TINT/QRY_DINT (STEP7 comprehensive guide
vol. 2, ch. 12): bit 2 = activated and not yet elapsed, bit 4 = OB loaded, bit 0 = the OB is
disabled (DIS_IRT). RET_VAL ``W#16#8090`` wrong OB_NR, ``8091`` bad DTIME, ``8092`` bad PERIOD,
``80A0`` nothing set/started, ``80A1`` a once-only start time already passed ``[K]``; EN_AIRT
without DIS_AIRT ``8080`` ``[K]``.
"""

from __future__ import annotations

from datetime import datetime
from typing import TYPE_CHECKING, cast

from s7graph.engine import blocks
from s7graph.engine.timed import ST_DISABLED, ST_LOADED
from s7graph.sfb.catalogue import as_int, engine_sections, lookup, specific_error

if TYPE_CHECKING:
    from s7graph.engine.context import BlockHost, CallContext

EN_AIRT_NOT_DISABLED = 0x8080


def _declare(name: str, body: blocks.FCBody) -> blocks.FC:
    entry = lookup(name)
    sections, ret = engine_sections(entry)
    return blocks.sfc(entry.number, entry.name, RET=ret, **sections)(body)


def _ob(params: dict[str, object]) -> int:
    return cast(int, params["OB_NR"])


def _rtc_now(cpu: BlockHost) -> datetime:
    return cpu.rtc.read(cpu.clock.now_ns())


def _status(cpu: BlockHost, ob: int, pending: int) -> int:
    loaded = ST_LOADED if ob in cpu.obs else 0
    ci = cpu.interrupts.active.get(ob)
    disabled = ST_DISABLED if ci is not None and not ci.enabled else 0
    return pending | loaded | disabled


def _set_tint(ctx: CallContext, params: dict[str, object]) -> int:
    sdt = params["SDT"]
    assert isinstance(sdt, datetime)
    return as_int(ctx.cpu.tod.set(_ob(params), sdt, cast(int, params["PERIOD"])))


def _can_tint(ctx: CallContext, params: dict[str, object]) -> int:
    return as_int(ctx.cpu.tod.cancel(_ob(params)))


def _act_tint(ctx: CallContext, params: dict[str, object]) -> int:
    return as_int(ctx.cpu.tod.activate(_ob(params), _rtc_now(ctx.cpu)))


def _qry_tint(ctx: CallContext, params: dict[str, object]) -> int:
    ob = _ob(params)
    if ob not in range(10, 18):
        return specific_error(0x8090)
    params["STATUS"] = _status(ctx.cpu, ob, ctx.cpu.tod.status(ob))
    return 0


def _srt_dint(ctx: CallContext, params: dict[str, object]) -> int:
    dtime, sign = cast(int, params["DTIME"]), cast(int, params["SIGN"])
    return as_int(ctx.cpu.delays.start(_ob(params), dtime, sign, ctx.now_ns))


def _can_dint(ctx: CallContext, params: dict[str, object]) -> int:
    return as_int(ctx.cpu.delays.cancel(_ob(params)))


def _qry_dint(ctx: CallContext, params: dict[str, object]) -> int:
    ob = _ob(params)
    if ob not in range(20, 24):
        return specific_error(0x8090)
    params["STATUS"] = _status(ctx.cpu, ob, ctx.cpu.delays.status(ob))
    return 0


def _dis_airt(ctx: CallContext, params: dict[str, object]) -> int:
    return ctx.cpu.dis_airt()


def _en_airt(ctx: CallContext, params: dict[str, object]) -> int:
    left = ctx.cpu.en_airt()
    return specific_error(EN_AIRT_NOT_DISABLED) if left is None else left


SFC28 = _declare("SET_TINT", _set_tint)
SFC29 = _declare("CAN_TINT", _can_tint)
SFC30 = _declare("ACT_TINT", _act_tint)
SFC31 = _declare("QRY_TINT", _qry_tint)
SFC32 = _declare("SRT_DINT", _srt_dint)
SFC33 = _declare("CAN_DINT", _can_dint)
SFC34 = _declare("QRY_DINT", _qry_dint)
SFC41 = _declare("DIS_AIRT", _dis_airt)
SFC42 = _declare("EN_AIRT", _en_airt)
BLOCKS = (SFC28, SFC29, SFC30, SFC31, SFC32, SFC33, SFC34, SFC41, SFC42)
