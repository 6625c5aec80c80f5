"""A variable of a DB by name — ``DB20.avg``, ``DB3.motor[2].on``, ``"Oven".temp`` — as the
command line watches and sets it (docs/cli.md, "s7graph sim"; docs/scl.md, "On the command
line").

``parse_name(text)`` splits a name into the DB (a number, or a name in quotes) and its path
of members and indices; ``member(t, path)`` walks the structure ``t`` of the DB (an FB's
instance: its variables; a global DB: its declared STRUCT) to the variable's type and where
its value is: the keys into an instance DB's values (a member name, the flat index of an
ARRAY element, as the instance holds them) and the byte and bit in a global DB's bytes (as
S7 lays a DB out). ``read_bytes``/``write_bytes`` decode and encode a global DB's variable;
``plain(value)`` is a value as JSON holds it: INT and DINT signed, BYTE, WORD and DWORD
unsigned, REAL a number, TIME and TIME_OF_DAY in ms, a DATE or DT as text (``1990-01-01``,
``1990-01-01 00:00:00``), an ARRAY a list, a STRUCT or an instance an object.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from datetime import date, datetime
from typing import Any

from s7graph.engine.blocks import OBJECT
from s7graph.steps.scl import types as ty
from s7graph.steps.scl.runtime import _decode, _encode

__all__ = ["Member", "hidden_members", "member", "parse_name", "plain", "read_bytes", "write_bytes"]

_NAME = re.compile(r'\s*(?:DB\s*(\d+)|"([^"]{1,64})")\s*\.(.*)', re.IGNORECASE | re.DOTALL)
_STEP = re.compile(r"\s*(?:\.\s*([A-Za-z_]\w{0,63})|\[\s*([-+\d\s,]{1,64})\])")
_FIRST = re.compile(r"\s*([A-Za-z_]\w{0,63})")
MAX_STEPS = 16
"""Members and indices a name may have: deeper names are refused, never walked."""

Path = tuple[str | tuple[int, ...], ...]
"""Members by name and indices (one integer a dimension), in order."""


def parse_name(text: str) -> tuple[int | str, Path] | None:
    """``(20, ("avg",))`` for ``DB20.avg``, ``("Oven", ("temp",))`` for ``"Oven".temp``,
    ``(3, ("motor", (2,), "on"))`` for ``DB3.motor[2].on``; None when ``text`` is not of
    that form. ``ValueError`` for a path that does not parse."""
    found = _NAME.fullmatch(text)
    if found is None:
        return None
    db: int | str = int(found[1]) if found[1] is not None else found[2]
    rest = found[3]
    first = _FIRST.match(rest)
    if first is None:
        raise ValueError(f"{text}: a DB variable starts with a name after the DB")
    path: list[str | tuple[int, ...]] = [first[1]]
    pos = first.end()
    while pos < len(rest.rstrip()):
        step = _STEP.match(rest, pos)
        if step is None or len(path) >= MAX_STEPS:
            why = "too deep" if step is not None else f"cannot read {rest[pos:]!r}"
            raise ValueError(f"{text}: {why}")
        if step[1] is not None:
            path.append(step[1])
        else:
            try:
                path.append(tuple(int(i) for i in step[2].split(",")))
            except ValueError:
                raise ValueError(f"{text}: an index is an integer: [{step[2]}]") from None
        pos = step.end()
    return db, tuple(path)


@dataclass(frozen=True, slots=True)
class Member:
    """A DB variable found: its type, its keys into an instance's values, and its byte and
    bit in a global DB."""

    type: ty.SclType
    keys: tuple[str | int, ...]
    byte: int
    bit: int


def member(t: ty.SclType, path: Path, fbs: dict[str, ty.SclType], what: str) -> Member:
    """The variable ``path`` of a DB of structure ``t``; ``fbs``: the instance structures of
    multi-instances by FB label. ``ValueError`` naming ``what`` (the name as written) for a
    member the structure lacks or an index outside its bounds."""
    keys: list[str | int] = []
    byte = bit = 0
    for step in path:
        if t.kind == "FB":
            inner = fbs.get(t.name)
            if inner is None:
                raise ValueError(f"{what}: the instance of {t.name} cannot be read by name")
            t, byte, bit = inner, 0, 0  # a multi-instance holds values, not bytes
        if isinstance(step, str):
            t, byte, bit = _field(t, step, keys, byte, what)
        else:
            t, byte, bit = _element(t, step, keys, byte, what)
    return Member(t, tuple(keys), byte, bit)


def _field(
    t: ty.SclType, name: str, keys: list[str | int], byte: int, what: str
) -> tuple[ty.SclType, int, int]:
    found = t.field_type(name) if t.kind == "STRUCT" else None
    if found is None:
        has = ", ".join(f for f, _ in t.fields[:24]) if t.kind == "STRUCT" else ""
        raise ValueError(f"{what}: {t} has no member {name}" + (f"; it has {has}" if has else ""))
    spelled, ft = found
    keys.append(spelled)
    offset = ty.struct_layout(t)[0][spelled]
    return ft, byte + offset[0], offset[1]


def _element(
    t: ty.SclType, index: tuple[int, ...], keys: list[str | int], byte: int, what: str
) -> tuple[ty.SclType, int, int]:
    if t.kind != "ARRAY" or t.element is None:
        raise ValueError(f"{what}: {t} is not an ARRAY")
    if len(index) != len(t.dims):
        raise ValueError(f"{what}: {t} takes {len(t.dims)} index(es), not {len(index)}")
    flat, stride = 0, 1
    for (lo, hi), i in reversed(list(zip(t.dims, index, strict=True))):
        if not lo <= i <= hi:
            raise ValueError(f"{what}: index {i} outside {lo}..{hi}")
        flat += (i - lo) * stride
        stride *= hi - lo + 1
    keys.append(flat)
    if t.element.kind == "BOOL":
        return t.element, byte + flat // 8, flat % 8
    return t.element, byte + flat * ty.element_stride(t), 0


def read_bytes(buf: bytearray, m: Member) -> Any:
    """The value of ``m`` in a global DB's bytes."""
    return _decode(buf, m.byte, m.bit, m.type)


def write_bytes(buf: bytearray, m: Member, value: Any) -> None:
    """Write ``value`` (of ``m``'s type) into a global DB's bytes."""
    _encode(buf, m.byte, m.bit, m.type, value)


def plain(value: Any) -> Any:
    """``value`` as JSON holds it (see the module docstring)."""
    if isinstance(value, bool | int | float | str) or value is None:
        return value
    if isinstance(value, datetime | date):
        return str(value)  # as a chart's FB variable reads: 1990-01-01 00:00:00
    if isinstance(value, list | tuple):
        return [plain(v) for v in value]
    if isinstance(value, dict):
        return {str(k): plain(v) for k, v in value.items()}
    values = getattr(value, "values", None)  # an instance DB (a multi-instance)
    if isinstance(values, dict):
        hidden = hidden_members(getattr(value, "fb", None))
        return {str(k): plain(v) for k, v in values.items() if k not in hidden}
    return str(value)


def hidden_members(fb: Any) -> frozenset[str]:
    """The variables of an FB's instances that hold the block's own Python state (an IEC
    timer's or counter's ``STATE``): no S7 value, never shown."""
    interface = getattr(fb, "interface", ())
    return frozenset(var.name for var in interface if var.type == OBJECT)
