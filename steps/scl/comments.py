"""Comments of an S7-SCL source (docs/scl.md, "Blocks and declarations").

A block comment ``(* … *)`` may hold further block comments, as S7-SCL V5 allows with its
nesting option (Siemens' S7-SCL V5.3 for S7-300/400, "Comments"); here nesting is always
accepted. A line comment ``//`` runs to the end of its line; inside a block comment it is
plain comment text, and a ``(*`` inside a line comment or a string opens nothing.
``blank_comments`` turns every comment into spaces (line breaks kept), so that places in
the text stay where they were.
"""

from __future__ import annotations

import re

from s7graph.engine.errors import SourceLocation
from s7graph.steps.scl.diagnostics import Diagnostic, error

_TOKEN = re.compile(r"'(?:[^'$\n]|\$.)*'|\"(?:[^\"\n]|\"\")*\"|//[^\n]*|\(\*")
_INSIDE = re.compile(r"\(\*|\*\)")


def blank_comments(text: str, file: str) -> tuple[str, Diagnostic | None]:
    """``text`` with its comments blanked, and E202 for a block comment never closed
    (named by the line and column where it opens)."""
    out: list[str] = []
    pos = 0
    while (found := _TOKEN.search(text, pos)) is not None:
        if found[0] == "(*":
            end = _close(text, found.end())
            if end < 0:
                return text, _unclosed(text, file, found.start())
            out.append(text[pos : found.start()])
            out.append(_blank(text[found.start() : end]))
            pos = end
        elif found[0].startswith("//"):
            out.append(text[pos : found.start()])
            out.append(" " * len(found[0]))
            pos = found.end()
        else:
            out.append(text[pos : found.end()])
            pos = found.end()
    out.append(text[pos:])
    return "".join(out), None


def _close(text: str, pos: int) -> int:
    """The end of the block comment whose body starts at ``pos``, or -1."""
    depth = 1
    while (found := _INSIDE.search(text, pos)) is not None:
        depth += 1 if found[0] == "(*" else -1
        pos = found.end()
        if depth == 0:
            return pos
    return -1


def _blank(comment: str) -> str:
    return re.sub(r"[^\n]", " ", comment)


def _unclosed(text: str, file: str, pos: int) -> Diagnostic:
    line = text.count("\n", 0, pos) + 1
    col = pos - (text.rfind("\n", 0, pos) + 1) + 1
    return error(
        "E202",
        f"the comment opened at line {line} is never closed (missing '*)')",
        SourceLocation(file, line, col),
    )
