"""Names and addresses across formats: which names a `.s7g` chart can hold unquoted, and
IEC directly represented variables (``%IX0.1``) ↔ S7 addresses (``I0.1``).

An FB variable's name must read back as that variable wherever the chart uses it: not a
keyword, event or FB pin of GRAPH, not ``S`` or ``R`` (a permanent set/reset coil) or ``C``
(the interlock mark), not a step (``S3``) or block (``FB1``) reference. Other names get
a ``_`` suffix (the importer reports each rename).

IEC addresses: ``%I`` ``%Q`` ``%M`` with size ``X`` (or none) ``B`` ``W`` ``D`` and the
two-level ``byte.bit`` form map one to one (``%QX2.3`` → ``Q2.3``, ``%MW4`` → ``MW4``); a
one-level bit address ``%IXn`` counts bits from ``I0.0`` (``%IX9`` → ``I1.1``); ``L``
(64-bit) and deeper hierarchies have no S7 form.
"""

from __future__ import annotations

import re
from typing import Final

from s7graph.sequencer.params import pin

__all__ = ["iec_address", "is_graph_name", "s7_to_iec", "safe_name"]

_KEYWORDS: Final = frozenset(
    [
        "FUNCTION_BLOCK",
        "END_FUNCTION_BLOCK",
        "VAR",
        "END_VAR",
        "SYMBOLS",
        "END_SYMBOLS",
        "PERMANENT",
        "END_PERMANENT",
        "BEFORE",
        "AFTER",
        "CALL",
        "SEQUENCE",
        "END_SEQUENCE",
        "STEP",
        "INITIAL_STEP",
        "END_STEP",
        "INTERLOCK",
        "SUPERVISION",
        "TRANSITION",
        "FROM",
        "TO",
        "STOP",
        "S_ALL",
        "OR",
        "XOR",
        "AND",
        "NOT",
        "MOD",
        "SHL",
        "SHR",
        "SSR",
        "ROL",
        "ROR",
        "TRUE",
        "FALSE",
        "S1",
        "S0",
        "V1",
        "V0",
        "L1",
        "L0",
        "A1",
        "R1",
        "S",
        "R",
        "C",
    ]
)
_NAME: Final = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_REFERENCE: Final = re.compile(r"(?i)(S\d+|(SFB|SFC|FB|FC|DB)\d+)")


def is_graph_name(name: str) -> bool:
    """``name`` can be an unquoted FB variable of a chart."""
    up = name.upper()
    if not _NAME.fullmatch(name) or up in _KEYWORDS or _REFERENCE.fullmatch(name):
        return False
    return pin(name) is None


def safe_name(name: str, taken: set[str]) -> str:
    """``name`` made a valid, unused (``taken`` holds upper-case names) FB variable name."""
    base = re.sub(r"[^A-Za-z0-9_]", "_", name) or "v"
    if not re.match(r"[A-Za-z_]", base):
        base = "v_" + base
    candidate = base if is_graph_name(base) else base + "_"
    n = 2
    while candidate.upper() in taken or not is_graph_name(candidate):
        candidate = f"{base}_{n}"
        n += 1
    return candidate


_IEC: Final = re.compile(r"%([IQM])([XBWDL]?)(\d+(?:\.\d+)*)", re.IGNORECASE)


def iec_address(text: str) -> str | None:
    """The S7 address of an IEC location, or None when it has none."""
    m = _IEC.fullmatch(text.strip())
    if m is None:
        return None
    area, size, nums = m.group(1).upper(), m.group(2).upper(), m.group(3).split(".")
    if size == "L":
        return None
    if size in ("", "X"):
        if len(nums) == 1:
            n = int(nums[0])
            return f"{area}{n // 8}.{n % 8}"
        if len(nums) == 2 and int(nums[1]) < 8:
            return f"{area}{int(nums[0])}.{int(nums[1])}"
        return None
    if len(nums) != 1:
        return None
    return f"{area}{size}{int(nums[0])}"


_S7: Final = re.compile(r"([IQM])([BWD]?)(\d+)(?:\.(\d))?", re.IGNORECASE)


def s7_to_iec(address: str) -> str | None:
    """The IEC location of an S7 address (I/Q/M areas), or None."""
    m = _S7.fullmatch(address.replace(" ", ""))
    if m is None:
        return None
    area, size, byte, bit = m.group(1).upper(), m.group(2).upper(), m.group(3), m.group(4)
    if bit is not None and not size:
        return f"%{area}X{int(byte)}.{bit}"
    if size and bit is None:
        return f"%{area}{size}{int(byte)}"
    return None
