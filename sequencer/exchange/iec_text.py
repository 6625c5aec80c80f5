"""Read IEC 61131-3 textual SFC (``INITIAL_STEP … END_STEP``, ``TRANSITION FROM … TO …``,
``ACTION … END_ACTION``) as matiec and ironplc read it, into ``IecChart`` s.

A file holds POUs (``FUNCTION_BLOCK``, ``PROGRAM``) and configurations; every POU with SFC
elements is a chart. Configurations are skipped (and reported: they bind a program's
variables to locations, which a GRAPH FB does not have). Statements of a POU body outside
the SFC elements are kept as its ``prelude``. Divergences and convergences are implicit:
several transitions from one step form an alternative, ``TO (a, b)`` a simultaneous
divergence, ``FROM (a, b)`` a simultaneous join (IEC 61131-3 §6.7.3).
"""

from __future__ import annotations

import re
from typing import Any

from lark import Token, Tree

from s7graph.engine.errors import SourceLocation
from s7graph.sequencer.exchange.iec_model import (
    IecAction,
    IecAssociation,
    IecChart,
    IecStep,
    IecTransition,
    IecVar,
    Unsupported,
)
from s7graph.sequencer.exchange.problems import Problems
from s7graph.sequencer.exchange.st import (
    SLiteral,
    SName,
    StSyntaxError,
    blank_comments,
    build,
    parse_tree,
)

__all__ = ["read_iec_text"]

_KINDS = {
    "VAR_INPUT": "input",
    "VAR_OUTPUT": "output",
    "VAR_IN_OUT": "inout",
    "VAR_EXTERNAL": "external",
    "VAR_GLOBAL": "global",
    "VAR_TEMP": "temp",
    "VAR": "local",
}
_POU_KINDS = {"FUNCTION_BLOCK": "functionBlock", "PROGRAM": "program", "FUNCTION": "function"}


def _loc(file: str, tok: Any) -> SourceLocation:
    if isinstance(tok, Token):
        return SourceLocation(file, tok.line or 0, tok.column or 0)
    return SourceLocation(file, getattr(tok, "line", 0), getattr(tok, "col", 0))


def read_iec_text(text: str, file: str, problems: Problems) -> list[IecChart]:
    """Every POU of ``text`` that holds SFC elements. When the text as a whole does not
    parse, each POU is read on its own (``_pieces``): one this grammar cannot read (an IL
    function, a TYPE block) is reported and left out, so that the charts beside it import;
    a piece with SFC elements that does not parse is an error, as before. Comments (nested
    too) and pragmas are blanks (``st.blank_comments``)."""
    text = blank_comments(text)
    try:
        trees = [build(parse_tree(text, "file", file, (1, 1), "the IEC text"))]
    except StSyntaxError as exc:
        pieces = _pieces(text)
        if len(pieces) < 2:
            where = exc.where if isinstance(exc.where, SourceLocation) else problems.at(1, 1)
            problems.error("I001", exc.message, where)
            return []
        trees = [t for t in (_piece(text, a, b, file, problems) for a, b in pieces) if t]
    charts: list[IecChart] = []
    for item in (i for tree in trees for i in tree.children):
        if isinstance(item, Tree) and item.data == "configuration":
            problems.warn(
                "I024",
                "CONFIGURATION not imported: it binds program variables to "
                "tasks and locations; a GRAPH FB is called from OB1",
                _loc(file, item.children[0]),
            )
            continue
        chart = _pou(item, file, text)
        if chart.steps:
            charts.append(chart)
        else:
            problems.warn("I024", f"{chart.name} has no SFC elements; not imported", chart.loc)
    return charts


_PIECE = re.compile(
    r"^[ \t]*(FUNCTION_BLOCK|PROGRAM|FUNCTION|CONFIGURATION|TYPE)(?![A-Za-z0-9_])",
    re.IGNORECASE | re.MULTILINE,
)
_SFC = re.compile(r"(?<![A-Za-z0-9_])INITIAL_STEP(?![A-Za-z0-9_])", re.IGNORECASE)


def _pieces(text: str) -> list[tuple[int, int]]:
    """Where each POU, configuration or TYPE block of ``text`` starts and ends (from one
    such keyword at the start of a line to the next); none when no line starts with one
    (``INITIAL_STEP`` without a ``PROGRAM`` header: the parser's error stands)."""
    starts = [m.start() for m in _PIECE.finditer(text)]
    if not starts:
        return []
    return list(zip(starts, [*starts[1:], len(text)], strict=True))


def _piece(text: str, start: int, end: int, file: str, problems: Problems) -> Any:
    """The parse tree of ``text[start:end]``, read in place (the rest blanked, so lines and
    columns stay the file's); None, reported, when it does not parse."""
    blank = re.sub(r"[^\n]", " ", text[:start])
    piece = text[start:end]
    try:
        return build(parse_tree(blank + piece, "file", file, (1, 1), "the IEC text"))
    except StSyntaxError as exc:
        where = exc.where if isinstance(exc.where, SourceLocation) else problems.at(1, 1)
        head = piece.split(None, 2)
        name = " ".join(head[:2]) if head else "a block"
        if _SFC.search(piece):
            problems.error("I001", exc.message, where)
        else:
            line = text.count("\n", 0, start) + 1
            problems.warn(
                "I024",
                f"{name} does not parse as ST or textual SFC at line {where.line} (IL, or a "
                "construct the import does not read): not imported; the charts beside it are",
                problems.at(line, 1),
            )
        return None


def _pou(tree: Tree[Any], file: str, text: str) -> IecChart:
    head = tree.children[0]
    kind_tok, name_tok = head.children[0], head.children[1]
    chart = IecChart(
        str(name_tok), _POU_KINDS[str(kind_tok).upper()], _loc(file, kind_tok), dialect="iec"
    )
    order = 0
    spans: list[str] = []
    for i, ch in enumerate(tree.children[1:], 1):
        if isinstance(ch, Tree):
            rule = ch.data
            if rule == "var_block":
                chart.vars += _var_block(ch, file)
            elif rule == "step":
                chart.steps.append(_step(ch, file))
            elif rule == "transition":
                chart.transitions.append(_transition(ch, file, order))
                order += 1
            elif rule == "action":
                act = _action(ch, file, text)
                chart.actions[act.name.upper()] = act
        elif ch is not None and not isinstance(ch, Token):
            chart.prelude.append(ch)  # a statement of the POU body
            nxt = next((c for c in tree.children[i + 1 :] if c is not None), None)
            spans.append(text[_offset(text, ch) : _offset(text, nxt) if nxt else len(text)])
    chart.prelude_text = "".join(spans)
    return chart


def _offset(text: str, node: Any) -> int:
    """Where ``node`` (a tree, a token or a statement) starts in ``text``."""
    if isinstance(node, Token) and node.start_pos is not None:
        return node.start_pos
    if isinstance(node, Tree):
        if not node.meta.empty:
            return int(node.meta.start_pos)
        return _offset(text, node.children[0]) if node.children else len(text)
    line, col = getattr(node, "line", 0), getattr(node, "col", 0)
    if not line:
        return len(text)
    start = 0
    for _ in range(line - 1):
        start = text.index("\n", start) + 1
    return start + col - 1


def _var_block(tree: Tree[Any], file: str) -> list[IecVar]:
    kind = _KINDS[str(tree.children[0]).upper()]
    qual = str(tree.children[1]).upper() if tree.children[1] is not None else ""
    out: list[IecVar] = []
    for decl in tree.children[2:]:
        names = [c for c in decl.children if isinstance(c, Token) and c.type == "NAME"]
        address = next(
            (str(c) for c in decl.children if isinstance(c, Token) and c.type == "DIRECT"), ""
        )
        type_spec = next(c for c in decl.children if isinstance(c, Tree) and c.data == "type_spec")
        init = decl.children[-1] if not isinstance(decl.children[-1], Tree | Token) else None
        type_name = _type(type_spec)
        for n in names:
            out.append(
                IecVar(
                    str(n),
                    type_name,
                    kind,
                    _loc(file, n),
                    address.upper(),
                    init,
                    constant=qual == "CONSTANT",
                )
            )
    return out


def _type(spec: Tree[Any]) -> str:
    first = spec.children[0]
    if isinstance(first, Token) and first.type == "ARRAY_KW":
        return "ARRAY"
    base = str(first).upper()
    size = spec.children[1] if len(spec.children) > 1 else None
    if isinstance(size, SLiteral):
        return f"{base}[{size.text}]"
    return base


def _step(tree: Tree[Any], file: str) -> IecStep:
    kw, name = tree.children[0], tree.children[1]
    step = IecStep(str(name), str(kw).upper() == "INITIAL_STEP", _loc(file, kw))
    for assoc in tree.children[2:]:
        if isinstance(assoc, Tree) and assoc.data == "association":
            step.associations.append(_association(assoc, file))
    return step


_TIMED = frozenset({"L", "D", "SD", "DS", "SL"})


def _association(tree: Tree[Any], file: str) -> IecAssociation:
    """``name(qualifier[, action time][, indicator …])``: after a timed qualifier (L D SD
    DS SL) comes the action time, a TIME literal or a variable (IEC 61131-3 §6.7.4.3);
    the other names are indicator variables."""
    name = tree.children[0]
    args: list[Any] = [a for a in tree.children[1:] if a is not None]
    qualifier, duration, indicator = "N", "", ""
    rest = args
    if args and isinstance(args[0], SName) and len(args[0].parts) == 1:
        qualifier = args[0].parts[0].upper()
        rest = args[1:]
    if qualifier in _TIMED and rest and isinstance(rest[0], SLiteral | SName):
        duration, rest = rest[0].text, rest[1:]
    for a in rest:
        if isinstance(a, SLiteral) and "#" in a.text and not duration:
            duration = a.text
        elif isinstance(a, SName):
            indicator = a.text
    return IecAssociation(str(name), qualifier, _loc(file, name), duration, indicator)


def _names(tree: Tree[Any]) -> list[str]:
    return [str(t) for t in tree.children if isinstance(t, Token)]


def _transition(tree: Tree[Any], file: str, order: int) -> IecTransition:
    ch = tree.children
    kw, name, prio = ch[0], ch[1], ch[2]
    sets = [c for c in ch if isinstance(c, Tree) and c.data == "step_names"]
    cond_tree = next(c for c in ch if isinstance(c, Tree) and c.data.endswith("_condition"))
    condition: Any
    if cond_tree.data == "il_condition":
        condition = Unsupported("an IL transition condition", _loc(file, cond_tree.children[0]))
    else:
        condition = cond_tree.children[0]
    priority = int(str(prio.children[1])) if isinstance(prio, Tree) else None
    return IecTransition(
        _names(sets[0]),
        _names(sets[1]),
        condition,
        _loc(file, kw),
        name=str(name) if name is not None else "",
        priority=priority,
        order=order,
    )


def _action(tree: Tree[Any], file: str, text: str) -> IecAction:
    """``ACTION name: … END_ACTION``: its statements (placed in the file) and its text."""
    kw, name, end = tree.children[0], tree.children[1], tree.children[-1]
    body: list[Any] = [s for s in tree.children[2:] if s is not None and not isinstance(s, Token)]
    assert isinstance(name, Token) and name.end_pos is not None
    start = text.index(":", name.end_pos) + 1
    stop = end.start_pos if isinstance(end, Token) and end.start_pos is not None else start
    return IecAction(str(name), body, _loc(file, kw), text=text[start:stop])
