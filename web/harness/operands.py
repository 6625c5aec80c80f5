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
    the CPU reads it into the process image at the start of the next cycle."""
    mem.write_as(addr, type_name, value)
    if addr.area is Area.I:
        n = addr.byte
        size = max(1, int(addr.width) // 8)
        mem.periph_in[n : n + size] = mem.inputs[n : n + size]
