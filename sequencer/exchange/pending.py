"""ST bodies that need the SCL block: run as SCL FCs, or kept, never dropped.

A GRAPH row is one instruction, so an action or transition body with statements (IF, CASE,
FOR, WHILE, REPEAT, EXIT, RETURN) has no row form. S7 runs such a body as an SCL FC called
from the step's row (``CALL FC n``), and so does the import: each such body is a
``PendingScl`` record (none of its statements is imported on its own, since the FC runs them
in their order), made an SCL FC numbered from FC 1 (``body_fc.PendingBodies``), called where
the record says and reported (I033); the chart's SCL source (``Imported.blocks_scl``) holds
them all.
A body the SCL compiler refuses stays pending:

* in ``Imported.pending``;
* in the chart, as a comment beginning ``(* PENDING SCL`` on the step that would call it
  (the chart's end comment for the POU body and for actions that run every call), so the
  `.s7g` file carries the body text;
* in the import's problems, as a located warning (I021) naming the SCL diagnostic.

Where the call goes: ``placement`` ``step`` (a row of step ``step`` with the event ``event``:
"" every call while active, ``S1`` on activation, ``S0`` on deactivation), ``before``
(PERMANENT BEFORE: the POU body beside the SFC, and a transition's body, which computes
the FB variable ``result`` its condition reads) or ``after`` (PERMANENT AFTER: an action an
initial step stores for good).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import PurePath
from typing import Literal

from s7graph.engine.errors import SourceLocation
from s7graph.sequencer.exchange.st import SAssign, SCallStmt, SName, SOther, SSetReset, SStmt

__all__ = ["MARK", "PendingScl", "comment", "first_other", "placement", "written_by"]

MARK = "PENDING SCL"


@dataclass(frozen=True, slots=True)
class PendingScl:
    """One ST body kept for the SCL block (see the module docstring)."""

    kind: Literal["action", "transition", "body"]
    name: str
    text: str
    loc: SourceLocation
    placement: Literal["step", "before", "after"]
    step: int | None = None
    event: str = ""
    writes: tuple[str, ...] = ()
    result: str = ""  # a transition's: the FB variable its condition reads
    why: str = ""  # the first statement a row cannot hold, e.g. "an IF statement at 7:2"


def comment(p: PendingScl) -> str:
    """The chart comment that carries ``p``: a block comment, its body text as written
    (``*)`` inside it broken so that the comment ends where it should)."""
    where = {
        "step": f"a row of S{p.step}" + (f" on {p.event}" if p.event else ""),
        "before": "PERMANENT BEFORE",
        "after": "PERMANENT AFTER",
    }[p.placement]
    file = PurePath(p.loc.file).name
    head = f"{MARK}: {p.kind} {p.name} ({file}:{p.loc.line}), called from {where}"
    if p.result:
        head += f", computing {p.result}"
    body = "\n".join(line.rstrip() for line in p.text.strip("\n").splitlines())
    body = body.replace("*)", "* )").replace("(*", "( *")
    return f"(* {head}:\n{body}\n*)"


def _why(first: SOther) -> str:
    article = "an" if first.keyword[:1] in "AEIOU" else "a"
    return f"{article} {first.keyword} statement"


def placement(p: PendingScl) -> str:
    """Where ``p``'s call goes, in words: ``S2 on S1``, ``PERMANENT BEFORE``."""
    if p.placement == "step":
        return f"S{p.step}" + (f" on {p.event}" if p.event else "")
    return "PERMANENT BEFORE" if p.placement == "before" else "PERMANENT AFTER"


def first_other(body: list[SStmt]) -> tuple[str, SOther] | None:
    """Why a body needs the SCL block, and its first statement a row cannot hold."""
    for st in body:
        if isinstance(st, SOther):
            return _why(st), st
    return None


def written_by(body: list[SStmt]) -> tuple[str, ...]:
    """The variables a body assigns (first names), in order."""
    out: list[str] = []
    for st in body:
        if isinstance(st, SOther):
            out += st.writes
        elif isinstance(st, SAssign | SSetReset):
            out.append(st.target.parts[0] if isinstance(st.target, SName) else st.target.text)
        elif isinstance(st, SCallStmt):
            out.append(st.name)
            out += [t.parts[0] if isinstance(t, SName) else t.text for _, t in st.outputs]
    return tuple(dict.fromkeys(out))
