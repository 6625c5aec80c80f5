"""Diagnostic buffer read (SFC51 RDSYSST) and SFC52 WR_USMSG (SPEC.md §1.7; seeds §6.6, §7.2).

SZL ``W#16#00A0`` lists every entry of the diagnostic buffer, **newest first** (No. 1 =
newest, as a programming device shows it); ``W#16#01A0`` lists the newest ``INDEX``
entries. A data record is 20 bytes (the OB start information), so the header says
``LENGTHDR = 20`` and ``N_DR`` = records delivered. If the destination holds fewer records
than exist, as many as fit are delivered and RET_VAL is ``W#16#8081``; an unknown SZL_ID
gives ``W#16#8082`` (``[K]`` Siemens system-function manual).

WR_USMSG writes a user entry with the clock's time stamp; user event ids are ``W#16#8000``
.. ``W#16#BFFF`` (``A1xx`` incoming, ``A0xx`` outgoing); the entry is written even when
sending to a display device is impossible (behaviour 53).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import NamedTuple, Protocol

from engine.record import DiagEntry
from sfb.catalogue import OK, specific_error

SZL_DIAG_ALL = 0x00A0
SZL_DIAG_NEWEST = 0x01A0
RECORD_BYTES = 20
RET_DR_TOO_SHORT = specific_error(0x8081)
RET_SZL_ID_UNKNOWN = specific_error(0x8082)
RET_EVENTN_ILLEGAL = specific_error(0x8083)
USER_EVENTS = range(0x8000, 0xC000)


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
        wanted, ret = wanted[:capacity], RET_DR_TOO_SHORT
    records = tuple(wanted)
    return SzlResult(ret, False, SzlHeader(RECORD_BYTES, len(records)), records)


def wr_usmsg(
    buffer: DiagSink, eventn: int, now_ns: int, *, send: bool = False, info: str = ""
) -> int:
    """SFC52 WR_USMSG(SEND, EVENTN, INFO1, INFO2): a user entry in the diagnostic buffer.

    Sending to a display device is not modelled: the entry is written either way.
    """
    if eventn not in USER_EVENTS:
        return RET_EVENTN_ILLEGAL
    state = "incoming" if eventn & 0x0100 else "outgoing"
    message = f"user message 16#{eventn:04X} ({state})" + (f": {info}" if info else "")
    buffer.record(now_ns, eventn, "SFC52", message)
    return OK
