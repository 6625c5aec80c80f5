"""A global DB's structure as the engine's layout: every variable by its name, S7 type and
place, as S7 lays a DB out (docs/scl.md, "Global DBs by name"; Siemens' Program Design
for S7-300/400, appendix C).

The offsets are the compiler's own (``types.struct_layout``, ``types.element_stride``),
so a name read over the bus (``DB20.avg``) reads the bytes the program writes. Names are
dotted for members (``recipe.speed``); an ARRAY of an elementary type or STRING is one
slot (``speeds``, type ``ARRAY[1..5] OF INT``: an index picks its element), an ARRAY of
STRUCT gets a slot per element and member (``motor[2]``, ``motor[2].on``; ``grid[1,2].x``
for two dimensions).
"""

from __future__ import annotations

import itertools

from s7graph.engine.datatypes import Layout, Slot
from s7graph.steps.scl import types as ty

__all__ = ["db_layout"]


def db_layout(t: ty.SclType) -> Layout:
    """The layout of a global DB of structure ``t`` (a STRUCT or a UDT)."""
    slots: dict[str, Slot] = {}
    _struct(t, "", 0, slots)
    return Layout(slots, ty.size_of(t))


def _struct(t: ty.SclType, prefix: str, start: int, out: dict[str, Slot]) -> None:
    offsets = ty.struct_layout(t)[0]
    for name, ft in t.fields:
        byte, bit = offsets[name]
        _place(f"{prefix}{name}", ft, start + byte, bit, out)


def _place(name: str, t: ty.SclType, byte: int, bit: int, out: dict[str, Slot]) -> None:
    if t.kind == "STRUCT":
        out[name] = Slot(byte, 0, "STRUCT", ty.size_of(t))
        _struct(t, f"{name}.", byte, out)
        return
    if t.kind == "ARRAY":
        assert t.element is not None
        if t.element.kind != "STRUCT":
            out[name] = Slot(byte, 0, str(t), ty.size_of(t))
            return
        out[name] = Slot(byte, 0, "ARRAY", ty.size_of(t))
        one: dict[str, Slot] = {}  # an element laid out once, copied to each place
        _place("", t.element, 0, 0, one)
        stride = ty.element_stride(t)
        ranges = [range(lo, hi + 1) for lo, hi in t.dims]
        for k, index in enumerate(itertools.product(*ranges)):
            at, spelled = byte + k * stride, f"{name}[{','.join(map(str, index))}]"
            for sub, slot in one.items():
                out[spelled + sub] = Slot(slot.byte + at, slot.bit, slot.type, slot.size)
        return
    if t.kind == "BOOL":
        out[name] = Slot(byte, bit, "BOOL", 0)
        return
    out[name] = Slot(byte, 0, str(t), ty.size_of(t))
