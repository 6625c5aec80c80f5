"""The operating modes and the one switching-rule table (docs/semantics.md, "One FB call", step 4.2
and "Modes"; docs/semantics.md, "Modes").

``MODE_RULES[mode](condition, push)`` says whether a valid transition whose condition is
``condition`` may switch when ``push`` is a rising edge of T_PUSH in this call:
AUTO: condition; TAP: condition AND push; TOP: condition OR push; MAN: never.
Modes are chosen by a rising edge of SW_AUTO / SW_TAP / SW_TOP / SW_MAN; when several rise
in one call the last of ``SELECTORS`` wins (MAN, the safest).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Final

MODE_RULES: Final[dict[str, Callable[[bool, bool], bool]]] = {
    "AUTO": lambda condition, push: condition,
    "TAP": lambda condition, push: condition and push,
    "TOP": lambda condition, push: condition or push,
    "MAN": lambda condition, push: False,
}

# (input pin, mode) in increasing precedence
SELECTORS: Final = (("SW_AUTO", "AUTO"), ("SW_TAP", "TAP"), ("SW_TOP", "TOP"), ("SW_MAN", "MAN"))

# output pin of each mode


def select_mode(mode: str, rose: set[str]) -> str:
    """The mode after this call's rising edges of the SW_* inputs (docs/semantics.md, "Modes")."""
    for pin, new in SELECTORS:
        if pin in rose:
            mode = new
    return mode
