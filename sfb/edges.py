"""Edge detection FP / FN and the R_TRIG / F_TRIG one-shots (docs/runtime.md, "The block runtime";
El-Shahat's S7-300/400 course, timers and counters).

The previous RLO lives in an edge-memory bit (M, DB bit or FB STAT — never TEMP). Rule:
``FP: edge := RLO AND NOT mem; mem := RLO`` and ``FN: edge := NOT RLO AND mem; mem := RLO``.
The result is TRUE for exactly one call per edge and instance.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

from s7graph.engine.address import Address
from s7graph.engine.memory import Memory


class Edge(NamedTuple):
    """Result of an edge instruction: the new RLO and the value to store in the memory bit."""

    rlo: bool
    mem: bool


def fp(rlo: bool, mem: bool) -> Edge:
    """FP: rising edge of the RLO against edge memory ``mem``."""
    return Edge(bool(rlo) and not mem, bool(rlo))


def fn(rlo: bool, mem: bool) -> Edge:
    """FN: falling edge of the RLO against edge memory ``mem``."""
    return Edge(not rlo and bool(mem), bool(rlo))


def fp_at(mem: Memory, mem_bit: Address, rlo: bool) -> bool:
    """``FP <mem_bit>`` with the edge memory in CPU memory (e.g. ``M10.0``)."""
    edge = fp(rlo, bool(mem.read(mem_bit)))
    mem.write(mem_bit, edge.mem)
    return edge.rlo


def fn_at(mem: Memory, mem_bit: Address, rlo: bool) -> bool:
    """``FN <mem_bit>`` with the edge memory in CPU memory."""
    edge = fn(rlo, bool(mem.read(mem_bit)))
    mem.write(mem_bit, edge.mem)
    return edge.rlo


@dataclass(slots=True)
class R_TRIG:
    """Rising-edge one-shot with its own STAT edge memory ``M``: Q = CLK AND NOT M."""

    M: bool = False
    Q: bool = False

    def __call__(self, CLK: bool) -> bool:
        self.Q, self.M = fp(CLK, self.M)
        return self.Q


@dataclass(slots=True)
class F_TRIG:
    """Falling-edge one-shot with its own STAT edge memory ``M``: Q = NOT CLK AND M."""

    M: bool = False
    Q: bool = False

    def __call__(self, CLK: bool) -> bool:
        self.Q, self.M = fn(CLK, self.M)
        return self.Q
