"""Operands by name for the sessions that run a program on the virtual clock (a chart's,
``web.harness.session``, and an S7-SCL program's, ``web.cli.scl``): an address or a
symbol, and how a stimulus writes one."""

from __future__ import annotations

from typing import Any

from s7graph.engine.address import Address, Area, parse_address
from s7graph.engine.blocks import from_stored
from s7graph.engine.datatypes import check_value, type_of
from s7graph.engine.errors import AddressError, S7Error
from s7graph.engine.literals import parse_literal
from s7graph.engine.memory import Memory
from s7graph.engine.modify import ModifyError, typed_value
from s7graph.engine.symbols import SymbolTable, default_type


def address_of(symbols: SymbolTable | None, name: str) -> tuple[Address, str] | None:
    """The address and type of a symbol (its declared type) or of an absolute address
    (its default type); None for any other name."""
    sym = symbols.lookup(name) if symbols is not None else None
    if sym is not None:
        return sym.address, sym.type
    try:
        addr = parse_address(name)
    except AddressError:
        return None
    return addr, default_type(addr)


def bad_address(name: str) -> AddressError | None:
    """Why ``name``, written as an S7 address, is none (``M10.8``: bit 8 outside 0..7;
    ``DB1.DBX99999.0``: byte 99999 outside 0..65535); None for a name of another form or a
    valid address. A name no address, symbol or variable resolves is refused with this,
    not as an unknown name."""
    try:
        parse_address(name)
    except AddressError as exc:
        return None if "not an S7 address" in exc.message else exc
    return None


def write_operand(mem: Memory, addr: Address, type_name: str, value: Any) -> None:
    """Write ``value`` at ``addr`` as ``type_name``; an input on the module side too, so
    the CPU reads it into the process image at the start of the next cycle. A word or
    double word in its width's type takes ``value`` in the format it is given in, as a
    watch table's display format: a negative number as INT / DINT, a number with a point
    as REAL (double words) — ``MW10: -5``, ``MD20: 1.5``."""
    mem.write_as(addr, written_as(addr, type_name, value), value)
    if addr.area is Area.I:
        n = addr.byte
        size = max(1, int(addr.width) // 8)
        mem.periph_in[n : n + size] = mem.inputs[n : n + size]


_SIGNED = {"WORD": "INT", "DWORD": "DINT"}


def written_as(addr: Address, type_name: str, value: Any) -> str:
    """The type ``value`` is written at ``addr`` as (``write_operand``)."""
    if type_name not in _SIGNED or type_name != default_type(addr):
        return type_name
    if isinstance(value, float) and type_name == "DWORD":
        return "REAL"
    if isinstance(value, int) and not isinstance(value, bool) and value < 0:
        return _SIGNED[type_name]
    return type_name


def stimulus_value(type_name: str, name: str, value: Any) -> Any:
    """``value`` of a stimulus or a ``set`` as the ``type_name`` of variable or pin ``name``:
    a bit, a number or a time by the rules a modify follows (``engine.modify``: ``5``,
    ``"5"``, ``"T#5S"``, ``"TRUE"``; a whole-numbered float is an integer's value); a
    STRING as text that fits; a DATE or DATE_AND_TIME as ``D#…``/``DT#…`` or ISO text;
    S7Error naming ``name`` otherwise."""
    upper = type_name.upper()
    try:
        if upper.startswith("STRING") or upper == "CHAR":
            return check_value(type_name, value)
        if upper in ("DATE", "DATE_AND_TIME", "DT"):
            return check_value(type_name, _date_of(upper, value))
        size = 1 if upper == "BOOL" else type_of(type_name).size_bits
    except S7Error as exc:
        raise S7Error(f"{name}: {exc.message} (to set the {type_name} {name})") from None
    if size not in (1, 8, 16, 32):
        return check_value(type_name, value)
    if isinstance(value, float) and value.is_integer() and upper not in ("REAL", "LREAL"):
        value = int(value)
    try:
        return typed_value(type_name, name, value)[0]
    except ModifyError as exc:
        said = exc.message.replace(" (to modify the", " (to set the")
        raise S7Error(said if said.startswith(f"{name}: ") else f"{name}: {said}") from None


def _date_of(type_name: str, value: Any) -> Any:
    """A DATE or DATE_AND_TIME from its S7 literal or ISO text (anything else as given)."""
    if not isinstance(value, str):
        return value
    text = value.strip()
    try:
        return parse_literal(text)[1] if "#" in text else from_stored(type_name, text)
    except (S7Error, ValueError):
        raise S7Error(f"'{value}' is not a {type_name.lower().replace('_', ' ')}") from None
