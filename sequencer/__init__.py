"""S7-GRAPH sequencers: parse, validate and compile ``.s7g`` charts, run them as engine FBs
(SPEC §2–§3).

The public names below are loaded on first use (``sequencer.X`` imports its module then), so
importing the package stays cheap and free of import cycles with ``steps``.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
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

_EXPORTS: dict[str, str] = {
    "ChartError": "s7graph.sequencer.compile",
    "compile_chart": "s7graph.sequencer.compile",
    "CompiledChart": "s7graph.sequencer.compiled",
    "Program": "s7graph.sequencer.compiled",
    "GraphRuntime": "s7graph.sequencer.cycle",
    "new_state": "s7graph.sequencer.cycle",
    "Diagnostic": "s7graph.sequencer.diagnostics",
    "compute_outputs": "s7graph.sequencer.display",
    "criteria_by_name": "s7graph.sequencer.display",
    "GraphFB": "s7graph.sequencer.fb",
    "StepEvent": "s7graph.sequencer.fb",
    "install_all": "s7graph.sequencer.fb",
    "startup_obs": "s7graph.sequencer.fb",
    "sync_messages": "s7graph.sequencer.messages",
    "Chart": "s7graph.sequencer.model",
    "ChartOptions": "s7graph.sequencer.model",
    "resolve_operand": "s7graph.sequencer.names",
    "PARAMETER_SETS": "s7graph.sequencer.params",
    "Pin": "s7graph.sequencer.params",
    "pins_for": "s7graph.sequencer.params",
    "parse_chart": "s7graph.sequencer.parse",
    "parse_file": "s7graph.sequencer.parse",
    "GraphState": "s7graph.sequencer.state",
    "validate": "s7graph.sequencer.validate",
}

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


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'sequencer' has no attribute {name!r}")
    return getattr(importlib.import_module(module), name)
