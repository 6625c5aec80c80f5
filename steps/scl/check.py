"""The check entry point: every diagnostic of an SCL source, without loading anything
(docs/scl.md, "Diagnostics").

``check_scl(text, file)`` parses, declares and compiles the source as ``compile_scl`` does
and returns what it found — errors and warnings with codes and ``file:line:col`` — an empty
list for a clean source. It never raises for a bad source.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

from s7graph.engine.blocks import FB, FC
from s7graph.engine.symbols import SymbolTable
from s7graph.steps.scl.blocks import compile_scl
from s7graph.steps.scl.diagnostics import Diagnostic, SclError


def check_scl(
    text: str,
    file: str = "<input>",
    *,
    blocks: Iterable[FB | FC] = (),
    names: Mapping[str, str] | None = None,
    symbols: SymbolTable | None = None,
) -> list[Diagnostic]:
    """All diagnostics of ``text`` (errors first in source order, then warnings)."""
    try:
        program = compile_scl(text, file, blocks=blocks, names=names, symbols=symbols)
    except SclError as exc:
        return exc.diagnostics
    return program.diagnostics
