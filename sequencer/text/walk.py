"""Walk and rewrite the chart model as data: every node is a frozen dataclass or a tuple.

``rewrite`` rebuilds a tree bottom-up through a function of each node, sharing every
subtree the function leaves alone (an edit copies only the path to what it changes);
``nodes`` yields every node without recursion; ``unlocated`` forgets where things were
written, so two charts compare by content, and ``uncommented`` their comments. The
editor (``sequencer.change.edit``) renumbers and relocates with these; the change summary
(``sequencer.change.diff``) compares with them.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import fields, is_dataclass, replace
from typing import Any, TypeVar

from s7graph.engine.errors import SourceLocation
from s7graph.sequencer.text.model import NOWHERE, Chart, Step, SymbolDecl, Transition

N = TypeVar("N")


_FIELDS: dict[type, tuple[str, ...]] = {}


def _field_names(cls: type) -> tuple[str, ...]:
    names = _FIELDS.get(cls)
    if names is None:
        names = _FIELDS[cls] = tuple(f.name for f in fields(cls))
    return names


def _is_node(x: object) -> bool:
    return is_dataclass(x) and not isinstance(x, type)


def rewrite(node: N, fn: Callable[[Any], Any]) -> N:
    """``node`` with ``fn`` applied to each dataclass node, children first; a node whose
    children and ``fn`` change nothing is returned as it was (the same object)."""
    if isinstance(node, tuple):
        items = tuple(rewrite(x, fn) for x in node)
        same = all(a is b for a, b in zip(items, node, strict=True))
        return node if same else items  # type: ignore[return-value]
    if not _is_node(node):
        return node
    changes = {}
    for name in _field_names(type(node)):
        value = getattr(node, name)
        new = rewrite(value, fn)
        if new is not value:
            changes[name] = new
    rebuilt = replace(node, **changes) if changes else node  # type: ignore[type-var]
    return fn(rebuilt)  # type: ignore[no-any-return]


def nodes(root: object) -> Iterator[Any]:
    """Every dataclass node under ``root`` (``root`` included), depth first, iteratively."""
    todo = [root]
    while todo:
        x = todo.pop()
        if isinstance(x, tuple):
            todo.extend(reversed(x))
        elif _is_node(x):
            yield x
            todo.extend(reversed([getattr(x, n) for n in _field_names(type(x))]))


def _forget_place(node: Any) -> Any:
    if isinstance(node, SourceLocation):
        return NOWHERE
    if isinstance(node, Chart) and (node.option_locs or node.file != "<input>"):
        return replace(node, option_locs=(), file="<input>")
    if isinstance(node, Step) and (node.interlock_loc or node.supervision_loc):
        return replace(node, interlock_loc=None, supervision_loc=None)
    if isinstance(node, Transition) and (node.source_locs or node.target_locs):
        return replace(node, source_locs=(), target_locs=())
    return node


def unlocated(node: N) -> N:
    """``node`` with every place forgotten (locations, FROM/TO places, the file a chart was
    read from): its content only, so that two models of the same chart compare equal
    whatever text they were read from."""
    return rewrite(node, _forget_place)


_COMMENTED = ("comment", "trailing", "end_comment")


def _forget_comment(node: Any) -> Any:
    if isinstance(node, SymbolDecl) or not _is_node(node):
        return node  # a symbol's comment is part of its declaration
    names = [n for n in _COMMENTED if n in _field_names(type(node)) and getattr(node, n)]
    return replace(node, **dict.fromkeys(names, "")) if names else node


def uncommented(node: N) -> N:
    """``node`` without the comments kept with its elements (``sequencer.text.comments``): what
    it does, for a change summary that must not call a reworded comment a changed step."""
    return rewrite(node, _forget_comment)


def relocated(node: N, file: str, line_offset: int) -> N:
    """``node`` with every place moved into ``file``, ``line_offset`` lines up (the places
    of a text parsed inside a wrapper, given back in the text's own lines)."""

    def move(x: Any) -> Any:
        if isinstance(x, SourceLocation) and x.line > 0:
            return SourceLocation(file, max(x.line - line_offset, 1), x.col)
        return x

    return rewrite(node, move)


def depth(root: object) -> int:
    """How deeply nodes nest under ``root`` (an operand alone: 1; places not counted),
    iteratively: the bound the editor checks before anything recursive reads a tree."""
    deepest = 0
    todo: list[tuple[object, int]] = [(root, 0)]
    while todo:
        x, d = todo.pop()
        if isinstance(x, tuple):
            todo.extend((y, d) for y in x)
        elif _is_node(x) and not isinstance(x, SourceLocation):
            deepest = max(deepest, d + 1)
            todo.extend((getattr(x, n), d + 1) for n in _field_names(type(x)))
    return deepest
