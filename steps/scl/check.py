"""The check entry point: every diagnostic of an SCL source, without loading anything
(docs/scl.md, "Diagnostics").

``check_scl(text, file)`` parses, declares and compiles the source as ``compile_scl`` does
and returns what it found — errors and warnings with codes and ``file:line:col`` — an empty
list for a clean source. It never raises for a bad source. ``check_scl_source`` gives the
parsed source beside them, for a caller that reads it further (parsed once).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

from s7graph.engine.blocks import FB, FC
from s7graph.engine.symbols import SymbolTable
from s7graph.steps.scl import model as m
from s7graph.steps.scl.blocks import build_program
from s7graph.steps.scl.compile import translate
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
    return check_scl_source(text, file, blocks=blocks, names=names, symbols=symbols)[0]


def check_scl_source(
    text: str,
    file: str = "<input>",
    *,
    blocks: Iterable[FB | FC] = (),
    names: Mapping[str, str] | None = None,
    symbols: SymbolTable | None = None,
) -> tuple[list[Diagnostic], m.Source]:
    """:func:`check_scl`'s diagnostics and the source as parsed (no units when it does not
    parse), compiled as ``compile_scl`` compiles it."""
    source, prog, generated, diags = translate(
        text, file, blocks=list(blocks), names=names, symbols=symbols
    )
    if generated is None:
        return diags, source
    try:
        return build_program(source, prog, generated, diags).diagnostics, source
    except SclError as exc:
        return exc.diagnostics, source
