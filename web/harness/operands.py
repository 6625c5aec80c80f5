"""Operands by name for the sessions that run a program on the virtual clock (a chart's,
``web.harness.session``, and an S7-SCL program's, ``web.cli.scl``): an address or a
symbol, and how a stimulus writes one."""

from __future__ import annotations

from typing import Any

from s7graph.engine.address import Address, Area, parse_address
from s7graph.engine.errors import AddressError
from s7graph.engine.memory import Memory
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
