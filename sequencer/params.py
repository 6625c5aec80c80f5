"""The FB pins of a GRAPH FB and the parameter sets holding them: the one table (docs/semantics.md,
"FB pins").

Sources: docs/semantics.md, "Decisions" (STEP7 comprehensive guide vol. 2, ch. 14 for the
User-defined set, STEP7 comprehensive guide vol. 2, ch. 14
and TIA "Standard" for STANDARD, STEP7 comprehensive guide vol. 2, ch. 14 for MAXIMUM). The sets
nest:
MINIMUM ⊂ STANDARD ⊂ MAXIMUM ⊂ USER. The book's table at STEP7 comprehensive guide vol. 2, ch. 14
also lists REG_EF,
ACK_S, REG_S, T_PREV, T_NEXT under Standard; per the errata they belong to USER only.

Everything that needs to know which pins exist reads this table: the FB interface
(``sequencer/fb.py``), the ``sim`` stimulus and watch names (docs/cli.md, "s7graph sim"), programs
that write pins, and docs/semantics.md (``markdown_table``).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from enum import StrEnum
from typing import Final

from s7graph.engine.errors import SourceLocation, SymbolError
from s7graph.sequencer.text.model import ChartOptions

PARAMETER_SETS: Final = ("MINIMUM", "STANDARD", "MAXIMUM", "USER")


class Direction(StrEnum):
    IN = "IN"
    OUT = "OUT"


@dataclass(frozen=True, slots=True)
class Pin:
    """One FB parameter: ``smallest`` is the smallest parameter set that has it (the sets
    nest, so every larger set has it too); ``default`` is an input's value while unwired
    (an output's value before the first call) unless ``OPTION_DEFAULTS`` gives it a chart
    option."""

    name: str
    direction: Direction
    type: str
    comment: str
    smallest: str
    default: object = False

    @property
    def sets(self) -> tuple[str, ...]:
        """The parameter sets that contain this pin."""
        return PARAMETER_SETS[PARAMETER_SETS.index(self.smallest) :]

    def in_set(self, set_name: str) -> bool:
        return PARAMETER_SETS.index(set_name) >= PARAMETER_SETS.index(self.smallest)


class PinError(SymbolError):
    """An FB pin that does not exist, or is not part of the chart's parameter set."""


_I, _O = Direction.IN, Direction.OUT
MIN, STD, MAX, USR = PARAMETER_SETS

# (name, direction, type, smallest set, default, comment). Order = the FB interface order of
# STEP7 comprehensive guide vol. 2, ch. 14 (inputs first, then outputs).
_TABLE: Final[tuple[tuple[str, Direction, str, str, object, str], ...]] = (
    ("OFF_SQ", _I, "BOOL", STD, False, "Sequencer off: all steps deactivated while 1"),
    ("INIT_SQ", _I, "BOOL", MIN, False, "Rising edge: initial steps on, all others off"),
    ("ACK_EF", _I, "BOOL", STD, False, "Rising edge: acknowledge all errors and faults"),
    ("REG_EF", _I, "BOOL", USR, False, "Rising edge: register all errors (event R1)"),
    ("ACK_S", _I, "BOOL", USR, False, "Rising edge: acknowledge the step shown in S_NO"),
    ("REG_S", _I, "BOOL", USR, False, "Rising edge: register the step shown in S_NO (R1)"),
    ("HALT_SQ", _I, "BOOL", MAX, False, "Halt the sequencer: no switching, steps stay"),
    ("HALT_TM", _I, "BOOL", MAX, False, "Halt step times and D/L timing"),
    ("ZERO_OP", _I, "BOOL", MAX, False, "N, D, L operands forced to 0, CALLs skipped"),
    ("EN_IL", _I, "BOOL", MAX, True, "Enable interlocks (0: every interlock holds)"),
    ("EN_SV", _I, "BOOL", MAX, True, "Enable supervisions (0: no supervision faults)"),
    ("EN_ACKREQ", _I, "BOOL", USR, True, "Faults must be acknowledged"),
    ("EN_SSKIP", _I, "BOOL", USR, False, "Skip steps"),
    ("DISP_SACT", _I, "BOOL", USR, False, "Rising edge: S_NO pages through active steps"),
    ("DISP_SEF", _I, "BOOL", USR, False, "Rising edge: S_NO pages through disturbed steps"),
    ("DISP_SALL", _I, "BOOL", USR, False, "Rising edge: S_NO pages through all steps"),
    (
        "S_PREV",
        _I,
        "BOOL",
        STD,
        False,
        "Rising edge: show the previous step in S_NO (in MAN: the next lower number)",
    ),
    (
        "S_NEXT",
        _I,
        "BOOL",
        STD,
        False,
        "Rising edge: show the next step in S_NO (in MAN: the next higher number)",
    ),
    ("SW_AUTO", _I, "BOOL", STD, False, "Rising edge: mode AUTO"),
    ("SW_TAP", _I, "BOOL", STD, False, "Rising edge: mode TAP (transition and push)"),
    ("SW_TOP", _I, "BOOL", STD, False, "Rising edge: mode TOP (transition or push)"),
    ("SW_MAN", _I, "BOOL", STD, False, "Rising edge: mode MAN (manual)"),
    ("S_SEL", _I, "INT", STD, 0, "Step number to show in S_NO (applied when it changes)"),
    ("S_SELOK", _I, "BOOL", USR, False, "Rising edge: apply S_SEL again"),
    ("S_ON", _I, "BOOL", STD, False, "MAN, rising edge: activate the step shown in S_NO"),
    ("S_OFF", _I, "BOOL", STD, False, "MAN, rising edge: deactivate the step in S_NO"),
    ("T_PREV", _I, "BOOL", USR, False, "Rising edge: show the previous valid transition"),
    ("T_NEXT", _I, "BOOL", USR, False, "Rising edge: show the next valid transition"),
    ("T_PUSH", _I, "BOOL", STD, False, "TAP/TOP, rising edge: permission to switch"),
    ("S_NO", _O, "INT", STD, 0, "Step number shown (0: none)"),
    ("S_MORE", _O, "BOOL", STD, False, "More steps to page through in the display set"),
    ("S_ACTIVE", _O, "BOOL", STD, False, "The step shown in S_NO is active"),
    ("S_TIME", _O, "TIME", USR, 0, "Activation time T of the step shown"),
    ("S_TIMEOK", _O, "TIME", USR, 0, "Activation time without disturbance U of the step"),
    ("S_CRITLOC", _O, "DWORD", USR, 0, "Interlock criteria bits of the step shown"),
    ("S_CRITLOCERR", _O, "DWORD", USR, 0, "Interlock criteria when the interlock was lost"),
    ("S_CRITSUP", _O, "DWORD", USR, 0, "Supervision criteria bits of the step shown"),
    ("S_STATE", _O, "WORD", USR, 0, "Status word of the step shown (display.S_STATE_BITS)"),
    ("T_NO", _O, "INT", USR, 0, "Valid transition shown (0: none)"),
    ("T_MORE", _O, "BOOL", USR, False, "More valid transitions to page through"),
    ("T_CRIT", _O, "DWORD", USR, 0, "Criteria bits of the transition shown"),
    ("T_CRITOLD", _O, "DWORD", USR, 0, "Criteria bits of its previous evaluation"),
    ("T_CRITFLT", _O, "DWORD", USR, 0, "Criteria bits when the preceding step faulted"),
    ("ERROR", _O, "BOOL", USR, False, "Some active step has an interlock error"),
    ("FAULT", _O, "BOOL", USR, False, "Some step has a supervision fault"),
    ("ERR_FLT", _O, "BOOL", STD, False, "Group error: ERROR or FAULT"),
    ("SQ_ISOFF", _O, "BOOL", USR, False, "Sequencer is off (no step active)"),
    ("SQ_HALTED", _O, "BOOL", MAX, False, "Sequencer halted"),
    ("TM_HALTED", _O, "BOOL", MAX, False, "Times halted"),
    ("OP_ZEROED", _O, "BOOL", MAX, False, "Operands zeroed"),
    ("IL_ENABLED", _O, "BOOL", MAX, True, "Interlocks enabled"),
    ("SV_ENABLED", _O, "BOOL", MAX, True, "Supervisions enabled"),
    ("ACKREQ_ENABLED", _O, "BOOL", USR, True, "Acknowledgement required"),
    ("SSKIP_ENABLED", _O, "BOOL", USR, False, "Skip steps enabled"),
    ("SACT_DISP", _O, "BOOL", USR, True, "S_NO pages through active steps"),
    ("SEF_DISP", _O, "BOOL", USR, False, "S_NO pages through disturbed steps"),
    ("SALL_DISP", _O, "BOOL", USR, False, "S_NO pages through all steps"),
    ("AUTO_ON", _O, "BOOL", STD, True, "Mode AUTO"),
    ("TAP_ON", _O, "BOOL", STD, False, "Mode TAP"),
    ("TOP_ON", _O, "BOOL", STD, False, "Mode TOP"),
    ("MAN_ON", _O, "BOOL", STD, False, "Mode MAN"),
)

# The block options that are the defaults of run-time pins (S7-GRAPH block settings "Skip
# steps" and "Acknowledge errors" with their pins EN_SSKIP / EN_ACKREQ and the outputs
# SSKIP_ENABLED / ACKREQ_ENABLED; docs/semantics.md, "Decisions", §C): pin → (``.s7g`` option,
# ``ChartOptions`` field). The instance DB starts with the option's value in the pin, so an
# unwired pin follows the option and a value written to the pin wins from then on.
OPTION_DEFAULTS: Final[dict[str, tuple[str, str]]] = {
    "EN_ACKREQ": ("ACK_REQUIRED", "ack_required"),
    "EN_SSKIP": ("SKIP_STEPS", "skip_steps"),
    "ACKREQ_ENABLED": ("ACK_REQUIRED", "ack_required"),
    "SSKIP_ENABLED": ("SKIP_STEPS", "skip_steps"),
}

PINS: Final[tuple[Pin, ...]] = tuple(
    Pin(name, direction, type_, comment, smallest, default)
    for name, direction, type_, smallest, default, comment in _TABLE
)
_BY_NAME: Final[dict[str, Pin]] = {p.name: p for p in PINS}
_BY_SET: Final[dict[str, tuple[Pin, ...]]] = {
    s: tuple(p for p in PINS if p.in_set(s)) for s in PARAMETER_SETS
}


def _set_name(set_name: str) -> str:
    key = set_name.upper()
    if key not in _BY_SET:
        raise PinError(f"unknown parameter set {set_name!r}; use {', '.join(PARAMETER_SETS)}")
    return key


def pins_for(set_name: str) -> tuple[Pin, ...]:
    """The pins of a parameter set (case-insensitive name), inputs first, in FB order."""
    return _BY_SET[_set_name(set_name)]


def inputs_for(set_name: str) -> tuple[Pin, ...]:
    return tuple(p for p in pins_for(set_name) if p.direction is Direction.IN)


def outputs_for(set_name: str) -> tuple[Pin, ...]:
    return tuple(p for p in pins_for(set_name) if p.direction is Direction.OUT)


def pin(name: str) -> Pin | None:
    """The pin called ``name`` (case-insensitive), in any set; None if no such pin."""
    return _BY_NAME.get(name.upper())


def is_pin(name: str) -> bool:
    return name.upper() in _BY_NAME


def check_pin(
    name: str,
    set_name: str,
    where: SourceLocation | str | None = None,
    *,
    direction: Direction | None = None,
) -> Pin:
    """The pin ``name`` of parameter set ``set_name``, or a ``PinError`` saying what to do.

    Used by ``sim`` stimulus/watch names and by programs that read or write pins; pass
    ``direction=Direction.IN`` where only an input may stand (a stimulus)."""
    p = pin(name)
    set_key = _set_name(set_name)
    if p is None:
        raise PinError(f"{name} is not an FB pin of a GRAPH FB", where)
    if not p.in_set(set_key):
        larger = " or ".join(PARAMETER_SETS[PARAMETER_SETS.index(p.smallest) :])
        raise PinError(
            f"pin {p.name} is not in parameter set {set_key}; use PARAMETERS := {larger}",
            where,
        )
    if direction is not None and p.direction is not direction:
        what = "an input" if direction is Direction.IN else "an output"
        raise PinError(f"pin {p.name} is an {p.direction.value} pin, not {what}", where)
    return p


def input_defaults(set_name: str, options: ChartOptions | None = None) -> dict[str, object]:
    """The value of every input pin (of every set) while nothing drives it.

    Pins outside ``set_name`` do not exist on the FB, so they keep these values for good.
    With ``options`` a pin of ``OPTION_DEFAULTS`` starts at its option's value."""
    _set_name(set_name)
    return _defaults([p for p in PINS if p.direction is Direction.IN], options)


def output_defaults(set_name: str, options: ChartOptions | None = None) -> dict[str, object]:
    """The value of each output pin of ``set_name`` before the first call (ACKREQ_ENABLED
    and SSKIP_ENABLED show their option, as the first call will)."""
    return _defaults(outputs_for(set_name), options)


def _defaults(pins: Iterable[Pin], options: ChartOptions | None) -> dict[str, object]:
    values: dict[str, object] = {}
    for p in pins:
        option = OPTION_DEFAULTS.get(p.name)
        if options is not None and option is not None:
            values[p.name] = getattr(options, option[1])
        else:
            values[p.name] = p.default
    return values


def markdown_table() -> str:
    """The pin table as Markdown, for docs/semantics.md (one row per pin, ✓ per set)."""
    head = "| Pin | Dir | Type | " + " | ".join(PARAMETER_SETS) + " | Default | Meaning |"
    rule = "|---|---|---|" + "---|" * len(PARAMETER_SETS) + "---|---|"
    rows = [head, rule]
    for p in PINS:
        marks = " | ".join("✓" if p.in_set(s) else "" for s in PARAMETER_SETS)
        default = "" if p.direction is Direction.OUT else _fmt(p.default)
        if p.name in OPTION_DEFAULTS and p.direction is Direction.IN:
            option, field_name = OPTION_DEFAULTS[p.name]
            default = f"option {option} ({_fmt(getattr(ChartOptions(), field_name))})"
        rows.append(
            f"| `{p.name}` | {p.direction.value} | {p.type} | {marks} | {default} | {p.comment} |"
        )
    return "\n".join(rows) + "\n"


def _fmt(value: object) -> str:
    if isinstance(value, bool):
        return "TRUE" if value else "FALSE"
    return str(value)
