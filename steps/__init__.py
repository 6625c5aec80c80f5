"""Step content → generated Python: conditions (transitions, interlocks, supervisions),
expressions, operands and action rows with the qualifier table (SPEC §2.3, §2.8, §2.9).

Public names are loaded on first use, like ``sequencer``'s (no import cycle with it).
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from steps.actions import ActionError, gen_step_actions
    from steps.conditions import MAX_CONTACTS, contact_text, contacts, gen_condition
    from steps.expressions import expr_type, gen_value
    from steps.operands import CodeGen, Ref
    from steps.qualifiers import Rule, check, operand_kind, table_rows

_EXPORTS: dict[str, str] = {
    "ActionError": "steps.actions",
    "gen_step_actions": "steps.actions",
    "MAX_CONTACTS": "steps.conditions",
    "contact_text": "steps.conditions",
    "contacts": "steps.conditions",
    "gen_condition": "steps.conditions",
    "expr_type": "steps.expressions",
    "gen_value": "steps.expressions",
    "CodeGen": "steps.operands",
    "Ref": "steps.operands",
    "Rule": "steps.qualifiers",
    "check": "steps.qualifiers",
    "operand_kind": "steps.qualifiers",
    "table_rows": "steps.qualifiers",
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
