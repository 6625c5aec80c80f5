"""Step content → generated Python: conditions (transitions, interlocks, supervisions),
expressions, operands and action rows with the qualifier table (docs/semantics.md).

The syntax tree of this language is ``steps.syntax``; the chart model holds it.
"""

from __future__ import annotations

from s7graph.steps.actions import ActionError, gen_step_actions
from s7graph.steps.conditions import MAX_CONTACTS, contact_text, contacts, gen_condition
from s7graph.steps.expressions import expr_type, gen_value
from s7graph.steps.operands import CodeGen, Ref
from s7graph.steps.qualifiers import Rule, check, operand_kind, table_rows

__all__ = [
    "MAX_CONTACTS",
    "ActionError",
    "CodeGen",
    "Ref",
    "Rule",
    "check",
    "contact_text",
    "contacts",
    "expr_type",
    "gen_condition",
    "gen_step_actions",
    "gen_value",
    "operand_kind",
    "table_rows",
]
