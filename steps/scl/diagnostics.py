"""Diagnostics of an S7-SCL source: what is wrong and where (docs/scl.md, "Diagnostics").

Every diagnostic carries ``file:line:col`` and a code; ``format_diagnostic`` prints it the
way compilers do::

    mix.scl:14:5: error[E220]: cannot assign a REAL to the INT variable 'n'

Codes: ``E2xx`` errors (the source does not compile), ``W3xx`` warnings. They are listed in
``CODES`` so that tests and ``s7graph check`` can name them. ``Diagnostic`` itself is the
chart's too (``steps/diagnostics.py``); here errors sort before warnings.
"""

from __future__ import annotations

from typing import Final

from s7graph.engine.errors import S7Error, SourceLocation
from s7graph.steps.diagnostics import Diagnostic, error, format_diagnostic, warning
from s7graph.steps.diagnostics import errors_first as sort_key

__all__ = [
    "CODES",
    "Diagnostic",
    "Problem",
    "SclError",
    "error",
    "format_diagnostic",
    "sort_key",
    "warning",
]

CODES: Final[dict[str, str]] = {
    # the text (steps/scl/parse.py)
    "E201": "syntax error: unexpected token or character",
    "E202": "the source ends too early (a missing END_… or ';')",
    "E203": "literal that does not parse or does not fit its type",
    "E204": "statements or expressions nested too deeply, or a source too large to compile",
    "E205": "absolute operand that does not parse or is out of range",
    # declarations (steps/scl/declare.py)
    "E210": "name declared twice (variable, constant, label, block, parameter)",
    "E211": "unknown name: no variable, constant, symbol or block of that name",
    "E212": "unknown or misused data type",
    "E213": "unknown block, or a block of the wrong kind",
    "E214": "block without a number (give FB17 or map its symbol to one), or a number out of range",
    "E215": "declaration section not allowed in this kind of block",
    "E216": "initial value that is not a constant of the variable's type",
    "E217": "array bounds or string length that is not a constant in range",
    # labels and jumps (steps/scl/stmts.py)
    "E218": "GOTO to a label that is not declared or not placed",
    "E219": "label placed twice, or a GOTO into a loop or another statement list",
    # types (steps/scl/exprs.py)
    "E220": "value of a type that cannot be assigned or passed there",
    "E221": "operator not defined for its operand types",
    "E222": "condition that is not a BOOL",
    "E223": "write to a constant, an input of the caller or a read-only operand",
    "E224": "indices or members that do not fit the variable",
    "E225": "index out of the array's bounds",
    # calls (steps/scl/calls.py)
    "E230": "unknown parameter, or a parameter given twice",
    "E231": "missing parameter",
    "E232": "call that is not allowed there (outputs inside an expression, EN of a function)",
    "E233": "FB called without an instance, or an instance of another FB",
    # statements (steps/scl/stmts.py)
    "E240": "EXIT or CONTINUE outside a loop",
    "E241": "FOR variable that is not a simple INT or DINT variable",
    "E242": "CASE selector that is not an integer, or a value listed twice",
    "E243": "function value not set: the function's name is never assigned",
    # warnings
    "W301": "declared label never placed or never jumped to",
}


class SclError(S7Error):
    """A source that does not compile; ``diagnostics`` lists every problem found."""

    def __init__(self, diagnostics: list[Diagnostic]) -> None:
        self.diagnostics = diagnostics
        errors = [d for d in diagnostics if d.is_error] or diagnostics
        more = f" (and {len(errors) - 1} more)" if len(errors) > 1 else ""
        super().__init__(f"{format_diagnostic(errors[0])}{more}")


class Problem(Exception):
    """Raised inside the compiler at the first problem of a statement: becomes a
    diagnostic, and the compiler goes on with the next statement."""

    def __init__(self, code: str, message: str, loc: SourceLocation) -> None:
        super().__init__(message)
        self.code = code
        self.message = message
        self.loc = loc
