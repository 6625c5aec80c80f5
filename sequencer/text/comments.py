"""The comments of a `.s7g` text, kept with the element they annotate, where they stood.

A chart's comments are part of its documentation: a chart read, edited in the browser and
written again (``sequencer.text.format``) keeps them, each in its place. ``attach_comments(chart,
text)`` finds every ``// …`` and ``(* … *)`` comment of ``text`` (not inside a quoted name
or a string literal) and gives each to one element, in this order of rules:

- a comment on the line an element starts on, after it, is that element's *trailing*
  comment (``pieces : INT := 0;  // work pieces``); with several elements on the line, the
  last one that starts before the comment;
- any other comment belongs to the next element that starts after it (the comment lines
  above a step, a transition, a row, a variable, a sequence, or ``FUNCTION_BLOCK``);
- a comment after the last element is the chart's ``end_comment``.

Elements: the block (``Chart.comment``: what stands above ``FUNCTION_BLOCK``), variables,
sequences, steps, action rows and transitions. Each keeps the comments above it in
``comment`` and those at the end of its first line in ``trailing``, verbatim, delimiters
included, one after the other separated by a newline. ``format_chart`` writes the first on
lines of their own above the element and the second at the end of its first line, so both
read back to the same element and the same place. A symbol's trailing ``//`` comment stays
its own (``SymbolDecl.comment``); comments among the symbols and the permanent instructions
go to the next element.
"""

from __future__ import annotations

import bisect
import re
from dataclasses import dataclass, replace
from typing import Any, TypeVar

from s7graph.sequencer.text.model import Chart, Sequence, Step

__all__ = ["Comment", "attach_comments", "find_comments"]

N = TypeVar("N")

_TOKENS = re.compile(r'"(?:[^"]|"")*"?|\'(?:[^\'$]|\$.)*\'?|//[^\n]*|\(\*.*?(?:\*\)|\Z)', re.S)


@dataclass(frozen=True, slots=True)
class Comment:
    """One comment: where it starts (1-based line and column) and its text as written."""

    line: int
    col: int
    text: str


def find_comments(text: str) -> list[Comment]:
    """The comments of ``text`` in order (quoted names and string literals skipped)."""
    out: list[Comment] = []
    starts = [0] + [m.end() for m in re.finditer("\n", text)]
    for m in _TOKENS.finditer(text):
        token = m.group()
        if token.startswith(("//", "(*")):
            line = bisect.bisect_right(starts, m.start())
            out.append(Comment(line, m.start() - starts[line - 1] + 1, token.rstrip()))
    return out


def attach_comments(chart: Chart, text: str) -> Chart:
    """``chart`` (parsed from ``text``) with each comment of ``text`` given to its element."""
    comments = find_comments(text)
    if not comments:
        return chart
    symbol_lines = {s.loc.line for s in chart.symbols if s.comment}
    places: list[tuple[int, int, tuple[Any, ...]]] = [(chart.loc.line, chart.loc.col, ("chart",))]
    places += [(v.loc.line, v.loc.col, ("var", k)) for k, v in enumerate(chart.vars)]
    for q, seq in enumerate(chart.sequences):
        places.append((seq.loc.line, seq.loc.col, ("seq", q)))
        for s, step in enumerate(seq.steps):
            places.append((step.loc.line, step.loc.col, ("step", q, s)))
            for k, r in enumerate(step.actions):
                places.append((r.loc.line, r.loc.col, ("row", q, s, k)))
        for k, t in enumerate(seq.transitions):
            places.append((t.loc.line, t.loc.col, ("trans", q, k)))
    places = sorted(p for p in places if p[0] > 0)
    keys = [(line, col) for line, col, _ in places]
    given: dict[tuple[Any, ...], list[str]] = {}
    for c in comments:
        if c.line in symbol_lines and c.text.startswith("//"):
            continue  # the symbol's own comment
        at = bisect.bisect_left(keys, (c.line, c.col))
        if at > 0 and places[at - 1][0] == c.line:
            owner = ("trailing", *places[at - 1][2])  # the last element begun on its line
        elif at < len(places):
            owner = places[at][2]  # leading: the next element
        else:
            owner = ("end",)
        given.setdefault(owner, []).append(c.text)
    return _with_comments(chart, {k: "\n".join(v) for k, v in given.items()})


def _with_comments(chart: Chart, given: dict[tuple[Any, ...], str]) -> Chart:
    def commented(node: N, *key: Any) -> N:
        above, trailing = given.get(key), given.get(("trailing", *key))
        if above:
            node = replace(node, comment=above)  # type: ignore[type-var]
        return replace(node, trailing=trailing) if trailing else node  # type: ignore[type-var]

    sequences: list[Sequence] = []
    for q, seq in enumerate(chart.sequences):
        steps: list[Step] = []
        for s, step in enumerate(seq.steps):
            rows = tuple(commented(r, "row", q, s, k) for k, r in enumerate(step.actions))
            steps.append(commented(replace(step, actions=rows), "step", q, s))
        transitions = tuple(commented(t, "trans", q, k) for k, t in enumerate(seq.transitions))
        sequences.append(
            commented(replace(seq, steps=tuple(steps), transitions=transitions), "seq", q)
        )
    return replace(
        commented(chart, "chart"),
        end_comment=given.get(("end",), ""),
        vars=tuple(commented(v, "var", k) for k, v in enumerate(chart.vars)),
        sequences=tuple(sequences),
    )
