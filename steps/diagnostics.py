"""Diagnostics of a source, a chart or an S7-SCL source: what is wrong, where, and what it
concerns.

Every diagnostic carries ``file:line:col``, a code and a severity; ``format_diagnostic``
prints it the way compilers do::

    drill.s7g:14:5: error[E020]: S0 NC: the interlock mark C is allowed only ... (step S2 row 3)
    mix.scl:14:5: error[E220]: cannot assign a REAL to the INT variable 'n' (FB17)

The codes of each language are listed beside it (``sequencer/checks/diagnostics.py``,
``steps/scl/diagnostics.py``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from s7graph.engine.errors import SourceLocation

Severity = Literal["error", "warning"]


@dataclass(frozen=True, slots=True)
class Diagnostic:
    """One problem of a source. ``element`` names what it concerns: a chart's ``step S3``,
    ``transition T2``, ``step S2 row 3``, ``sequence 1``, ``permanent before``; an S7-SCL
    block ``FB17``; or ``""``."""

    severity: Severity
    code: str
    message: str
    loc: SourceLocation
    element: str = ""

    @property
    def is_error(self) -> bool:
        return self.severity == "error"


def error(code: str, message: str, loc: SourceLocation, element: str = "") -> Diagnostic:
    return Diagnostic("error", code, message, loc, element)


def warning(code: str, message: str, loc: SourceLocation, element: str = "") -> Diagnostic:
    return Diagnostic("warning", code, message, loc, element)


def format_diagnostic(d: Diagnostic) -> str:
    """``file:line:col: error[E012]: message (step S3)``; no parentheses without an element."""
    tail = f" ({d.element})" if d.element else ""
    return f"{d.loc}: {d.severity}[{d.code}]: {d.message}{tail}"


def sort_key(d: Diagnostic) -> tuple[str, int, int, str]:
    """Source order: file, line, column, then code."""
    return (d.loc.file, d.loc.line, d.loc.col, d.code)


def errors_first(d: Diagnostic) -> tuple[bool, str, int, int, str]:
    """Errors before warnings, each in source order."""
    return (not d.is_error, *sort_key(d))
