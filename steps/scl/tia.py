"""TIA Portal's SCL notations that S7-SCL V5 does not have, and what S7-SCL V5 writes
instead: an engineer who knows TIA Portal writes them from habit, and the diagnostic says
so rather than only that a name or character is unknown (docs/scl.md, "Where TIA Portal
differs")."""

from __future__ import annotations

__all__ = ["function_hint", "syntax_hint", "type_hint"]

_FUNCTIONS = {
    "INT_TO_STRING": "I_STRNG",
    "DINT_TO_STRING": "DI_STRNG",
    "REAL_TO_STRING": "R_STRNG",
    "STRING_TO_INT": "STRNG_I",
    "STRING_TO_DINT": "STRNG_DI",
    "STRING_TO_REAL": "STRNG_R",
}
"""TIA Portal's string conversions and S7-SCL V5's IEC functions doing the same."""

_TYPES = {
    "LREAL": "REAL",
    "LINT": "DINT",
    "SINT": "INT",
    "USINT": "BYTE or INT",
    "UINT": "WORD or DINT",
    "UDINT": "DWORD or DINT",
    "ULINT": "DINT",
    "LWORD": "DWORD",
    "WSTRING": "STRING",
    "WCHAR": "CHAR",
    "LTIME": "TIME",
    "LTOD": "TIME_OF_DAY",
    "LTIME_OF_DAY": "TIME_OF_DAY",
    "LDT": "DATE_AND_TIME",
    "DTL": "DATE_AND_TIME",
}
"""TIA Portal's data types of S7-1200/1500 and the S7-300/400 type closest to each."""


def function_hint(name: str) -> str | None:
    """What S7-SCL V5 calls TIA Portal's function ``name``, as a sentence; None if it is
    not one of them."""
    v5 = _FUNCTIONS.get(name.upper())
    if v5 is None:
        return None
    return f"{name.upper()} is TIA Portal's; S7-SCL V5 writes {v5}"


_EDGES = {"R_TRIG": "clk AND NOT last", "F_TRIG": "NOT clk AND last"}
"""TIA Portal's edge FBs, which S7-300/400 has no system block for: the edge S7-SCL V5
computes with a static BOOL instead."""


def type_hint(name: str) -> str | None:
    """What to declare instead of TIA Portal's data type ``name``; None if it is not one."""
    key = "".join(name.split()).upper()
    if key in _EDGES:
        return (
            f"{key} is TIA Portal's: S7-300/400 has no such system block; keep the last "
            f"input in a static BOOL (q := {_EDGES[key]}; last := clk;)"
        )
    v5 = _TYPES.get(key)
    if v5 is None:
        return None
    return f"{name.upper()} is a TIA Portal type of S7-1200/1500, not S7-SCL V5's: use {v5}"


def syntax_hint(found: str, before: str | None, after: str) -> str | None:
    """What S7-SCL V5 writes where the parser found ``found`` (a character or a token)
    after the token ``before`` and before the text ``after``; None when ``found`` is not
    TIA Portal's notation."""
    if found == "#" and (after[:1].isalpha() or after[:1] in ("_", '"')):
        return "'#' before a local name is TIA Portal's: S7-SCL V5 writes the name alone"
    if found == ">" and before == "=":
        return (
            "'=>' in a call is TIA Portal's: S7-SCL V5 reads an FB's output after the call "
            "(inst.Q) and gives an FC's output with ':='"
        )
    word = (before or "").upper()
    if word in ("REGION", "END_REGION"):
        return f"{word} is TIA Portal's: S7-SCL V5 has no regions; leave the line out"
    return None
