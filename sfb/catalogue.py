"""The one catalogue of system blocks, and the RET_VAL conventions (docs/runtime.md, "The block
runtime"; STEP7 comprehensive guide vol. 2, ch. 12).

``CATALOGUE`` lists every SFB/SFC s7graph emulates: number, name, kind, and the pins with
direction, S7 type and (an SFB's) default in the order Siemens documents them. Code reads it —
to declare the engine interfaces and to let the sequencer's ``CALL`` validate parameters — so
a pin is named once, here. ``lookup("SFB4")``, ``lookup("SFB 4")`` and ``lookup("TON")`` give the
same entry.

RET_VAL: ``>= 0`` success (BR = 1), ``< 0`` error (bit 15 set, BR = 0). Error words are
``W#16#8xyy``: general errors carry the parameter number in ``x``, specific errors have ``x = 0``.
As an INT a word ``W#16#8122`` is ``-32478``.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from enum import StrEnum

from s7graph.engine.blocks import default_value
from s7graph.engine.errors import BlockError
from s7graph.engine.literals import format_literal, parse_literal

# --- RET_VAL -----------------------------------------------------------------------------

OK = 0
# General error events (low byte ``yy``; the parameter number goes into ``x``), STEP7 comprehensive
# guide vol. 2, ch. 12.
AREA_LENGTH_READ = 0x22
AREA_LENGTH_WRITE = 0x23
AREA_READ = 0x24
AREA_WRITE = 0x25
DB_NOT_LOADED = 0x3A
# Specific error codes (x = 0).
PARAM_RANGE = 0x8080  # a parameter value is out of range (e.g. SET_CLK date)


def as_int(word: int) -> int:
    """A 16-bit RET_VAL word as the signed INT the block returns (``W#16#8122`` -> -32478)."""
    word &= 0xFFFF
    return word - 0x10000 if word & 0x8000 else word


def as_word(ret_val: int) -> int:
    """A signed RET_VAL as its 16-bit word (for display as ``W#16#8122``)."""
    return ret_val & 0xFFFF


def general_error(param: int, event: int) -> int:
    """General error code ``W#16#8xyy`` for parameter number ``param`` (1-based), as INT."""
    return as_int(0x8000 | (param << 8) | event)


def specific_error(code: int) -> int:
    """Specific error ``W#16#80yy`` as INT."""
    return as_int(code)


def is_error(ret_val: int) -> bool:
    """RET_VAL < 0 (bit 15 set) means failure."""
    return as_int(ret_val) < 0


def br_of(ret_val: int) -> bool:
    """The BR bit (ENO) an SFC leaves: 1 on success, 0 on error."""
    return not is_error(ret_val)


# --- The catalogue -----------------------------------------------------------------------


class Kind(StrEnum):
    SFB = "SFB"  # needs an instance DB (or multi-instance)
    SFC = "SFC"  # no memory of its own


class Direction(StrEnum):
    IN = "IN"
    OUT = "OUT"
    IN_OUT = "IN_OUT"


@dataclass(frozen=True, slots=True)
class Pin:
    """One formal parameter: name, direction and S7 type (``ANY`` for an area pointer), and
    the initial value of an SFB's instance DB where Siemens gives one other than zero."""

    name: str
    direction: Direction
    type: str
    comment: str = ""
    default: object = None

    @property
    def initial(self) -> object:
        """The value the pin has in a new instance DB: its default, else the type's zero."""
        return default_value(self.type) if self.default is None else self.default

    @property
    def is_input(self) -> bool:
        return self.direction in (Direction.IN, Direction.IN_OUT)

    @property
    def is_output(self) -> bool:
        return self.direction in (Direction.OUT, Direction.IN_OUT)


@dataclass(frozen=True, slots=True)
class Entry:
    """One system block: ``SFB4 TON`` with its pins in documentation order."""

    kind: Kind
    number: int
    name: str
    pins: tuple[Pin, ...]
    summary: str

    @property
    def key(self) -> str:
        """``SFB4``."""
        return f"{self.kind}{self.number}"

    @property
    def needs_instance(self) -> bool:
        return self.kind is Kind.SFB

    def pin(self, name: str) -> Pin | None:
        upper = name.upper()
        return next((p for p in self.pins if p.name == upper), None)

    def param_number(self, name: str) -> int:
        """1-based position of pin ``name`` (the ``x`` of a general error code)."""
        upper = name.upper()
        for i, p in enumerate(self.pins, start=1):
            if p.name == upper:
                return i
        raise KeyError(f"{self.key} {self.name} has no parameter {name}")

    @property
    def inputs(self) -> tuple[Pin, ...]:
        return tuple(p for p in self.pins if p.is_input)

    @property
    def outputs(self) -> tuple[Pin, ...]:
        return tuple(p for p in self.pins if p.is_output)

    def check_call(
        self, inputs: Iterable[str] = (), outputs: Iterable[str] = (), *, has_instance: bool
    ) -> list[str]:
        """Problems with ``CALL <block>(in := ..., out => ...)``; empty when the call is valid.

        An SFB needs an instance DB, an SFC must not have one; ``:=`` must name an IN/IN_OUT
        pin, ``=>`` an OUT/IN_OUT pin; a pin may be given once.
        """
        where = f"{self.key} {self.name}"
        problems: list[str] = []
        if self.needs_instance and not has_instance:
            problems.append(f"{where} is an SFB and needs an instance DB")
        if not self.needs_instance and has_instance:
            problems.append(f"{where} is an SFC and takes no instance DB")
        seen: set[str] = set()
        for names, want_input in ((inputs, True), (outputs, False)):
            for name in names:
                pin = self.pin(name)
                if pin is None:
                    known = ", ".join(p.name for p in self.pins) or "none"
                    problems.append(f"{where} has no parameter {name} (parameters: {known})")
                    continue
                if name.upper() in seen:
                    problems.append(f"{where}: parameter {pin.name} given twice")
                seen.add(name.upper())
                if want_input and not pin.is_input:
                    problems.append(f"{where}: {pin.name} is an output, use {pin.name} => ...")
                if not want_input and not pin.is_output:
                    problems.append(f"{where}: {pin.name} is an input, use {pin.name} := ...")
        return problems


def _pins(spec: str) -> tuple[Pin, ...]:
    """``"IN CU:BOOL GAIN:REAL=2.0; OUT Q:BOOL"`` -> pins (the compact notation of the table
    below; ``=literal`` is a default, an S7 literal of the pin's type)."""
    pins: list[Pin] = []
    for section in filter(None, (s.strip() for s in spec.split(";"))):
        direction, *items = section.split()
        for item in items:
            name, typed = item.split(":", 1)
            type_, _, literal = typed.partition("=")
            default = None
            if literal:
                kind, default = parse_literal(literal)
                assert kind == type_, f"{name}: {literal} is not a {type_}"
            pins.append(Pin(name, Direction(direction), type_, default=default))
    return tuple(pins)


def _e(kind: Kind, number: int, name: str, pins: str, summary: str) -> Entry:
    return Entry(kind, number, name, _pins(pins), summary)


_SFB, _SFC = Kind.SFB, Kind.SFC

CATALOGUE: tuple[Entry, ...] = (
    _e(
        _SFB,
        0,
        "CTU",
        "IN CU:BOOL R:BOOL PV:INT; OUT Q:BOOL CV:INT",
        "up counter: CV+1 on rising CU to 32767, R -> 0, Q = CV >= PV",
    ),
    _e(
        _SFB,
        1,
        "CTD",
        "IN CD:BOOL LOAD:BOOL PV:INT; OUT Q:BOOL CV:INT",
        "down counter: CV-1 on rising CD to -32768, LOAD -> PV, Q = CV <= 0",
    ),
    _e(
        _SFB,
        2,
        "CTUD",
        "IN CU:BOOL CD:BOOL R:BOOL LOAD:BOOL PV:INT; OUT QU:BOOL QD:BOOL CV:INT",
        "up/down counter: QU = CV >= PV, QD = CV <= 0",
    ),
    _e(_SFB, 3, "TP", "IN IN:BOOL PT:TIME; OUT Q:BOOL ET:TIME", "pulse of length PT"),
    _e(_SFB, 4, "TON", "IN IN:BOOL PT:TIME; OUT Q:BOOL ET:TIME", "on delay"),
    _e(_SFB, 5, "TOF", "IN IN:BOOL PT:TIME; OUT Q:BOOL ET:TIME", "off delay"),
    _e(
        _SFB,
        41,
        "CONT_C",
        "IN COM_RST:BOOL MAN_ON:BOOL=TRUE PVPER_ON:BOOL P_SEL:BOOL=TRUE I_SEL:BOOL=TRUE"
        " INT_HOLD:BOOL I_ITL_ON:BOOL D_SEL:BOOL CYCLE:TIME=T#1S SP_INT:REAL PV_IN:REAL"
        " PV_PER:WORD MAN:REAL GAIN:REAL=2.0 TI:TIME=T#20S TD:TIME=T#10S TM_LAG:TIME=T#2S"
        " DEADB_W:REAL LMN_HLM:REAL=100.0 LMN_LLM:REAL PV_FAC:REAL=1.0 PV_OFF:REAL"
        " LMN_FAC:REAL=1.0 LMN_OFF:REAL I_ITLVAL:REAL DISV:REAL;"
        " OUT LMN:REAL LMN_PER:WORD QLMN_HLM:BOOL QLMN_LLM:BOOL LMN_P:REAL LMN_I:REAL"
        " LMN_D:REAL PV:REAL ER:REAL",
        "continuous PID controller: P, I, D parts, dead band, limits, manual mode",
    ),
    _e(
        _SFB,
        42,
        "CONT_S",
        "IN COM_RST:BOOL LMNR_HS:BOOL LMNR_LS:BOOL LMNS_ON:BOOL LMNUP:BOOL LMNDN:BOOL"
        " PVPER_ON:BOOL CYCLE:TIME=T#1S SP_INT:REAL PV_IN:REAL PV_PER:WORD GAIN:REAL=2.0"
        " TI:TIME=T#20S DEADB_W:REAL=1.0 PV_FAC:REAL=1.0 PV_OFF:REAL PULSE_TM:TIME=T#3S"
        " BREAK_TM:TIME=T#3S MTR_TM:TIME=T#30S DISV:REAL;"
        " OUT QLMNUP:BOOL QLMNDN:BOOL PV:REAL ER:REAL",
        "PI step controller for an integrating actuator: up/down pulses",
    ),
    _e(
        _SFB,
        43,
        "PULSEGEN",
        "IN INV:REAL PER_TM:TIME=T#1S P_B_TM:TIME=T#50MS RATIOFAC:REAL=1.0 STEP3_ON:BOOL=TRUE"
        " ST2BI_ON:BOOL MAN_ON:BOOL POS_P_ON:BOOL NEG_P_ON:BOOL SYN_ON:BOOL=TRUE COM_RST:BOOL"
        " CYCLE:TIME=T#10MS; OUT QPOS_P:BOOL QNEG_P:BOOL",
        "pulse-width modulation of INV: two-step or three-step pulses",
    ),
    _e(_SFC, 0, "SET_CLK", "IN PDT:DATE_AND_TIME; OUT RET_VAL:INT", "set the CPU clock"),
    _e(_SFC, 1, "READ_CLK", "OUT RET_VAL:INT CDT:DATE_AND_TIME", "read the CPU clock"),
    _e(
        _SFC,
        2,
        "SET_RTM",
        "IN NR:BYTE PV:INT; OUT RET_VAL:INT",
        "set run-time meter NR (0..7) to PV hours",
    ),
    _e(
        _SFC,
        3,
        "CTRL_RTM",
        "IN NR:BYTE S:BOOL; OUT RET_VAL:INT",
        "start (S = 1) or stop (S = 0) run-time meter NR",
    ),
    _e(
        _SFC,
        4,
        "READ_RTM",
        "IN NR:BYTE; OUT RET_VAL:INT CQ:BOOL CV:INT",
        "read run-time meter NR: running, hours (saturating at 32767)",
    ),
    _e(
        _SFC,
        17,
        "ALARM_SQ",
        "IN SIG:BOOL ID:WORD EV_ID:DWORD SD:ANY; OUT RET_VAL:INT",
        "acknowledgeable message on each SIG edge",
    ),
    _e(
        _SFC,
        18,
        "ALARM_S",
        "IN SIG:BOOL ID:WORD EV_ID:DWORD SD:ANY; OUT RET_VAL:INT",
        "message without acknowledgement on each SIG edge",
    ),
    _e(
        _SFC,
        19,
        "ALARM_SC",
        "IN EV_ID:DWORD; OUT RET_VAL:INT STATE:BOOL Q_STATE:BOOL",
        "query the signal and acknowledgement state of a message",
    ),
    _e(_SFC, 20, "BLKMOV", "IN SRCBLK:ANY; OUT RET_VAL:INT DSTBLK:ANY", "copy an area"),
    _e(_SFC, 21, "FILL", "IN BVAL:ANY; OUT RET_VAL:INT BLK:ANY", "fill an area with a pattern"),
    _e(
        _SFC,
        22,
        "CREAT_DB",
        "IN LOW_LIMIT:WORD UP_LIMIT:WORD COUNT:WORD; OUT RET_VAL:INT DB_NUMBER:WORD",
        "create the lowest free DB in LOW_LIMIT..UP_LIMIT with COUNT (even) bytes",
    ),
    _e(_SFC, 23, "DEL_DB", "IN DB_NUMBER:WORD; OUT RET_VAL:INT", "delete a DB"),
    _e(
        _SFC,
        24,
        "TEST_DB",
        "IN DB_NUMBER:WORD; OUT RET_VAL:INT DB_LENGTH:WORD WRITE_PROT:BOOL",
        "length and write protection of a DB (W#16#80B1: no such DB)",
    ),
    _e(
        _SFC,
        28,
        "SET_TINT",
        "IN OB_NR:INT SDT:DATE_AND_TIME PERIOD:WORD; OUT RET_VAL:INT",
        "set start and period of a time-of-day interrupt (not activated)",
    ),
    _e(_SFC, 29, "CAN_TINT", "IN OB_NR:INT; OUT RET_VAL:INT", "cancel a time-of-day interrupt"),
    _e(_SFC, 30, "ACT_TINT", "IN OB_NR:INT; OUT RET_VAL:INT", "activate a time-of-day interrupt"),
    _e(
        _SFC,
        31,
        "QRY_TINT",
        "IN OB_NR:INT; OUT RET_VAL:INT STATUS:WORD",
        "status of a time-of-day interrupt (bit 2: active, bit 4: OB loaded)",
    ),
    _e(
        _SFC,
        32,
        "SRT_DINT",
        "IN OB_NR:INT DTIME:TIME SIGN:WORD; OUT RET_VAL:INT",
        "start a delay interrupt: OB_NR runs once after DTIME with SIGN",
    ),
    _e(_SFC, 33, "CAN_DINT", "IN OB_NR:INT; OUT RET_VAL:INT", "cancel a delay interrupt"),
    _e(
        _SFC,
        34,
        "QRY_DINT",
        "IN OB_NR:INT; OUT RET_VAL:INT STATUS:WORD",
        "status of a delay interrupt (bit 2: pending, bit 4: OB loaded)",
    ),
    _e(
        _SFC,
        41,
        "DIS_AIRT",
        "OUT RET_VAL:INT",
        "delay higher-priority interrupts until EN_AIRT or OB end; RET_VAL = delays in force",
    ),
    _e(
        _SFC,
        42,
        "EN_AIRT",
        "OUT RET_VAL:INT",
        "undo one DIS_AIRT; RET_VAL = delays still in force (W#16#8080: none)",
    ),
    _e(_SFC, 43, "RE_TRIGR", "", "restart cycle-time monitoring"),
    _e(
        _SFC,
        44,
        "REPL_VAL",
        "IN VAL:DWORD; OUT RET_VAL:INT",
        "in OB122: the value the failed peripheral read returns",
    ),
    _e(_SFC, 46, "STP", "", "put the CPU into STOP"),
    _e(_SFC, 47, "WAIT", "IN WT:INT", "busy-wait WT microseconds (recorded, time not advanced)"),
    _e(
        _SFC,
        51,
        "RDSYSST",
        "IN REQ:BOOL SZL_ID:WORD INDEX:WORD; OUT RET_VAL:INT BUSY:BOOL SZL_HEADER:ANY DR:ANY",
        "read a system status list (0x00A0: diagnostic buffer, newest first)",
    ),
    _e(
        _SFC,
        52,
        "WR_USMSG",
        "IN SEND:BOOL EVENTN:WORD INFO1:ANY INFO2:ANY; OUT RET_VAL:INT",
        "user entry in the diagnostic buffer with time stamp (EVENTN W#16#8000..BFFF)",
    ),
    _e(_SFC, 64, "TIME_TCK", "OUT RET_VAL:TIME", "ms tick of the CPU clock, wrapping at 2^31"),
    _e(
        _SFC,
        101,
        "RTM",
        "IN NR:BYTE MODE:BYTE PV:DINT; OUT RET_VAL:INT CQ:BOOL CV:DINT",
        "32-bit run-time meter NR (0..15): MODE 0 read, 1 start, 2 stop, 4/5/6 set (+start/stop)",
    ),
)

_BY_KEY: dict[str, Entry] = {e.key: e for e in CATALOGUE} | {e.name: e for e in CATALOGUE}


def find(key: str) -> Entry | None:
    """The entry for ``SFB4`` / ``SFB 4`` / ``sfb4`` / ``TON``, or None."""
    return _BY_KEY.get("".join(str(key).split()).upper())


def lookup(key: str) -> Entry:
    """Like ``find`` but an unknown block raises ``BlockError`` naming the known ones."""
    entry = find(key)
    if entry is None:
        known = ", ".join(f"{e.key} {e.name}" for e in CATALOGUE)
        raise BlockError(f"unknown system block {key!r} (known: {known})")
    return entry


# --- Engine declarations -----------------------------------------------------------------

ANY_AS = "STRING[254]"
"""How an ANY pin is declared to the engine: the pointer text ``P#M0.0 BYTE 10``."""


def engine_sections(
    entry: Entry,
) -> tuple[dict[str, dict[str, str | tuple[str, object]]], str | None]:
    """The ``engine.blocks`` sections for ``entry`` and the RET type of an SFC.

    RET_VAL becomes the SFC's return value; an ANY pin is passed as pointer text and is
    therefore an IN for the engine even when it names a destination (DSTBLK, BLK, DR). A pin
    with a default is declared ``(type, default)``: the initial value of a new instance DB.
    """
    sections: dict[str, dict[str, str | tuple[str, object]]] = {}
    ret: str | None = None
    for pin in entry.pins:
        if pin.name == "RET_VAL":
            ret = pin.type
            continue
        decl = "IN" if pin.type == "ANY" else pin.direction.value
        type_ = ANY_AS if pin.type == "ANY" else pin.type
        spec = type_ if pin.default is None else (type_, pin.default)
        sections.setdefault(decl, {})[pin.name] = spec
    return sections, ret


def pin_table(entry: Entry) -> str:
    """``entry``'s pins as a Markdown table: pin, direction, S7 type, initial value (the
    tables of docs/runtime.md, "Process control: CONT_C, CONT_S, PULSEGEN", are these)."""
    rows = ["| Pin | Direction | Type | Initial |", "| --- | --- | --- | --- |"]
    for p in entry.pins:
        rows.append(
            f"| `{p.name}` | {p.direction} | {p.type} | `{format_literal(p.type, p.initial)}` |"
        )
    return "\n".join(rows)
