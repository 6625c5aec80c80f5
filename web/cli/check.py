"""``s7graph check CHART.s7g [--symbols FILE]``: print a chart's diagnostics (SPEC.md §3).

One diagnostic a line on stdout (``file:line:col: error[E010]: message (element)``), then a
summary line. Exit status: 0 clean, 1 warnings only, 2 errors (syntax errors included). An
unreadable chart or symbol file is one line on stderr and exit 2.
"""

from __future__ import annotations

import sys
from pathlib import Path

from s7graph.engine.errors import S7Error
from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.diagnostics import Diagnostic, format_diagnostic
from s7graph.sequencer.parse import ChartSyntaxError, parse_chart
from s7graph.sequencer.validate import validate


def check_command(chart: Path, symbols: Path | None = None) -> int:
    """Parse and validate ``chart``; print diagnostics and a summary; return the exit code."""
    try:
        text = chart.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        print(f"s7graph: error: cannot read {chart}: {exc}", file=sys.stderr)
        return 2
    table: SymbolTable | None = None
    if symbols is not None:
        try:
            table = SymbolTable.from_file(symbols)
        except (OSError, UnicodeDecodeError, S7Error) as exc:
            print(f"s7graph: error: cannot read symbols {symbols}: {exc}", file=sys.stderr)
            return 2
    diags: list[Diagnostic]
    try:
        diags = validate(parse_chart(text, str(chart)), table)
    except ChartSyntaxError as exc:
        diags = exc.diagnostics
    for d in diags:
        print(format_diagnostic(d))
    errors = sum(d.severity == "error" for d in diags)
    warnings = len(diags) - errors
    print(f"{chart}: {_plural(errors, 'error')}, {_plural(warnings, 'warning')}")
    return 2 if errors else 1 if warnings else 0


def _plural(n: int, word: str) -> str:
    return f"{n} {word}" if n == 1 else f"{n} {word}s"
