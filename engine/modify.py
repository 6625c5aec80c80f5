"""Modifying: a value written once, as STEP 7's "Modify Variables" writes it and TIA Portal's
*Modify to 1*, *Modify to 0* and *Modify value* do from a watch table or a block's status
view (docs/runtime.md, "Modify").

Unlike a force job (``engine/force.py``) a modify is not held: it is written once, at a
scan boundary, and the program and the modules may write the operand again at once, as on
S7. ``MODIFY_POINTS`` is the one table of the areas that can be modified and where the
value goes:

- **I**: into the inputs as the modules deliver them (the peripheral inputs): the next
  scan reads them into the process-image input table, so the program sees the value in
  that scan — until the modules (the plant) deliver another one;
- **Q**: into the process-image output table: the modules get it at the end of the next
  scan unless the program writes it first;
- **M**: into the flags;
- **DB**: into the data block (``DB20.DBX0.1``, ``DB20.DBW2``; the DB must exist).

A bit, byte, word or double word, by address or by a symbol (in its declared type), with
the values a force takes (``TRUE``, ``-5``, ``16#00FF``, ``T#5S``, ``1.5``). An operand a
force job holds is refused: the force value would be written over it at its next point
(unforce it first). Pure data and a write into ``Memory``: no clock, no threads.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Final

from s7graph.engine.address import Address, Area, Width
from s7graph.engine.datatypes import decode, type_of
from s7graph.engine.errors import S7Error
from s7graph.engine.force import ForceTable, bit_masks, encode_value, resolve_operand

if TYPE_CHECKING:
    from s7graph.engine.memory import Memory

__all__ = ["MODIFY_POINTS", "Modify", "ModifyError", "make_modify", "typed_value", "write_modify"]

MODIFY_POINTS: Final[dict[Area, str]] = {
    Area.I: "the peripheral inputs: the next scan reads them into the process image",
    Area.Q: "the process-image output table: the modules get it at the end of the next scan",
    Area.M: "the flags",
    Area.DB: "the data block",
}
"""The areas that can be modified, and where the value is written."""


_WIDTHS: Final = {1: Width.BIT, 8: Width.BYTE, 16: Width.WORD, 32: Width.DWORD}


class ModifyError(S7Error):
    """A modify refused: unknown operand, an area that cannot be modified, a value that does
    not fit, an operand outside its area or a forced one; the message names the problem."""


@dataclass(frozen=True, slots=True)
class Modify:
    """One modify: ``address`` written with ``value`` (its raw bits, unsigned; a bit 0/1),
    ``shown`` as the engineer reads it, ``symbol`` the name it was given by ("" for an
    absolute address)."""

    address: Address
    value: int
    shown: str
    symbol: str = ""
    variable: str = ""
    """A DB variable's name when it was given by one (``DB20.avg``)."""

    def __str__(self) -> str:
        if self.symbol:
            name = f'"{self.symbol}" ({self.address})'
        elif self.variable:
            name = f"{self.variable} ({self.address})"
        else:
            name = str(self.address)
        return f"{name} = {self.shown}"


def make_modify(
    mem: Memory,
    target: str | Address,
    value: object,
    *,
    type_name: str | None = None,
    variable: str = "",
) -> Modify:
    """The modify of ``target`` (an address or a symbol of ``mem.symbols``) with ``value``;
    an address may come with its type (``type_name``) and the DB variable it is
    (``variable``). ModifyError names what is wrong."""
    address, declared, symbol = resolve_operand(mem, target, ModifyError)
    type_name = type_name or declared
    if address.area not in MODIFY_POINTS:
        areas = ", ".join(str(a) for a in MODIFY_POINTS)
        raise ModifyError(
            f"{address} cannot be modified: only {areas} can (inputs, outputs, flags, data)"
        )
    size = len(_buffer(mem, address))
    if address.byte + address.size > size:
        where = f"DB{address.db}" if address.area is Area.DB else f"the {address.area} area"
        raise ModifyError(f"{address} is outside {where} ({size} bytes)")
    name = f'"{symbol}" ({address})' if symbol else variable or str(address)
    raw, shown = encode_value(address, type_name, name, value, "modify", ModifyError)
    return Modify(address, raw, shown, symbol, variable)


def typed_value(type_name: str, name: str, value: object) -> tuple[object, str]:
    """The value of S7 type ``type_name`` that ``value`` stands for (``TRUE``, ``-5``,
    ``T#5S``, ``1.5``, JSON's true, 5, 1.5) and how S7 writes it, by the rules a modify of
    an address of that type follows: for a variable that lives as a value, not in bytes
    (an instance DB's). ModifyError names ``name`` and what does not fit; a type wider
    than a double word or a STRING cannot be modified."""
    try:
        size = type_of(type_name).size_bits
    except S7Error:
        size = 0
    width = _WIDTHS.get(1 if type_name == "BOOL" else size)
    if width is None:
        article = "an" if type_name[:1] in ("A", "E", "I", "O") else "a"
        raise ModifyError(
            f"{name} is {article} {type_name}: a modify writes a bit, a byte, a word or a "
            "double word"
        )
    shape = Address(Area.M, width, 0, 0)
    raw, shown = encode_value(shape, type_name, name, value, "modify", ModifyError)
    if width is Width.BIT:
        return bool(raw), shown
    return decode(type_name, raw.to_bytes(shape.size, "big")), shown


def write_modify(mem: Memory, forces: ForceTable, modify: Modify) -> None:
    """Write ``modify`` where :data:`MODIFY_POINTS` says (call at a scan boundary);
    ModifyError when a force job holds a bit of it."""
    held = forces.holding(modify.address)
    if held is not None:
        raise ModifyError(
            f"{modify.address} is forced ({held}): the force value would be written over "
            f"it; unforce {held.address} first"
        )
    buf = _buffer(mem, modify.address)
    for byte, (mask, bits) in bit_masks(modify.address, modify.value).items():
        buf[byte] = buf[byte] & ~mask & 0xFF | bits


def _buffer(mem: Memory, address: Address) -> bytearray | memoryview:
    """The bytes a modify of ``address`` is written into (the I area: as many peripheral
    inputs as the process image has)."""
    if address.area is Area.I:
        return memoryview(mem.periph_in)[: len(mem.inputs)]
    try:
        return mem.area_bytes(address.area, address.db)
    except S7Error as exc:
        raise ModifyError(f"{address}: {exc.message}") from None
