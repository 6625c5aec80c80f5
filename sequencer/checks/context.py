"""The state the validation rules share: the chart, its symbols, the steps and transitions by
number and the diagnostics found so far (docs/chart-format.md)."""

from __future__ import annotations

from dataclasses import dataclass, field

from s7graph.engine.errors import SourceLocation
from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.checks.diagnostics import Diagnostic, error, warning
from s7graph.sequencer.checks.interfaces import ProgramBlocks
from s7graph.sequencer.text.model import Chart, Step, Transition


@dataclass
class _Ctx:
    chart: Chart
    symbols: SymbolTable | None
    steps: dict[int, Step] = field(default_factory=dict)
    transitions: dict[int, Transition] = field(default_factory=dict)
    diags: list[Diagnostic] = field(default_factory=list)
    blocks: ProgramBlocks | None = None
    """The program's FBs, FCs and DBs the chart's calls reach (``--blocks``), if given."""
    readable: ProgramBlocks | None = None
    """The program's FBs whose instance DBs' variables the chart reads by name (``blocks``
    unless told: the compiler reads them without checking the calls again)."""
    held: ProgramBlocks | None = None
    """The CPU's user blocks the chart's calls are checked against as a download into it
    checks them: as ``blocks``, but a call of a block the CPU lacks and an instance DB are
    the swap's to judge (``sequencer.calls.plan_calls``)."""
    instances: dict[int, str] = field(default_factory=dict)
    """The instance DBs the chart's calls name so far: number → the FB or SFB's label."""

    def err(self, code: str, msg: str, loc: SourceLocation, element: str = "") -> None:
        self.diags.append(error(code, msg, loc, element))

    def warn(self, code: str, msg: str, loc: SourceLocation, element: str = "") -> None:
        self.diags.append(warning(code, msg, loc, element))


def _step_el(n: int) -> str:
    return f"step S{n}"


def _row_el(step: Step, i: int) -> str:
    return f"step S{step.number} row {i + 1}"
