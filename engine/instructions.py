"""Operating-system instructions a language calls by name at run time: the S5 timer and
counter functions (docs/runtime.md, "The block runtime").

The engine keeps the table, ``sfb`` fills it when imported — as it registers the S5 timer
tick with ``engine.cpu.add_os_scan_hook`` — and a language above the engine calls an
instruction by name, as a CALL finds a system block in the CPU's block table, without
importing ``sfb`` (``steps/scl/runtime.py``: ``S_ODT``, ``S_CUD`` and the rest).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from s7graph.engine.errors import BlockError

__all__ = ["add_instruction", "instruction"]

_INSTRUCTIONS: dict[str, Callable[..., Any]] = {}


def add_instruction(name: str, function: Callable[..., Any]) -> None:
    """Register the operating system's instruction ``name`` (idempotent; the last wins)."""
    _INSTRUCTIONS[name] = function


def instruction(name: str) -> Callable[..., Any]:
    """The instruction ``name``; a BlockError if no system module registered it."""
    found = _INSTRUCTIONS.get(name)
    if found is None:
        raise BlockError(f"the CPU has no {name} instruction (the system blocks are not loaded)")
    return found
