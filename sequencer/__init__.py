"""S7-GRAPH sequencers: parse, validate and compile ``.s7g`` charts, run them as engine FBs
(docs/semantics.md).

The package exports the names a program of blocks or a tool needs; each lives in the module
named after what it holds.
"""

from __future__ import annotations

from s7graph.sequencer.compile import ChartError, compile_chart
from s7graph.sequencer.compiled import CompiledChart, Program
from s7graph.sequencer.cycle import GraphRuntime, new_state
from s7graph.sequencer.diagnostics import Diagnostic
from s7graph.sequencer.display import compute_outputs, criteria_by_name
from s7graph.sequencer.fb import GraphFB, StepEvent, install_all, startup_obs
from s7graph.sequencer.messages import sync_messages
from s7graph.sequencer.model import Chart, ChartOptions
from s7graph.sequencer.names import resolve_operand
from s7graph.sequencer.params import PARAMETER_SETS, Pin, pins_for
from s7graph.sequencer.parse import parse_chart, parse_file
from s7graph.sequencer.state import GraphState
from s7graph.sequencer.validate import validate

__all__ = [
    "PARAMETER_SETS",
    "Chart",
    "ChartError",
    "ChartOptions",
    "CompiledChart",
    "Diagnostic",
    "GraphFB",
    "GraphRuntime",
    "GraphState",
    "Pin",
    "Program",
    "StepEvent",
    "compile_chart",
    "compute_outputs",
    "criteria_by_name",
    "install_all",
    "new_state",
    "parse_chart",
    "parse_file",
    "pins_for",
    "resolve_operand",
    "startup_obs",
    "sync_messages",
    "validate",
]
