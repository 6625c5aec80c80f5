"""Step content → generated Python: conditions (transitions, interlocks, supervisions),
expressions, operands and action rows with the qualifier table (SPEC §2.3, §2.8, §2.9).

Public names are loaded on first use, like ``sequencer``'s (no import cycle with it).
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from s7graph.steps.actions import ActionError, gen_step_actions
    from s7graph.steps.conditions import MAX_CONTACTS, contact_text, contacts, gen_condition
    from s7graph.steps.expressions import expr_type, gen_value
    from s7graph.steps.operands import CodeGen, Ref
    from s7graph.steps.qualifiers import Rule, check, operand_kind, table_rows

_EXPORTS: dict[str, str] = {
    "ActionError": "s7graph.steps.actions",
    "gen_step_actions": "s7graph.steps.actions",
    "MAX_CONTACTS": "s7graph.steps.conditions",
    "contact_text": "s7graph.steps.conditions",
    "contacts": "s7graph.steps.conditions",
    "gen_condition": "s7graph.steps.conditions",
    "expr_type": "s7graph.steps.expressions",
    "gen_value": "s7graph.steps.expressions",
    "CodeGen": "s7graph.steps.operands",
    "Ref": "s7graph.steps.operands",
    "Rule": "s7graph.steps.qualifiers",
    "check": "s7graph.steps.qualifiers",
    "operand_kind": "s7graph.steps.qualifiers",
    "table_rows": "s7graph.steps.qualifiers",
}

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


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'steps' has no attribute {name!r}")
    return getattr(importlib.import_module(module), name)
