"""Check a parsed chart and report every problem at once (docs/semantics.md, "Structure" and
"Actions" and "Conditions"; docs/chart-format.md).

``validate(chart, symbols)`` runs each rule of ``RULES`` (one small function per rule) and
returns all diagnostics sorted by place; errors stop compilation, warnings do not. Codes and
their meaning are listed in ``sequencer.checks.diagnostics.CODES``. The rules live by topic in
``sequencer.checks.structure`` (numbers, declarations, FROM/TO, initial steps, ways in and
out, limits, joins), ``sequencer.checks.rows`` (action rows, permanent instructions) and
``sequencer.checks.types`` (conditions, operands, typing); they share a
``sequencer.checks.context._Ctx``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Final

from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.checks.context import _Ctx
from s7graph.sequencer.checks.diagnostics import Diagnostic, sort_key
from s7graph.sequencer.checks.interfaces import ProgramBlocks
from s7graph.sequencer.checks.rows import (
    rule_action_rows,
    rule_c_without_interlock,
    rule_instance_db_addresses,
    rule_permanent_instructions,
)
from s7graph.sequencer.checks.structure import (
    MAX_ALTERNATIVE_PATHS,
    MAX_CONDITION_ELEMENTS,
    MAX_MARKINGS,
    MAX_SEQUENCES,
    MAX_SIMULTANEOUS_PATHS,
    MAX_STEPS,
    MAX_TRANSITIONS,
    rule_branches_in_one_sequence,
    rule_declarations,
    rule_duplicate_declarations,
    rule_duplicate_numbers,
    rule_initial_steps,
    rule_joins,
    rule_limits,
    rule_unknown_steps_in_from_to,
    rule_ways_in_and_out,
)
from s7graph.sequencer.checks.types import (
    COMPARABLE,
    COMPARISONS,
    FUNCTIONS,
    LOGIC,
    rule_conditions,
    rule_empty_conditions,
)
from s7graph.sequencer.checks.user_calls import check_own_blocks
from s7graph.sequencer.text.model import Chart

__all__ = [
    "COMPARABLE",
    "COMPARISONS",
    "FUNCTIONS",
    "LOGIC",
    "MAX_ALTERNATIVE_PATHS",
    "MAX_CONDITION_ELEMENTS",
    "MAX_MARKINGS",
    "MAX_SEQUENCES",
    "MAX_SIMULTANEOUS_PATHS",
    "MAX_STEPS",
    "MAX_TRANSITIONS",
    "RULES",
    "ProgramBlocks",
    "rule_action_rows",
    "rule_branches_in_one_sequence",
    "rule_c_without_interlock",
    "rule_conditions",
    "rule_declarations",
    "rule_duplicate_declarations",
    "rule_duplicate_numbers",
    "rule_empty_conditions",
    "rule_initial_steps",
    "rule_instance_db_addresses",
    "rule_joins",
    "rule_limits",
    "rule_permanent_instructions",
    "rule_unknown_steps_in_from_to",
    "rule_ways_in_and_out",
    "validate",
]

RULES: Final[tuple[Callable[[_Ctx], None], ...]] = (
    rule_duplicate_numbers,
    rule_duplicate_declarations,
    rule_declarations,
    rule_unknown_steps_in_from_to,
    rule_branches_in_one_sequence,
    rule_initial_steps,
    rule_ways_in_and_out,
    rule_limits,
    rule_empty_conditions,
    rule_c_without_interlock,
    rule_action_rows,
    rule_permanent_instructions,
    rule_conditions,
    rule_joins,
    rule_instance_db_addresses,
)


def validate(
    chart: Chart,
    symbols: SymbolTable | None = None,
    *,
    blocks: ProgramBlocks | None = None,
    readable: ProgramBlocks | None = None,
    held: ProgramBlocks | None = None,
) -> list[Diagnostic]:
    """Every diagnostic of ``chart`` (errors and warnings), sorted by place. ``blocks``: the
    program's FBs, FCs and DBs, when known, that the chart's calls are checked against
    (E047, ``sequencer.checks.user_calls``) and whose FBs' variables the chart reads by name
    (E048); ``readable``: those FBs only, the calls not checked (the compiler's); ``held``:
    the blocks a CPU holds, read as ``readable`` and its calls checked as a download into
    that CPU checks them (a block it lacks and an instance DB are the swap's to judge)."""
    ctx = _Ctx(chart, symbols, blocks=blocks, readable=readable or blocks or held, held=held)
    if chart.db_number is not None and chart.fb_number is not None:
        ctx.instances[chart.db_number] = f"FB{chart.fb_number} (this chart)"
    for s in chart.all_steps():
        ctx.steps.setdefault(s.number, s)
    for t in chart.all_transitions():
        ctx.transitions.setdefault(t.number, t)
    for rule in RULES:
        rule(ctx)
    check_own_blocks(ctx)
    unique = list(dict.fromkeys(ctx.diags))
    return sorted(unique, key=sort_key)
