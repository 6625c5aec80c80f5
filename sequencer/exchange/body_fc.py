"""An ST body kept for the SCL block (``pending.PendingScl``) as an S7-SCL FUNCTION.

IEC structured text and S7-SCL are close (docs/scl.md): the statements, operators, typed
literals, ``(* *)`` and ``//`` comments and the IEC functions read the same. What differs
is translated: CODESYS ends ``END_IF`` (and the other ends) without ``;``, SCL needs it.

The FC's parameters are the chart variables the body names: one it only reads is a
VAR_INPUT of the same name; one it writes a VAR_OUTPUT of the same name with a VAR_INPUT
``<name>_IN`` that gives it its value before the body runs (the first statement), so a body
that reads it, or leaves it alone on some path, sees and keeps the chart's value — what an
IN_OUT parameter does for an FC called once a call, which a chart's CALL row binds only
with ``:=`` and ``=>``. A transition body's result (its name) is a VAR_OUTPUT that starts
FALSE. The call: ``CALL FC n (level := level, busy_IN := busy, busy => busy)``.

``make_fc`` returns the FC, or the first SCL error of the source when the compiler refuses
it (``Refusal``, placed in the body: the body then stays pending).
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import PurePath
from typing import Any, Protocol

from s7graph.engine.errors import SourceLocation
from s7graph.sequencer.exchange.pending import MARK, PendingScl, comment, placement
from s7graph.sequencer.exchange.problems import Problems
from s7graph.sequencer.exchange.st import blank_comments, shift
from s7graph.sequencer.text.model import BlockCall, Expr, Operand
from s7graph.steps.scl import check_scl

__all__ = ["BodyFc", "PendingBodies", "Refusal", "blocks_source", "make_fc", "to_scl"]

_TOKEN = re.compile(
    r"\(\*[\s\S]*?\*\)|//[^\n]*|'(?:[^'$\n]|\$.)*'|\"[^\"\n]*\""
    r"|[A-Za-z_][A-Za-z0-9_]*#[-+]?[A-Za-z0-9_:.#+-]*|\d[\d_]*#[0-9A-Za-z_]+"
    r"|\.\s*[A-Za-z_][A-Za-z0-9_]*|([A-Za-z_][A-Za-z0-9_]*)"
)
_ENDS = re.compile(r"\b(END_IF|END_CASE|END_FOR|END_WHILE|END_REPEAT)\b(?!\s*;)", re.IGNORECASE)


class _VarLike(Protocol):
    @property
    def graph(self) -> str: ...
    @property
    def type(self) -> str: ...
    @property
    def symbol(self) -> bool: ...


@dataclass(frozen=True, slots=True)
class BodyFc:
    """A pending body as SCL FC ``number``: its source and the chart's call of it."""

    item: PendingScl
    number: int
    source: str  # FUNCTION FCn : VOID … END_FUNCTION
    call: BlockCall


@dataclass(frozen=True, slots=True)
class Refusal:
    """The first SCL error of a body's FC; ``at``: its place in the body's text (line 1 its
    first line), None when it is in the FC's interface."""

    code: str
    message: str
    at: tuple[int, int] | None

    def __str__(self) -> str:
        return f"{self.code}: {self.message}"


def identifiers(text: str) -> dict[str, str]:
    """The names ``text`` uses, upper case → as first written: not in comments, strings or
    typed literals, not a member after a ``.``."""
    out: dict[str, str] = {}
    for m in _TOKEN.finditer(blank_comments(text)):
        if m.group(1):
            out.setdefault(m.group(1).upper(), m.group(1))
    return out


def to_scl(text: str) -> str:
    """An IEC ST body as S7-SCL statements: every ``END_IF`` … ``END_REPEAT`` ends with
    ``;`` (comments and strings untouched, but for those S7-SCL does not read: nested
    comments, ``/* */``, pragmas — blanks)."""
    text = blank_comments(text, keep_flat=True)
    out: list[str] = []
    pos = 0
    for m in re.finditer(r"\(\*[\s\S]*?\*\)|//[^\n]*|'(?:[^'$\n]|\$.)*'", text):
        out.append(_ENDS.sub(r"\1;", text[pos : m.start()]))
        out.append(m.group(0))
        pos = m.end()
    out.append(_ENDS.sub(r"\1;", text[pos:]))
    return "".join(out)


def _fresh(name: str, taken: set[str]) -> str:
    candidate = f"{name}_IN"
    k = 2
    while candidate.upper() in taken:
        candidate = f"{name}_IN{k}"
        k += 1
    taken.add(candidate.upper())
    return candidate


def make_fc(item: PendingScl, number: int, variables: Mapping[str, _VarLike]) -> BodyFc | Refusal:
    """``item`` as FC ``number`` over ``variables`` (upper-case IEC name → the chart's
    variable), or the SCL diagnostic that refuses it."""
    used = identifiers(item.text)
    taken = set(used)
    result = item.name.upper() if item.result else ""
    writes = {w.upper() for w in item.writes} - {result}
    inputs: list[tuple[str, Expr]] = []
    outputs: list[tuple[str, Operand]] = []
    decl_in: list[str] = []
    decl_out: list[str] = []
    prefix: list[str] = []
    for key, name in used.items():
        v = variables.get(key)
        if v is None or key == result:
            continue
        target = Operand(v.graph, v.symbol, item.loc)
        if key in writes:
            fresh = _fresh(name, taken)
            decl_in.append(f"    {fresh} : {v.type};")
            inputs.append((fresh, target))
            decl_out.append(f"    {name} : {v.type};")
            outputs.append((name, target))
            prefix.append(f"{name} := {fresh};")
        else:
            decl_in.append(f"    {name} : {v.type};")
            inputs.append((name, target))
    if result:
        decl_out.append(f"    {item.name} : BOOL;")
        outputs.append((item.name, Operand(item.result, False, item.loc)))
        prefix.append(f"{item.name} := FALSE;")
    head = [
        f"FUNCTION FC{number} : VOID",
        f"(* {item.kind} {item.name} ({PurePath(item.loc.file).name}:{item.loc.line}), "
        "imported by s7graph *)",
    ]
    for section, decls in (("VAR_INPUT", decl_in), ("VAR_OUTPUT", decl_out)):
        if decls:
            head += [section, *decls, "END_VAR"]
    head += ["BEGIN", *prefix]
    start = len(head) + 1  # the body's first line in the source
    source = "\n".join(head) + "\n" + to_scl(item.text) + "\nEND_FUNCTION\n"
    problems = [d for d in check_scl(source, f"FC{number}.scl") if d.is_error]
    if problems:
        d = problems[0]
        line = d.loc.line - start + 1
        inside = 1 <= line <= item.text.count("\n") + 1
        return Refusal(d.code, d.message, (line, d.loc.col) if inside else None)
    call = BlockCall("FC", number, None, tuple(inputs), tuple(outputs), item.loc)
    return BodyFc(item, number, source, call)


def blocks_source(functions: list[BodyFc], chart: str) -> str:
    """The SCL source of ``functions``: what ``s7graph import -o`` writes beside the chart."""
    if not functions:
        return ""
    head = f"// The ST bodies of {chart} a GRAPH row cannot hold: SCL FCs the chart calls.\n"
    return head + "\n".join(f.source for f in functions)


class PendingBodies:
    """The bodies an import keeps for the SCL block: each one the SCL compiler accepts
    becomes an FC the chart calls (``functions``); the others stay pending, with the
    comments that carry them."""

    def __init__(self, problems: Problems, variables: Mapping[str, Any] | None = None) -> None:
        self.p = problems
        self.variables: Mapping[str, Any] = variables if variables is not None else {}
        self.items: list[PendingScl] = []
        self.functions: list[BodyFc] = []
        self.by_body: dict[tuple[str, str, str], BodyFc] = {}
        self.next_fc = 1
        self.step_comments: dict[int, list[str]] = {}
        self.end_comments: list[str] = []

    def keep(
        self, item: PendingScl, first: SourceLocation, origin: tuple[int, int]
    ) -> BlockCall | None:
        """The call of ``item``'s FC (reported, located at ``first``, the first statement a
        row cannot hold), or None: the SCL compiler refuses it, and it is recorded with its
        comment and its warning, located at the SCL error (``origin``: where the body's
        text starts in the file)."""
        key = (item.kind, item.name.upper(), item.text)
        made: BodyFc | Refusal | None = self.by_body.get(key)
        if made is None:
            made = make_fc(item, self.next_fc, self.variables)
            if isinstance(made, BodyFc):
                self.by_body[key] = made
                self.functions.append(made)
                self.next_fc += 1
        if isinstance(made, BodyFc):
            self.p.warn(
                "I033",
                f"{item.kind} {item.name}: {item.why}, which a GRAPH row cannot hold; the "
                f"body is SCL FC {made.number} (the chart's SCL source), called from "
                f"{placement(item)}: load that source with the chart",
                first,
            )
            return made.call
        assert isinstance(made, Refusal)
        if made.at is not None:
            first = SourceLocation(first.file, *shift(*made.at, origin))
        self.items.append(item)
        text = comment(item)
        if item.placement == "step" and item.step is not None:
            self.step_comments.setdefault(item.step, []).append(text)
        else:
            self.end_comments.append(text)
        where = {
            "step": f"step S{item.step}'s comment",
            "before": "the chart's end comment",
            "after": "the chart's end comment",
        }[item.placement]
        waits = f"; {item.result} stays FALSE" if item.result else ""
        self.p.warn(
            "I021",
            f"{item.kind} {item.name}: {item.why}, which a GRAPH row cannot hold, and the "
            f"SCL compiler refuses it as an FC ({made}); the whole body is kept in {where} "
            f"({MARK}), to be called from {placement(item)}: none of it runs{waits}",
            first,
        )
        return None

    def writes(self) -> dict[str, str]:
        """Variable (upper case) → the pending body that writes it."""
        out: dict[str, str] = {}
        for item in self.items:
            for name in (*item.writes, item.result):
                if name:
                    out.setdefault(name.upper(), f"{item.kind} {item.name}")
        return out
