"""How the command line reports an error: one line (or a chart's diagnostics) on stderr."""

from __future__ import annotations

import sys

from s7graph.web.harness.scl import SclLoadError
from s7graph.web.harness.session import ChartLoadError

__all__ = ["fail"]


def fail(error: object, status: int = 2) -> int:
    """Report ``error`` on stderr and return the exit ``status``: a ``ChartLoadError`` or an
    ``SclLoadError`` as its diagnostics, one a line, anything else as one ``s7graph:
    error:`` line."""
    if isinstance(error, ChartLoadError | SclLoadError):
        lines = error.lines
    else:
        lines = [f"s7graph: error: {error}"]
    for line in lines:
        print(line, file=sys.stderr)
    return status
