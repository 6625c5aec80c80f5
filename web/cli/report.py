"""How the command line reports an error: one line (or a chart's diagnostics) on stderr."""

from __future__ import annotations

import sys
from pathlib import Path

from s7graph.web.harness.scl import SclLoadError
from s7graph.web.harness.session import ChartLoadError

__all__ = ["fail", "not_a_chart"]


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


IMPORTED = {".xml": "a chart in PLCopen XML or SimaticML", ".st": "a chart in IEC text"}
"""The files ``s7graph import`` turns into charts, by suffix: no other command reads them."""


def not_a_chart(path: Path, takes: str) -> str:
    """Why a command that ``takes`` charts (``check takes a chart (.s7g) or an S7-SCL source
    (.scl)``) does not read ``path``, by its suffix: a Python program of blocks, or a chart
    ``s7graph import`` reads; "" for another file (read as a chart, whatever its name)."""
    suffix = path.suffix.lower()
    if suffix == ".py":
        return f"{path}: a Python program of blocks; {takes} (s7graph run runs a program)"
    if suffix in IMPORTED:
        return (
            f"{path}: {IMPORTED[suffix]}? {takes}: import it first "
            f"(s7graph import {path} -o {path.with_suffix('.s7g').name})"
        )
    return ""
