"""Whether a PLCopen file s7graph exported is still the file it exported.

The export keeps the chart's `.s7g` source in the POU's ``addData``, beside the SFC other
IEC tools read and edit. Another tool may change the SFC (rename a step, change a
condition) and keep that data: read from the data, the chart would silently undo the edit.
So the data is trusted only when it is recognised: the POU (its interface and SFC body)
and the configuration's global variables are what s7graph's export of the kept chart
writes, element for element, attributes and ST text alike (blanks collapsed; layout —
``position``, ``relPosition``, ``height``, ``width`` — and ``documentation`` and
``addData`` left aside: moving a box changes nothing a chart says). Otherwise the chart is
read from the SFC, and the import says where the file first differs (I024).
"""

from __future__ import annotations

from s7graph.engine.errors import S7Error, SourceLocation
from s7graph.sequencer.exchange.export_plcopen import export_plcopen
from s7graph.sequencer.exchange.plcopen import TRANSITION_IDS, Kept
from s7graph.sequencer.exchange.problems import ImportFailed
from s7graph.sequencer.exchange.xmltree import Node, is_true, parse_xml
from s7graph.sequencer.text.model import Chart

__all__ = ["edited_at"]

_LAYOUT_TAGS = frozenset({"position", "relPosition", "addData", "documentation"})
_LAYOUT_ATTRS = frozenset({"height", "width"})
_BOOLEANS = frozenset({"true", "false", "1", "0"})
_Found = tuple[Node, str]


def edited_at(kept: Kept, chart: Chart, file: str) -> tuple[SourceLocation, str] | None:
    """None when the POU ``kept`` is what s7graph's export of ``chart`` (its kept source,
    parsed) writes; else where the file first differs and the warning's text."""
    try:
        xml, reported = export_plcopen(chart)
        ours = parse_xml(xml.encode("utf-8"), "<export>")
    except (ValueError, S7Error, ImportFailed) as exc:  # not what the export wrote
        at = SourceLocation(file, kept.line, 1)
        return at, _message(f"s7graph's data, which no export writes ({exc})", 0)
    found = _differ(kept.pou, next(ours.iter("pou"))) or _differ_globals(kept.root, ours)
    if found is None:
        return None
    node, what = found
    left = sum(1 for d in reported if d.code in ("X010", "X011"))
    return node.loc(file), _message(f"{_element(node)}: {what}", left)


def _message(where: str, left: int) -> str:
    """I024's text: where the file first differs, and what is not imported for it."""
    parts = f" — {left} part(s) the export reported —" if left else ""
    return (
        f"the SFC was edited after s7graph exported it (first at {where}): the chart is read "
        "from the SFC, not from s7graph's data; what only that data holds (transition "
        f"names, interlocks, supervisions, block options, rows without an IEC form){parts} "
        "is not imported"
    )


def _differ(mine: Node, ours: Node) -> _Found | None:
    """The first element of ``mine`` (the file) that is not as in ``ours`` (the export),
    depth first, and what differs."""
    if mine.tag != ours.tag:
        return mine, f"<{mine.tag}> where the export wrote <{ours.tag}>"
    a, b = _attrs(mine), _attrs(ours)
    for key in sorted(a.keys() | b.keys()):
        if not _same(a.get(key), b.get(key)):
            return mine, f"{key}={_shown(a.get(key))} where the export wrote {_shown(b.get(key))}"
    if _words(mine.text) != _words(ours.text):
        mine_text, our_text = _shown(_words(mine.text)), _shown(_words(ours.text))
        return mine, f"{mine_text} where the export wrote {our_text}"
    kids = [c for c in mine.children if c.tag not in _LAYOUT_TAGS]
    our_kids = [c for c in ours.children if c.tag not in _LAYOUT_TAGS]
    if (found := _differ_pairs(kids, our_kids)) is not None:
        return found
    if len(kids) > len(our_kids):
        return kids[len(our_kids)], f"a <{kids[len(our_kids)].tag}> the export did not write"
    if len(kids) < len(our_kids):
        return mine, f"no <{our_kids[len(kids)].tag}> where the export wrote one"
    return None


def _differ_pairs(mine: list[Node], ours: list[Node]) -> _Found | None:
    """The first difference within the elements the file and the export both have."""
    return next(filter(None, map(_differ, mine, ours)), None)


def _differ_globals(root: Node, ours: Node) -> _Found | None:
    """The first global variable of the file's configurations not as the export wrote it."""
    mine = _globals(root)
    theirs = _globals(ours)
    if (found := _differ_pairs(mine, theirs)) is not None:
        return found
    if len(mine) > len(theirs):
        return mine[len(theirs)], "a global variable the export did not write"
    if len(mine) < len(theirs):
        where = next(root.iter("configuration"), root)
        return where, f"no global {theirs[len(mine)].get('name')} where the export wrote one"
    return None


def _globals(root: Node) -> list[Node]:
    return [
        v
        for conf in root.iter("configuration")
        for section in conf.all("globalVars")
        for v in section.all("variable")
    ]


def _attrs(node: Node) -> dict[str, str]:
    return {k: v for k, v in node.attrib.items() if k not in _LAYOUT_ATTRS}


def _same(a: str | None, b: str | None) -> bool:
    """Equal values; an ``xsd:boolean`` in either spelling (``1``, ``true``) alike."""
    if a is not None and b is not None and {a.strip(), b.strip()} <= _BOOLEANS:
        return is_true(a) == is_true(b)
    return a == b


def _words(text: str) -> str:
    return " ".join(text.split())


def _shown(value: str | None) -> str:
    if value is None:
        return "nothing"
    return repr(value if len(value) <= 60 else value[:57] + "...")


def _element(node: Node) -> str:
    """The chart element ``node`` belongs to: ``step Fill (S2)``, ``T3``, ``variable x`` …"""
    n: Node | None = node
    while n is not None and n.tag not in ("pou", "variable") and n.get("localId") in ("", "0"):
        n = n.parent
    if n is None or n.tag == "pou":
        return f"<{node.tag}>"
    ident = n.get("localId")
    if n.tag == "actionBlock":
        owner = next(n.iter("connection"), None)
        ref = owner.get("refLocalId") if owner is not None else ""
        return f"the actions of S{ref}" if ref.isdigit() else "an action block"
    if n.tag == "step":
        return f"step {n.get('name')} (S{ident})" if ident.isdigit() else f"step {n.get('name')}"
    if n.tag == "transition" and ident.isdigit() and int(ident) > TRANSITION_IDS:
        return f"transition T{int(ident) - TRANSITION_IDS}"
    if n.tag == "variable":
        return f"variable {n.get('name')}"
    return f"<{n.tag}> {ident}"
