"""Diagnostic buffer read (SFC51 RDSYSST) and SFC52 WR_USMSG (docs/runtime.md, "The block runtime";
STEP7 comprehensive guide vol. 2, ch. 12; Siemens' Program Design for S7-300/400, ch. 10).

SZL ``W#16#00A0`` lists every entry of the diagnostic buffer, **newest first** (No. 1 =
newest, as a programming device shows it); ``W#16#01A0`` lists the newest ``INDEX``
entries. A data record is 20 bytes (the OB start information), so the header says
``LENGTHDR = 20`` and ``N_DR`` = records delivered. If the destination holds fewer records
than exist, as many as fit are delivered and RET_VAL is the warning ``W#16#0081``; if not
even one fits it is ``W#16#8081``; an unknown SZL_ID gives ``W#16#8082``; a call with
REQ = FALSE reads nothing and returns ``W#16#7000`` (``[K]`` Siemens system-function manual).
A record is the entry's event id (WORD), priority and OB number (bytes), DATID, INFO1
(WORD), INFO2 (DWORD) and the DATE_AND_TIME time stamp of the CPU clock (8 bytes BCD).

WR_USMSG writes a user entry with the clock's time stamp; user event ids are ``W#16#8000``
.. ``W#16#BFFF`` (``A1xx`` incoming, ``A0xx`` outgoing); the entry is written even when
sending to a display device is impossible: no display is modelled, so
SEND = TRUE writes it and returns the warning ``W#16#0091`` (no partner registered).

``SFC51`` / ``SFC52`` are the engine adapters (``ctx.call("RDSYSST", ...)``): SZL_HEADER,
DR, INFO1 and INFO2 are ANY pointer texts such as ``P#DB1.DBX0.0 BYTE 40``.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Sequence
from datetime import datetime
from typing import TYPE_CHECKING, NamedTuple, Protocol, cast

from s7graph.engine import blocks
from s7graph.engine.datatypes import encode
from s7graph.engine.record import DiagEntry
from s7graph.sfb.catalogue import (
    AREA_LENGTH_WRITE,
    OK,
    engine_sections,
    general_error,
    lookup,
    specific_error,
)
from s7graph.sfb.sfc_clock import rtc_of
from s7graph.sfb.sfc_memory import _pointer, _span, _store

if TYPE_CHECKING:
    from s7graph.engine.context import CallContext

SZL_DIAG_ALL = 0x00A0
SZL_DIAG_NEWEST = 0x01A0
RECORD_BYTES = 20
HEADER_BYTES = 4  # SZL_HEADER: STRUCT LENGTHDR: WORD; N_DR: WORD END_STRUCT
RET_DR_PARTIAL = 0x0081  # warning: as many records as fit were delivered
RET_NO_REQUEST = 0x7000  # REQ = FALSE: no read started, BUSY = FALSE
RET_NOT_SENT = 0x0091  # warning: entry written, no display registered to send it to
RET_DR_TOO_SHORT = specific_error(0x8081)
RET_SZL_ID_UNKNOWN = specific_error(0x8082)
RET_EVENTN_ILLEGAL = specific_error(0x8083)
USER_EVENTS = range(0x8000, 0xC000)
_OB = re.compile(r"OB(\d+)$")


class DiagSink(Protocol):
    """What WR_USMSG needs (``engine.diagnostics.DiagnosticBuffer.record``)."""

    def record(
        self, t_ns: int, event_id: int, block: str = "", message: str = "", address: str = ""
    ) -> DiagEntry: ...


class SzlHeader(NamedTuple):
    """``SZL_HEADER``: record length in bytes and number of records delivered."""

    lengthdr: int
    n_dr: int


class SzlResult(NamedTuple):
    """RDSYSST outputs: RET_VAL, BUSY (always FALSE: the read is synchronous), header, DR."""

    ret_val: int
    busy: bool
    header: SzlHeader
    records: tuple[DiagEntry, ...]


def rdsysst(
    buffer: Iterable[DiagEntry], szl_id: int, index: int = 0, *, capacity: int | None = None
) -> SzlResult:
    """SFC51 RDSYSST for the diagnostic buffer partial lists (0x00A0, 0x01A0)."""
    newest_first: Sequence[DiagEntry] = list(buffer)[::-1]
    if szl_id == SZL_DIAG_ALL:
        wanted = newest_first
    elif szl_id == SZL_DIAG_NEWEST:
        wanted = newest_first[: max(0, index)]
    else:
        return SzlResult(RET_SZL_ID_UNKNOWN, False, SzlHeader(RECORD_BYTES, 0), ())
    ret = OK
    if capacity is not None and len(wanted) > capacity:
        if capacity <= 0:
            return SzlResult(RET_DR_TOO_SHORT, False, SzlHeader(RECORD_BYTES, 0), ())
        wanted, ret = wanted[:capacity], RET_DR_PARTIAL
    records = tuple(wanted)
    return SzlResult(ret, False, SzlHeader(RECORD_BYTES, len(records)), records)


def wr_usmsg(
    buffer: DiagSink, eventn: int, now_ns: int, *, send: bool = False, info: str = ""
) -> int:
    """SFC52 WR_USMSG(SEND, EVENTN, INFO1, INFO2): a user entry in the diagnostic buffer.

    Sending to a display device is not modelled: the entry is written either way, and
    SEND = TRUE returns the warning ``W#16#0091`` (no partner registered).
    """
    if eventn not in USER_EVENTS:
        return RET_EVENTN_ILLEGAL
    state = "incoming" if eventn & 0x0100 else "outgoing"
    message = f"user message 16#{eventn:04X} ({state})" + (f": {info}" if info else "")
    buffer.record(now_ns, eventn, "SFC52", message)
    return RET_NOT_SENT if send else OK


def encode_record(entry: DiagEntry, stamp: datetime) -> bytes:
    """The 20-byte SZL 0x00A0 record of ``entry`` with its time stamp ``stamp``: the priority
    class of the OB in which the event happened, and the OB the entry names (else that
    OB)."""
    match = _OB.match(entry.block)
    ob_nr = (int(match.group(1)) if match else entry.ob) & 0xFF
    head = (entry.event_id & 0xFFFF).to_bytes(2, "big") + bytes([entry.priority & 0xFF, ob_nr])
    return head + bytes(8) + encode("DATE_AND_TIME", stamp)


# --- Engine adapters -----------------------------------------------------------------------


def _rdsysst(ctx: CallContext, params: dict[str, object]) -> int:
    params["BUSY"] = False
    if not params["REQ"]:
        return RET_NO_REQUEST
    entry = lookup("RDSYSST")
    header, dr = _pointer(params, "SZL_HEADER", entry.name), _pointer(params, "DR", entry.name)
    if isinstance(header, int):
        return header
    if isinstance(dr, int):
        return dr
    hbuf = _span(ctx.mem, header, entry.param_number("SZL_HEADER"), write=True)
    if isinstance(hbuf, int):
        return hbuf
    if header.bits // 8 < HEADER_BYTES:
        return general_error(entry.param_number("SZL_HEADER"), AREA_LENGTH_WRITE)
    dbuf = _span(ctx.mem, dr, entry.param_number("DR"), write=True)
    if isinstance(dbuf, int):
        return dbuf
    szl_id, index = cast(int, params["SZL_ID"]), cast(int, params["INDEX"])
    capacity = dr.bits // 8 // RECORD_BYTES
    result = rdsysst(ctx.cpu.diagnostics, szl_id, index, capacity=capacity)
    if result.ret_val < 0:
        return result.ret_val
    rtc = rtc_of(ctx.cpu)
    data = b"".join(encode_record(e, rtc.read(e.t_ns)) for e in result.records)
    head = result.header
    _store(ctx.mem, header, hbuf, head.lengthdr.to_bytes(2, "big") + head.n_dr.to_bytes(2, "big"))
    _store(ctx.mem, dr, dbuf, data)
    return result.ret_val


def _info(ctx: CallContext, params: dict[str, object], name: str) -> str | int:
    """``INFO1=16#0001`` from the bytes behind an INFO pointer ('' when not given)."""
    if not str(params.get(name) or "").strip():
        return ""
    ptr = _pointer(params, name, "WR_USMSG")
    if isinstance(ptr, int):
        return ptr
    buf = _span(ctx.mem, ptr, lookup("WR_USMSG").param_number(name), write=False)
    if isinstance(buf, int):
        return buf
    return f"{name}=16#{bytes(buf[ptr.byte : ptr.byte + ptr.bits // 8]).hex().upper()}"


def _wr_usmsg(ctx: CallContext, params: dict[str, object]) -> int:
    infos: list[str] = []
    for name in ("INFO1", "INFO2"):
        info = _info(ctx, params, name)
        if isinstance(info, int):
            return info
        if info:
            infos.append(info)
    eventn = cast(int, params["EVENTN"])
    now_ns = ctx.cpu.clock.now_ns()  # the diagnostic time stamp runs on in HOLD too
    return wr_usmsg(
        ctx.cpu.diagnostics, eventn, now_ns, send=bool(params["SEND"]), info=" ".join(infos)
    )


def _declare(name: str, body: blocks.FCBody) -> blocks.FC:
    entry = lookup(name)
    sections, ret = engine_sections(entry)
    return blocks.sfc(entry.number, entry.name, RET=ret, **sections)(body)


SFC51 = _declare("RDSYSST", _rdsysst)
SFC52 = _declare("WR_USMSG", _wr_usmsg)
BLOCKS = (SFC51, SFC52)
