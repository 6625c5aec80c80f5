"""What an import or an export reports: one table of codes, and the exception that carries
the list.

An import yields a chart or, when no chart can be built, ``ImportFailed`` with every problem
found, each located in the source file (``file:line:col``). Constructs that have no exact
GRAPH equivalent are left out of the chart and reported as warnings (``I02x``): nothing is
dropped without a line saying what and where. An export reports (``X01x``) what of the chart
the format's other readers do not see, or run otherwise.
"""

from __future__ import annotations

from typing import Final

from s7graph.engine.errors import S7Error, SourceLocation
from s7graph.sequencer.checks.diagnostics import Diagnostic, error, format_diagnostic, warning

__all__ = ["CODES", "ImportFailed", "Problems"]

CODES: Final[dict[str, str]] = {
    # the file as a whole (no chart)
    "I001": "not well-formed XML, or text that is not a chart of a known format",
    "I002": "a DTD or entity declaration (refused: no entity expansion)",
    "I003": "merge-conflict markers in the file",
    "I004": "no sequential chart in the file",
    "I005": "more than one chart in the file and none chosen",
    # structure (no chart)
    "I010": "a reference to a step, transition or element that does not exist",
    "I011": "a transition without preceding or following step",
    "I012": "a condition or expression that does not parse",
    "I013": "a chart shape GRAPH cannot hold",
    "I014": "an address the import must allocate does not fit the CPU's memory",
    # not imported (the chart is built without it)
    "I020": "an IEC action qualifier without an exact GRAPH equivalent",
    "I021": "an ST statement or action body without an exact GRAPH equivalent",
    "I022": "a network element or block without an exact GRAPH equivalent",
    "I023": "a variable, type or address without an exact GRAPH equivalent",
    "I024": "a part of the file the chart does not use (configuration, other POUs ...)",
    "I025": "a step the chart can never leave: what its transitions wait for, nothing writes",
    # mapped, with a difference worth knowing
    "I030": "a name changed to be a valid GRAPH name",
    "I031": "an IEC and a GRAPH rule differ here; the GRAPH rule applies",
    "I032": "an address the export does not give; one was allocated",
    "I033": "an ST body a GRAPH row cannot hold, run as an SCL FC the chart calls",
    # export: what the format's other readers do not see or run otherwise
    "X010": "a chart part other tools do not see (kept in s7graph's own data only)",
    "X011": "a chart part other tools run otherwise",
    "X012": "a chart part written in s7graph's spelling, which other tools may not read",
    "X013": "a name changed so that the other tool takes it (TIA: unique element names)",
}


class Problems:
    """The problems found while importing one file, in the order found."""

    def __init__(self, file: str) -> None:
        self.file = file
        self.items: list[Diagnostic] = []

    def at(self, line: int, col: int) -> SourceLocation:
        return SourceLocation(self.file, line, col)

    def error(self, code: str, message: str, loc: SourceLocation, element: str = "") -> None:
        assert code in CODES, code
        d = error(code, message, loc, element)
        if d not in self.items:
            self.items.append(d)

    def warn(self, code: str, message: str, loc: SourceLocation, element: str = "") -> None:
        assert code in CODES, code
        d = warning(code, message, loc, element)
        if d not in self.items:  # an action shared by steps is reported once
            self.items.append(d)

    @property
    def errors(self) -> list[Diagnostic]:
        return [d for d in self.items if d.is_error]

    def fail_if_errors(self) -> None:
        if self.errors:
            raise ImportFailed(self.items)


class ImportFailed(S7Error):
    """No chart could be built; ``diagnostics`` lists every problem, located; ``charts``
    the charts of a file that holds several when none was chosen (a ``pou`` for each)."""

    def __init__(self, diagnostics: list[Diagnostic], charts: tuple[str, ...] = ()) -> None:
        self.diagnostics = diagnostics
        self.charts = charts
        first = next((d for d in diagnostics if d.is_error), diagnostics[0])
        more = f" (and {len(diagnostics) - 1} more)" if len(diagnostics) > 1 else ""
        super().__init__(f"{format_diagnostic(first)}{more}")
