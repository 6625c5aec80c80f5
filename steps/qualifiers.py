"""Which qualifier may follow which event: the one table (docs/semantics.md, "Actions", STEP7
comprehensive guide vol. 2, ch. 14).

Code reads ``ALLOWED``; the validator and the compiler are derived
from it. A row is ``(event, qualifier, interlocked, operand kind)``; an operand kind is one of
``bit`` (N S R on a bit), ``assign`` (N with ``:=``), ``call``, ``step`` (ON/OFF Sx),
``s_all`` (OFF S_ALL), ``counter`` (CS CU CD CR), ``timer`` (TL TD TF TR), ``timed`` (D, L).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Final

EVENTS: Final = ("S1", "S0", "V1", "V0", "L1", "L0", "A1", "R1")
QUALIFIERS: Final = (
    "N",
    "S",
    "R",
    "D",
    "L",
    "CALL",
    "ON",
    "OFF",
    "CS",
    "CU",
    "CD",
    "CR",
    "TL",
    "TD",
    "TF",
    "TR",
)

# Step event bits (``GraphState.ev[i]`` of the sequencer), in the order of ``EVENTS``.
EV_S1: Final = 1  # step activated in this call
EV_S0: Final = 2  # step deactivated in this call
EV_V1: Final = 4  # supervision fault came (or was present at activation)
EV_V0: Final = 8  # supervision fault went (eliminated or acknowledged)
EV_L1: Final = 16  # interlock lost (or not held at activation)
EV_L0: Final = 32  # interlock returned
EV_A1: Final = 64  # fault acknowledged
EV_R1: Final = 128  # registration (REG_EF / REG_S)
EVENT_BITS: Final = {
    "S1": EV_S1,
    "S0": EV_S0,
    "V1": EV_V1,
    "V0": EV_V0,
    "L1": EV_L1,
    "L0": EV_L0,
    "A1": EV_A1,
    "R1": EV_R1,
}
EVENT_NAMES: Final = tuple(EVENT_BITS)

# Events whose rows may carry the interlock mark C.
EVENTS_WITH_C: Final = frozenset({"S1", "V1", "A1", "R1"})
# Events after which OFF S_ALL may stand.
EVENTS_WITH_S_ALL: Final = frozenset({"S1", "V1", "L1"})
# Events after which OFF S_ALL may carry C (only those of EVENTS_WITH_C).
COUNTER_QUALIFIERS: Final = frozenset({"CS", "CU", "CD", "CR"})
TIMER_QUALIFIERS: Final = frozenset({"TL", "TD", "TF", "TR"})
TIMED_QUALIFIERS: Final = frozenset({"D", "L"})
# Qualifiers whose row needs a value after the comma.
NEEDS_VALUE: Final = frozenset({"D", "L", "CS", "TL", "TD", "TF"})


@dataclass(frozen=True, slots=True)
class Rule:
    """Whether a (event, qualifier, C, operand kind) row is allowed, and why not."""

    allowed: bool
    reason: str = ""


def operand_kind(qualifier: str, *, assignment: bool = False, s_all: bool = False) -> str:
    """The operand kind of a row, as used by ``check``."""
    if qualifier in COUNTER_QUALIFIERS:
        return "counter"
    if qualifier in TIMER_QUALIFIERS:
        return "timer"
    if qualifier in TIMED_QUALIFIERS:
        return "timed"
    if qualifier == "CALL":
        return "call"
    if qualifier in ("ON", "OFF"):
        return "s_all" if s_all else "step"
    if qualifier == "N" and assignment:
        return "assign"
    return "bit"


def check(event: str | None, qualifier: str, interlocked: bool, kind: str) -> Rule:
    """Apply the table of docs/semantics.md, "Actions" to one action row."""
    if qualifier not in QUALIFIERS:
        return Rule(False, f"unknown qualifier {qualifier!r}")
    if event is not None and event not in EVENTS:
        return Rule(False, f"unknown event {event!r}")
    if kind == "timed":
        if event is not None:
            return Rule(False, f"{qualifier} takes no event ({event} {qualifier} is not allowed)")
        return Rule(True)
    if kind in ("counter", "timer"):
        # Counters and timers need an event (they run once, in the event call).
        if event is None:
            return Rule(False, f"{qualifier} needs an event (S1 S0 V1 V0 L1 L0 A1 R1)")
        return Rule(True)
    if kind == "assign":
        return Rule(True)  # with any event or none, with or without C
    if qualifier in ("ON", "OFF") and event is None:
        return Rule(False, f"{qualifier} needs an event (S1 V1 A1 R1 S0 V0 L0 L1)")
    if kind == "s_all":
        if qualifier != "OFF":
            return Rule(False, "only OFF may take S_ALL")
        if event not in EVENTS_WITH_S_ALL:
            return Rule(False, f"OFF S_ALL is allowed only with S1, V1 or L1, not {event}")
    if event is None:
        return Rule(True)  # N S R CALL with or without C
    if interlocked and event not in EVENTS_WITH_C:
        return Rule(
            False, f"{event} {qualifier}C: the interlock mark C is allowed only with S1 V1 A1 R1"
        )
    return Rule(True)
