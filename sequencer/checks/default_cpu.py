"""Operands beyond a default CPU's memory (W140; docs/cli.md, "s7graph check").

``s7graph check`` knows no CPU: an absolute address (or a symbol's) that is valid S7 but lies
beyond the memory areas of a CPU as s7graph makes one by default (``engine.memory.Memory``
with its default sizes: I and Q 128 bytes, M 256, 256 timers and counters, …) passed the
check; a download refuses the chart, and a run stops the CPU at the operand's first use (an
area length error naming it). ``default_cpu_warnings`` warns of each such operand at its
first use, naming the element it is used in, the address and the size of the default area.
``scl_default_cpu_warnings`` does the same for the absolute operands (and symbols) of an
S7-SCL source, found by its cross-references (``steps.scl.xref``), naming the block.
Not part of ``validate``: a download is checked against its CPU's own memory
(``sequencer.change.online.refusal``). DB addresses are not judged: the program makes its
DBs.
"""

from __future__ import annotations

import functools
import re
from collections.abc import Iterator

from s7graph.engine.address import Address, Area, parse_address
from s7graph.engine.errors import S7Error
from s7graph.engine.memory import Memory
from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.checks.context import _row_el
from s7graph.sequencer.checks.diagnostics import Diagnostic, warning
from s7graph.sequencer.text.model import Chart, Operand
from s7graph.sequencer.text.names import Resolved, resolve_operand
from s7graph.sequencer.text.walk import nodes
from s7graph.steps.operands import TYPE_BYTES
from s7graph.steps.scl.model import Source
from s7graph.steps.scl.xref import scl_uses

__all__ = [
    "beyond_default",
    "beyond_message",
    "default_areas",
    "default_cpu_warnings",
    "scl_default_cpu_warnings",
]

_CELLS = {Area.T: "timers", Area.C: "counters"}


@functools.cache
def default_areas() -> dict[Area, int]:
    """The size of each memory area of a default CPU: bytes (I, Q, M, L, PI, PQ), cells (T,
    C) — read from ``Memory()`` itself, so that the check follows the engine's defaults."""
    mem = Memory()
    areas = [a for a in Area if a not in _CELLS and a is not Area.DB]
    sizes: dict[Area, int] = {area: len(mem.area_bytes(area)) for area in areas}
    return sizes | {Area.T: len(mem.timers), Area.C: len(mem.counters)}


def _elements(chart: Chart) -> Iterator[tuple[str, object]]:
    """Each element of ``chart`` that holds operands, with its name as diagnostics give it."""
    for t in chart.all_transitions():
        yield f"transition T{t.number}", t.condition
    for s in chart.all_steps():
        yield f"step S{s.number} interlock", s.interlock
        yield f"step S{s.number} supervision", s.supervision
        for i, row in enumerate(s.actions):
            yield _row_el(s, i), row
    for place, items in (("before", chart.before), ("after", chart.after)):
        yield f"permanent {place}", items


def _beyond(res: Resolved) -> str | None:
    """The default area ``res`` lies beyond, with its size (``the M area of a default CPU (256
    bytes, MB0 to MB255)``), or None: it fits, or it is not judged."""
    return beyond_default(res.address, res.type if res.kind == "symbol" else None)


def beyond_default(addr: Address | None, declared: str | None = None) -> str | None:
    """``_beyond`` of an address (a symbol's: ``declared``, its type, whose width counts)."""
    if addr is None or addr.area is Area.DB:
        return None
    area, size = addr.area, default_areas()[addr.area]
    if area in _CELLS:
        if addr.byte < size:
            return None
        return f"the {_CELLS[area]} of a default CPU ({size}, {area}0 to {area}{size - 1})"
    end = addr.byte + max(addr.size, TYPE_BYTES.get(declared, 1) if declared else 1)
    if end <= size:
        return None
    return f"the {area} area of a default CPU ({size} bytes, {area}B0 to {area}B{size - 1})"


def beyond_message(name: str, why: str, *, chart: bool = True) -> str:
    """W140's message of the operand ``name`` beyond ``why`` (``beyond_default``); a
    ``chart``'s download refuses it too."""
    refused = "a download refuses the chart, " if chart else ""
    stops = "a run stops the CPU at its first use (unless the CPU has more)"
    return f"{name} is beyond {why}: {refused}{stops}"


def block_element(block: str) -> str:
    """The element a block's diagnostic names, as the S7-SCL compiler's do: a numbered
    block without a space (``OB 1`` → ``OB1``), a block by name as written (``FC "Scale"``)."""
    return re.sub(r"^([A-Z]+) (\d+)$", r"\1\2", block)


def scl_default_cpu_warnings(
    source: Source, symbols: SymbolTable | None = None
) -> list[Diagnostic]:
    """W140 for each absolute operand (a symbol's too) the code blocks of an S7-SCL
    ``source`` use beyond a default CPU's memory, at its first use (``steps.scl.xref``):
    the block, the address and the default area's size."""
    found: list[Diagnostic] = []
    seen: set[str] = set()
    for use in scl_uses(source):
        key = use.operand.casefold()
        if key in seen:
            continue
        seen.add(key)
        name, addr, declared = use.operand, None, None
        try:
            if use.operand.startswith('"') and use.operand.endswith('"'):
                symbol = symbols.lookup(use.operand[1:-1]) if symbols is not None else None
                if symbol is None:
                    continue
                addr, declared = symbol.address, symbol.type
                name = f"{use.operand} ({addr})"
            else:
                addr = parse_address(use.operand)
        except S7Error:
            continue  # a name, a DB variable, a block: not an operand area
        why = beyond_default(addr, declared)
        if why is not None:
            message = beyond_message(name, why, chart=False)
            found.append(warning("W140", message, use.loc, block_element(use.block)))
    return found


def default_cpu_warnings(chart: Chart, symbols: SymbolTable | None = None) -> list[Diagnostic]:
    """W140 for each operand of ``chart`` beyond a default CPU's memory, at its first use:
    the element, the address (a symbol's too) and the default area's size."""
    found: list[Diagnostic] = []
    seen: set[tuple[str, bool]] = set()
    for element, holder in _elements(chart):
        for op in nodes(holder):
            if not isinstance(op, Operand) or (op.name, op.quoted) in seen:
                continue
            seen.add((op.name, op.quoted))
            try:
                res = resolve_operand(op, chart, symbols)
            except S7Error:
                continue  # an error of its own (E040-E042)
            why = _beyond(res)
            if why is not None:
                name = f'"{op.name}" ({res.address})' if op.quoted else str(res.address)
                found.append(warning("W140", beyond_message(name, why), op.loc, element))
    return found
