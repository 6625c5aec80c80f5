"""S7-GRAPH sequencers: parse, validate and compile ``.s7g`` charts, run them as engine FBs
(SPEC §2–§3).

The public names below are loaded on first use (``sequencer.X`` imports its module then), so
importing the package stays cheap and free of import cycles with ``steps``.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from sequencer.compile import ChartError, compile_chart
    from sequencer.compiled import CompiledChart, Program
    from sequencer.cycle import GraphRuntime, new_state
    from sequencer.diagnostics import Diagnostic
    from sequencer.display import compute_outputs, criteria_by_name
    from sequencer.fb import GraphFB, StepEvent, install_all, startup_obs
    from sequencer.messages import sync_messages
    from sequencer.model import Chart, ChartOptions
    from sequencer.names import resolve_operand
    from sequencer.params import PARAMETER_SETS, Pin, pins_for
    from sequencer.parse import parse_chart, parse_file
    from sequencer.state import GraphState
    from sequencer.validate import validate

_EXPORTS: dict[str, str] = {
    "ChartError": "sequencer.compile",
    "compile_chart": "sequencer.compile",
    "CompiledChart": "sequencer.compiled",
    "Program": "sequencer.compiled",
    "GraphRuntime": "sequencer.cycle",
    "new_state": "sequencer.cycle",
    "Diagnostic": "sequencer.diagnostics",
    "compute_outputs": "sequencer.display",
    "criteria_by_name": "sequencer.display",
    "GraphFB": "sequencer.fb",
    "StepEvent": "sequencer.fb",
    "install_all": "sequencer.fb",
    "startup_obs": "sequencer.fb",
    "sync_messages": "sequencer.messages",
    "Chart": "sequencer.model",
    "ChartOptions": "sequencer.model",
    "resolve_operand": "sequencer.names",
    "PARAMETER_SETS": "sequencer.params",
    "Pin": "sequencer.params",
    "pins_for": "sequencer.params",
    "parse_chart": "sequencer.parse",
    "parse_file": "sequencer.parse",
    "GraphState": "sequencer.state",
    "validate": "sequencer.validate",
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
