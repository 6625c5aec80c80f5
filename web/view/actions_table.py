"""A step's action table beside its box, as S7-GRAPH draws it: one row per action with the
columns event, qualifier and action (the operand with its time or value), and a last
column where the status view shows the operand's live value while the step is active;
under the table the step's interlock (``C``) and supervision (``V``) conditions.

:class:`Columns` are the column widths of one chart (every table of a chart alike, as in
S7-GRAPH); :func:`step_block` lays out one step's block at the right of its box: its
texts, lines, live-value cells and where each contact of its conditions stands
(``web.view.criteria``). Scene units, y up; computed once per chart.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field

from s7graph.web.bus.protocol import StepInfo
from s7graph.web.view.criteria import ConditionKey, Rect, span_rects
from s7graph.web.view.glyphs import LINE, Text, line_starts, text_width, wrap

__all__ = ["ACTION_SIZE", "Block", "Cell", "Columns", "block_width", "columns_of", "step_block"]

ACTION_SIZE = 0.15  # text height in a table and its conditions
PAD = 0.05  # left of a cell's text
ROW_PAD = 0.06  # above and below a row's text
VALUE_W = 0.85  # the live value's column
OPERAND_MIN, OPERAND_MAX = 1.0, 2.4  # the action column: as wide as its longest text
CONDITION_MIN = 2.2  # a block's width when its step has conditions only
GAP = 0.06  # between the table and the conditions under it

Segment = list[list[float]]


@dataclass(frozen=True, slots=True)
class Columns:
    """The widths of the table's columns (event, qualifier, action, live value)."""

    event: float
    qualifier: float
    operand: float
    value: float

    @property
    def width(self) -> float:
        return self.event + self.qualifier + self.operand + self.value


@dataclass(frozen=True, slots=True)
class Cell:
    """Where the live value of action row ``row`` (the value ``key``) is shown."""

    row: int
    key: str
    cx: float
    cy: float
    w: float
    h: float


@dataclass(slots=True)
class Block:
    """One step's block: its texts, lines, live cells and contacts; width and height."""

    width: float = 0.0
    height: float = 0.0
    texts: list[Text] = field(default_factory=list)
    segments: list[Segment] = field(default_factory=list)
    cells: list[Cell] = field(default_factory=list)
    contacts: dict[ConditionKey, tuple[tuple[Rect, ...], ...]] = field(default_factory=dict)


def _operand_text(operand: str, value: str) -> str:
    return f"{operand}, {value}" if value else operand


def columns_of(steps: Iterable[StepInfo]) -> Columns | None:
    """The columns of a chart's tables (None: no step has an action row)."""
    rows = [a for s in steps for a in s.actions]
    if not rows:
        return None

    def widest(texts: Iterable[str], least: float) -> float:
        return max([least, *(text_width(t, ACTION_SIZE) + 2 * PAD for t in texts)])

    operand = widest((_operand_text(a.operand, a.value) for a in rows), OPERAND_MIN)
    return Columns(
        event=widest((a.event for a in rows), 0.3),
        qualifier=widest((a.qualifier for a in rows), 0.3),
        operand=min(operand, OPERAND_MAX),
        value=VALUE_W if any(a.watch for a in rows) else 0.0,
    )


def block_width(cols: Columns | None, steps: Iterable[StepInfo]) -> float:
    """How wide the chart's blocks are (0: no step has a table or a condition)."""
    has_condition = any(s.interlock_condition or s.supervision_condition for s in steps)
    width = cols.width if cols is not None else 0.0
    return max(width, CONDITION_MIN) if has_condition else width


def step_block(info: StepInfo, cols: Columns | None, width: float, x: float, y: float) -> Block:
    """The block of step ``info`` with its top-left corner at ``(x, y)``, ``width`` wide."""
    block = Block(width=width)
    if info.actions and cols is not None:
        _table(block, info, cols, x, y)
    top = y - block.height - (GAP if block.height else 0.0)
    for kind, text, spans in (
        ("C", info.interlock_condition, info.interlock_contacts),
        ("V", info.supervision_condition, info.supervision_contacts),
    ):
        if text:
            top = _condition(block, (kind, info.number), text, spans, x, top)
    block.height = y - top if block.texts else 0.0
    return block


def _table(block: Block, info: StepInfo, cols: Columns, x: float, y: float) -> None:
    pitch = ACTION_SIZE * LINE
    edges = [x, x + cols.event, x + cols.event + cols.qualifier]
    edges += [edges[2] + cols.operand] + ([edges[2] + cols.operand + cols.value] * bool(cols.value))
    right = edges[-1]
    top = y
    for i, a in enumerate(info.actions):
        lines = wrap(_operand_text(a.operand, a.value), cols.operand - 2 * PAD, ACTION_SIZE)
        h = len(lines) * pitch + 2 * ROW_PAD
        text_top = top - ROW_PAD
        if a.event:
            block.texts.append(Text((a.event,), edges[0] + PAD, text_top, ACTION_SIZE))
        block.texts.append(Text((a.qualifier,), edges[1] + PAD, text_top, ACTION_SIZE))
        block.texts.append(Text(tuple(lines), edges[2] + PAD, text_top, ACTION_SIZE))
        if a.watch and cols.value:
            cx = (edges[3] + edges[4]) / 2
            block.cells.append(Cell(i, a.watch, cx, top - h / 2, cols.value - 0.04, h - 0.04))
        top -= h
        block.segments.append([[x, top, 0.0], [right, top, 0.0]])
    block.segments.append([[x, y, 0.0], [right, y, 0.0]])
    block.segments += [[[e, y, 0.0], [e, top, 0.0]] for e in edges]
    block.height = y - top


def _condition(
    block: Block, key: ConditionKey, text: str, spans: list[tuple[int, int]], x: float, y: float
) -> float:
    """The condition ``text`` under the table, after its ``C`` or ``V`` mark: its lines and
    where its contacts stand; the y under it."""
    mark = f"{key[0]}:"
    indent = text_width(mark, ACTION_SIZE) + 0.08
    lines = wrap(text, block.width - indent, ACTION_SIZE)
    block.texts.append(Text((mark,), x, y, ACTION_SIZE))
    block.texts.append(Text(tuple(lines), x + indent, y, ACTION_SIZE))
    starts = line_starts(text, lines)
    block.contacts[key] = span_rects(lines, starts, spans, x + indent, y, ACTION_SIZE)
    return y - len(lines) * ACTION_SIZE * LINE - 0.04
