"""What a place in a chart's source text belongs to — ``step S3``, ``transition T2``,
``permanent before`` — read from the text itself, for the syntax errors the parser gives
before there is a model to ask (docs/chart-format.md: every diagnostic names the step or
transition it concerns)."""

from __future__ import annotations

import re
from typing import Final

# Comments and quoted texts, blanked before the text is read (a ';' or a keyword in them
# is not one).
_QUIET: Final = re.compile(r"\(\*.*?\*\)|//[^\n]*|\"[^\"\n]*\"|'[^'\n]*'", re.DOTALL)
_MARKS: Final = re.compile(
    r"(?<![\w#])(?:"
    r"(?:INITIAL_STEP|STEP)\s+S\s*(?P<step>\d+)"
    r"|(?P<end_step>END_STEP)"
    r"|TRANSITION\s+T\s*(?P<trans>\d+)"
    r"|PERMANENT\s+(?P<perm>BEFORE|AFTER)"
    r"|(?P<end_perm>END_PERMANENT)"
    r")(?![\w])|(?P<semi>;)",
    re.IGNORECASE,
)


def enclosing_element(text: str, line: int, col: int) -> str:
    """The step, transition or permanent instruction the place (``line``, ``col``, from
    1) lies in, as diagnostics name them; ``""`` outside every one."""
    lines = text.split("\n")
    offset = sum(len(x) + 1 for x in lines[: max(line - 1, 0)]) + max(col - 1, 0)
    head = _QUIET.sub(lambda m: " " * len(m.group(0)), text[:offset])
    step = trans = perm = ""
    for m in _MARKS.finditer(head):
        if m.group("step"):
            step, trans = f"step S{int(m.group('step'))}", ""
        elif m.group("end_step"):
            step = ""
        elif m.group("trans"):
            trans = f"transition T{int(m.group('trans'))}"
        elif m.group("perm"):
            perm = f"permanent {m.group('perm').lower()}"
        elif m.group("end_perm"):
            perm = ""
        else:  # ';' ends a transition
            trans = ""
    return trans or step or perm
