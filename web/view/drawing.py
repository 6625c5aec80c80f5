"""A placed chart drawn as S7-GRAPH draws it, into a viser scene: the picture (computed once
per chart) and its drawing (the scene nodes of one scene, recoloured live).

:func:`picture` turns a :class:`~web.view.layout.Placement` into scene geometry: steps as
boxes (the initial step double-framed, ``C``/``V`` marks), transitions as bars with their
number, name and whole condition wrapped beside them (a transition row grows when its text
needs more lines), lines, jumps, stops and the continuation arrows of wrapped sequences.
Every text is fitted: a step's name wraps inside its box and its size shrinks until it fits,
so it is never cut nor spills out; all texts are rendered into images (one per part of the
chart that has text, each at most 2048 pixels square: labels are slow under software WebGL,
an image is not; ``web.view.glyphs``), each drawn as a mesh over its inked blocks only
(``web.view.text_mesh``).
Beside each step its action table and under it its interlock and supervision conditions
(``web.view.actions_table``); lanes are wide enough for them. The picture also says where
the status view shows what changes (``web.view.status_layer``): each step's times, each
action row's live value, each contact of a condition (``web.view.criteria``), and where each
sequence lies (``Picture.sequence_bounds``). :class:`Drawing` puts a picture into one
scene (the shared live scene, or one page's edit scene at an offset) with click handlers
on steps and on transitions (a box's and a bar's click their own; the transitions' texts
are text meshes of their own, covering only their ink, that take the clicks on them and
find the transition from where the click meets the chart — no invisible target costs a
frame its pixels; the other texts take none, so a step's name passes a click and the
hover on to its box), and recolours its steps and transitions. :func:`camera_for` aims a
camera at a picture at a zoom where its text is readable: the whole chart when it fits,
else its top-left part.
"""

from __future__ import annotations

import functools
import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from s7graph.web.view import texts
from s7graph.web.view.actions_table import Block, Cell, block_width, columns_of, step_block
from s7graph.web.view.criteria import ConditionKey, Rect, span_rects
from s7graph.web.view.glyphs import (
    LINE,
    TEXT_PX,
    TILE_PX,
    Text,
    Tile,
    fit_text,
    line_starts,
    text_width,
    tiles,
    wrap,
)
from s7graph.web.view.layout import Placement
from s7graph.web.view.text_mesh import lines_glb, tile_glb

__all__ = [
    "ACTIVE",
    "BOX_H",
    "BOX_W",
    "DISCONNECTED",
    "DISTURBED",
    "FLAT_LIGHT",
    "FLAWED",
    "INACTIVE",
    "INK",
    "LINE",
    "PANEL_W",
    "READABLE_PX",
    "SELECTED",
    "TEXT_PX",
    "TILE_PX",
    "Drawing",
    "Picture",
    "aim_camera",
    "camera_for",
    "canvas_of",
    "contrast",
    "fit_text",
    "picture",
    "rect_segments",
    "same_canvas",
    "wrap",
]

Rgb = tuple[int, int, int]
ACTIVE: Rgb = (40, 170, 60)
DISTURBED: Rgb = (240, 100, 100)  # a light red: black text on it keeps a contrast over 4.5
INACTIVE: Rgb = (205, 205, 205)
DISCONNECTED: Rgb = (238, 238, 238)  # every step, while the CPU is unreachable
SELECTED: Rgb = (130, 180, 245)  # the element an editor has selected
FLAWED: Rgb = (250, 190, 90)  # an element an error diagnostic names (edit mode)
INK: Rgb = (30, 30, 30)

FLAT_LIGHT = math.pi
"""The scene's one light: ambient, of intensity π, so a box shows exactly its RGB (three.js
lights a standard material's albedo by irradiance / π). A chart is flat: no default lights,
no shadows, no environment map — each is a pass software WebGL pays for in every frame
(``bench/page.py``: frames 67 → 33 ms for 8 steps, 167 → 83 ms for 250)."""

LANE = 3.6  # scene units per lane (more when steps have action tables)
ROW = 0.8  # scene units per row (more under a transition whose text needs it)
BOX_W, BOX_H = 1.9, 0.6
BAR_W = 0.55
BAR_H = 0.07
STEP_SIZES = (0.22, 0.19, 0.16, 0.13, 0.11, 0.09, 0.075)  # text heights tried in a box
TRANSITION_SIZE = 0.18
TEXT_W = LANE - BAR_W / 2 - 0.08 - BOX_W / 2 - 0.35  # beside a bar, short of the next lane
TEXT_TOP = 0.32  # a transition's text starts this far above its bar
TEXT_ROOM = 0.64  # and has this much height before its row grows
BLOCK_GAP = 0.34  # from a step box to its action table (room for the V mark)
LEFT_ROOM = 1.4  # left of a box: an incoming jump, the C mark, the step's times
MAX_TRANSITION_LINES = 24  # beyond: "…", the whole condition is in the details panel
READABLE_PX = 55.0  # screen pixels per scene unit at the default zoom: text of 10-12 px
FRAME_W = 2.0 / READABLE_PX
"""The width of a step box's and an action table's lines, in scene units: 2 pixels at the
default zoom, growing and shrinking with the chart like its text (one mesh of quads: under
software WebGL each segment of a line object costs a frame as much as a small mesh)."""


_width = text_width  # the name the tests know


def contrast(a: Rgb, b: Rgb) -> float:
    """The WCAG contrast ratio of two colours (≥ 4.5 reads as normal text)."""

    def lum(c: Rgb) -> float:
        ch = [v / 255 for v in c]
        lin = [x / 12.92 if x <= 0.04045 else ((x + 0.055) / 1.055) ** 2.4 for x in ch]
        return 0.2126 * lin[0] + 0.7152 * lin[1] + 0.0722 * lin[2]

    hi, lo = sorted((lum(a), lum(b)), reverse=True)
    return (hi + 0.05) / (lo + 0.05)


# ---------------------------------------------------------------- the picture


@dataclass(frozen=True, slots=True)
class Picture:
    """The scene geometry of one placed chart (scene units, y up), computed once per chart."""

    placement: Placement
    steps: dict[int, tuple[float, float]]
    transitions: dict[int, tuple[float, float]]
    targets: dict[int, tuple[float, float, float, float]]  # transition: cx, cy, w, h
    segments: Any  # float32 (n, 2, 3): links, jumps, stops
    double: Any
    frames: Any  # float32 (n, 2, 3): the frames of step boxes and action tables
    tiles: tuple[Tile, ...]
    bounds: tuple[float, float, float, float]  # x0, x1, y0 (bottom), y1 (top)
    lane: float = LANE
    times: dict[int, tuple[float, float]] = field(default_factory=dict)  # step: T/U top-left
    cells: dict[int, tuple[Cell, ...]] = field(default_factory=dict)  # step: live values
    contacts: dict[ConditionKey, tuple[tuple[Rect, ...], ...]] = field(default_factory=dict)
    sequence_bounds: dict[int, tuple[float, float, float, float]] = field(default_factory=dict)
    shown: dict[int, tuple[float, float, float, float]] = field(default_factory=dict)
    """transition: x0, y0, x1, y1 of its bar and the text drawn beside it (its click target
    reaches across the lane)"""


def rect_segments(
    cx: float, cy: float, w: float, h: float, z: float = 0.03
) -> list[list[list[float]]]:
    """The four sides of the ``w`` × ``h`` rectangle centred on ``(cx, cy)`` at height ``z``,
    as line segments."""
    x0, x1, y0, y1 = cx - w / 2, cx + w / 2, cy - h / 2, cy + h / 2
    corners = [(x0, y0), (x1, y0), (x1, y1), (x0, y1), (x0, y0)]
    return [[[a[0], a[1], z], [b[0], b[1], z]] for a, b in itertools.pairwise(corners)]


class _Rows:
    """Scene y of grid rows: ``ROW`` apart, more under a transition row that needs it. A
    fractional row below the middle of a gap keeps its distance to the row above, one past
    the middle to the row below (a convergence line stays just above its step)."""

    def __init__(self, extra: dict[int, float]) -> None:
        self._y: dict[int, float] = {}
        self._extra = extra
        top = max(extra, default=0) + 2
        y = 0.0
        for r in range(top + 1):
            self._y[r] = y
            y -= ROW + extra.get(r, 0.0)
        self._last = top

    def at(self, row: float, *, from_above: bool = False) -> float:
        r = math.floor(row)
        frac = row - r
        if r < 0:
            base = -r * ROW
        else:
            base = self._y.get(r, self._y[self._last] - (r - self._last) * ROW)
        if frac == 0:
            return base
        gap = ROW + self._extra.get(r, 0.0)
        if from_above or frac < 0.5:
            return base - frac * ROW
        return base - gap + (1 - frac) * ROW


def picture(placement: Placement) -> Picture:
    """The scene geometry and rendered texts of ``placement``."""
    p = placement
    infos = [s.info for s in p.steps.values() if s.info is not None]
    cols = columns_of(infos)
    block_w = block_width(cols, infos)
    lane = max(LANE, BOX_W + BLOCK_GAP + block_w + LEFT_ROOM) if block_w else LANE
    blocks = {
        s.number: step_block(s.info, cols, block_w, 0.0, 0.0)
        for s in p.steps.values()
        if s.info is not None and block_w
    }
    trans_text, rows = _transition_texts(p, lane - (LANE - TEXT_W), blocks)
    d = _Drawing(rows, lane)
    d.links(p)
    d.steps(p)
    d.blocks(p, {n: b for n, b in blocks.items() if b.height}, cols, block_w)
    d.transitions(p, trans_text)
    d.jumps(p)
    d.incoming_jumps(p)
    d.continuations(p)
    d.stops(p)
    for q in p.sequences:
        x, _ = d.xy(q.x0, 0)
        title = f"Sequence {q.number}  {q.name}".rstrip()
        d.text_at([title], x - BOX_W / 2, 0.75, "bottom-left", 0.22)
    bounds = d.bounds()
    return Picture(
        placement=p,
        steps=d.step_xy,
        transitions=d.transition_xy,
        targets=d.targets,
        shown=d.shown,
        segments=joined(np.array(d.segments, np.float32).reshape(-1, 2, 3)),
        double=joined(np.array(d.double, np.float32).reshape(-1, 2, 3)),
        frames=joined(np.array(d.frames, np.float32).reshape(-1, 2, 3)),
        tiles=tuple(tiles(d.text_items)),
        bounds=bounds,
        lane=lane,
        times=d.times,
        cells=d.cells,
        contacts=d.contacts,
        sequence_bounds={
            q.number: (
                q.x0 * lane - BOX_W / 2 - LEFT_ROOM,
                min(q.x1 * lane + lane - BOX_W / 2 - 0.2, bounds[1]),
                bounds[2],
                bounds[3],
            )
            for q in p.sequences
        },
    )


_TOUCH = 1e-4  # scene units: segment ends this close touch


def joined(segments: Any) -> Any:
    """The same lines in fewer segments: vertical and horizontal segments on one line that
    touch or overlap are one segment (a sequence's line from step to transition to step is
    drawn as one run); the others as they are. Software WebGL pays per segment drawn."""
    runs: dict[tuple[int, float, float], list[tuple[float, float]]] = {}
    rest: list[Any] = []
    for a, b in segments.tolist():
        for axis in (0, 1):  # 0: vertical (x the same), 1: horizontal (y the same)
            if abs(a[axis] - b[axis]) < _TOUCH and a[2] == b[2]:
                key = (axis, round(a[axis] / _TOUCH) * _TOUCH, a[2])
                lo, hi = sorted((a[1 - axis], b[1 - axis]))
                runs.setdefault(key, []).append((lo, hi))
                break
        else:
            rest.append([a, b])
    out = rest
    for (axis, at, z), spans in runs.items():
        spans.sort()
        lo, hi = spans[0]
        for nlo, nhi in [*spans[1:], (math.inf, math.inf)]:
            if nlo <= hi + _TOUCH:
                hi = max(hi, nhi)
                continue
            ends = [[at, lo, z], [at, hi, z]] if axis == 0 else [[lo, at, z], [hi, at, z]]
            out.append(ends)
            lo, hi = nlo, nhi
    return np.array(out, np.float32).reshape(-1, 2, 3)


@dataclass(frozen=True, slots=True)
class _TransitionText:
    """A transition's lines beside its bar: its title, then its condition from line
    ``first`` (``condition``: those lines, ``starts``: where each begins in the text)."""

    lines: list[str]
    size: float
    first: int
    condition: list[str]
    starts: list[int]


def _transition_texts(
    p: Placement, text_w: float, blocks: dict[int, Block]
) -> tuple[dict[int, _TransitionText], _Rows]:
    """Each transition's wrapped title and condition, and the rows, each as high as the
    longest transition text on it needs, or a step's action table and conditions."""
    trans_text: dict[int, _TransitionText] = {}
    extra: dict[int, float] = {}
    for t in p.transitions.values():
        title = texts.title("T", t.number, t.name, 10_000)
        lines = wrap(title, text_w, TRANSITION_SIZE)
        first = len(lines)
        condition = wrap(t.condition, text_w, TRANSITION_SIZE) if t.condition else []
        lines += condition
        if len(lines) > MAX_TRANSITION_LINES:
            lines = [*lines[: MAX_TRANSITION_LINES - 1], "… (whole condition: click)"]
            condition = condition[: max(MAX_TRANSITION_LINES - 1 - first, 0)]
        starts = line_starts(t.condition, condition)
        trans_text[t.number] = _TransitionText(lines, TRANSITION_SIZE, first, condition, starts)
        need = len(lines) * TRANSITION_SIZE * LINE - TEXT_ROOM
        if need > 0:
            row = int(t.y)
            extra[row] = max(extra.get(row, 0.0), need)
    room = BOX_H / 2 + ROW / 2 - 0.08  # from a box's top to a line half a row under it
    for number, block in blocks.items():
        if block.height > room:
            row = int(p.steps[number].y)
            extra[row] = max(extra.get(row, 0.0), block.height - room)
    return trans_text, _Rows(extra)


class _Drawing:
    """The line segments and texts of a picture as they are drawn, element kind by kind."""

    def __init__(self, rows: _Rows, lane: float = LANE) -> None:
        self.rows = rows
        self.lane = lane
        self.text_w = lane - (LANE - TEXT_W)
        self.text_items: list[Text] = []
        self.segments: list[list[list[float]]] = []
        self.double: list[list[list[float]]] = []
        self.frames: list[list[list[float]]] = []  # step boxes, marks, action tables
        self.step_xy: dict[int, tuple[float, float]] = {}
        self.transition_xy: dict[int, tuple[float, float]] = {}
        self.targets: dict[int, tuple[float, float, float, float]] = {}
        self.shown: dict[int, tuple[float, float, float, float]] = {}
        self.times: dict[int, tuple[float, float]] = {}
        self.cells: dict[int, tuple[Cell, ...]] = {}
        self.contacts: dict[ConditionKey, tuple[tuple[Rect, ...], ...]] = {}

    def xy(self, x: float, y: float, *, from_above: bool = False) -> tuple[float, float]:
        return x * self.lane, self.rows.at(y, from_above=from_above)

    def text_at(
        self,
        lines: list[str],
        x: float,
        y: float,
        anchor: str,
        size: float,
        *,
        click: bool = False,
    ) -> None:
        w = max((_width(line, size) for line in lines), default=0.0)
        h = size * LINE * len(lines)
        vertical, _, horizontal = anchor.partition("-")
        left = x - {"left": 0.0, "center": w / 2, "right": w}[horizontal]
        top = y + {"top": 0.0, "center": h / 2, "bottom": h}[vertical]
        self.text_items.append(Text(tuple(lines), left, top, size, click))

    def links(self, p: Placement) -> None:
        for link in p.links:
            pts = [self.xy(x, y) for x, y in link.points]
            for (ax, ay), (bx, by) in itertools.pairwise(pts):
                if link.double and ay == by:
                    for d in (-0.035, 0.035):
                        self.double.append([[ax, ay + d, 0.0], [bx, by + d, 0.0]])
                else:
                    self.segments.append([[ax, ay, 0.0], [bx, by, 0.0]])

    def steps(self, p: Placement) -> None:
        for s in p.steps.values():
            x, y = self.xy(s.x, s.y)
            self.step_xy[s.number] = (x, y)
            self.frames += rect_segments(x, y, BOX_W, BOX_H)
            if s.initial:  # S7-GRAPH draws the initial step with a double frame
                self.frames += rect_segments(x, y, BOX_W + 0.12, BOX_H + 0.12)
            label = texts.title("S", s.number, s.name, 10_000)
            lines, size = fit_text(label, BOX_W - 0.12, BOX_H - 0.08, STEP_SIZES)
            self.text_at(lines, x, y, "center-center", size)
            self.times[s.number] = (x - BOX_W / 2, y - BOX_H / 2 - 0.03)
            if s.interlock:
                self.frames += rect_segments(x - BOX_W / 2 - 0.14, y, 0.22, 0.28)
                self.text_at(["C"], x - BOX_W / 2 - 0.14, y, "center-center", 0.2)
            if s.supervision:
                self.frames += rect_segments(x + BOX_W / 2 + 0.14, y, 0.22, 0.28)
                self.text_at(["V"], x + BOX_W / 2 + 0.14, y, "center-center", 0.2)

    def blocks(self, p: Placement, blocks: dict[int, Block], cols: Any, width: float) -> None:
        """Each step's action table and conditions right of its box, its top at the box's."""
        for number in blocks:
            s = p.steps[number]
            assert s.info is not None
            x, y = self.step_xy[number]
            b = step_block(s.info, cols, width, x + BOX_W / 2 + BLOCK_GAP, y + BOX_H / 2)
            self.text_items += b.texts
            self.frames += b.segments
            if b.cells:
                self.cells[number] = tuple(b.cells)
            self.contacts.update(b.contacts)

    def transitions(self, p: Placement, trans_text: dict[int, _TransitionText]) -> None:
        for t in p.transitions.values():
            x, y = self.xy(t.x, t.y)
            self.transition_xy[t.number] = (x, y)
            tt = trans_text[t.number]
            lines, size = tt.lines, tt.size
            left, top = x + BAR_W / 2 + 0.08, y + TEXT_TOP
            self.text_at(lines, left, top, "top-left", size, click=True)
            if t.contacts:
                cond_top = top - tt.first * size * LINE
                spans = list(t.contacts)
                rects = span_rects(tt.condition, tt.starts, spans, left, cond_top, size)
                self.contacts[("T", t.number)] = rects
            h = max(size * LINE * len(lines), 0.3)
            x0, x1 = x - BAR_W / 2 - 0.05, left + self.text_w
            y0, y1 = min(top - h, y - 0.15), max(top, y + 0.15)
            self.targets[t.number] = ((x0 + x1) / 2, (y0 + y1) / 2, x1 - x0, y1 - y0)
            drawn = self.text_items[-1]
            self.shown[t.number] = (x0, y0, max(x + BAR_W / 2, drawn.x + drawn.width), y1)

    def jumps(self, p: Placement) -> None:
        for j in p.jumps:
            x, y = self.xy(j.x, j.y, from_above=True)
            tip = y - 0.32
            self.segments += [
                [[x, y + 0.35, 0.0], [x, tip, 0.0]],
                [[x - 0.1, tip + 0.14, 0.0], [x, tip, 0.0]],
                [[x + 0.1, tip + 0.14, 0.0], [x, tip, 0.0]],
            ]
            self.text_at([f"S{j.target}"], x + 0.12, tip + 0.05, "center-left", 0.22)

    def incoming_jumps(self, p: Placement) -> None:
        sources: dict[int, list[int]] = {}
        for inc in p.incoming_jumps:
            sources.setdefault(inc.step, []).append(inc.transition)
        for number, ts in sources.items():
            target = p.steps[number]
            sx, y = self.step_xy[number]
            end = sx - BOX_W / 2 - (0.3 if target.interlock else 0.04)
            start = end - 0.55
            self.segments += [
                [[start, y, 0.0], [end, y, 0.0]],
                [[end - 0.12, y + 0.08, 0.0], [end, y, 0.0]],
                [[end - 0.12, y - 0.08, 0.0], [end, y, 0.0]],
            ]
            names = ", ".join(f"T{t}" for t in sorted(set(ts)))
            self.text_at([names], start - 0.04, y, "center-right", 0.19)

    def continuations(self, p: Placement) -> None:
        for c in p.continuations:
            x, y = self.xy(c.x, c.y, from_above=not c.incoming)
            if c.incoming:  # an arrowhead into the line going down to the target
                self.segments += [
                    [[x - 0.1, y - 0.02, 0.0], [x, y - 0.16, 0.0]],
                    [[x + 0.1, y - 0.02, 0.0], [x, y - 0.16, 0.0]],
                ]
                self.text_at([c.text], x + 0.12, y, "center-left", 0.18)
            else:
                self.segments += [
                    [[x - 0.1, y + 0.14, 0.0], [x, y, 0.0]],
                    [[x + 0.1, y + 0.14, 0.0], [x, y, 0.0]],
                ]
                self.text_at([c.text], x + 0.12, y + 0.05, "center-left", 0.18)

    def stops(self, p: Placement) -> None:
        for stop in p.stops:
            x, y = self.xy(stop.x, stop.y, from_above=True)
            self.segments += [
                [[x, y + 0.4, 0.0], [x, y - 0.1, 0.0]],
                [[x - 0.2, y - 0.1, 0.0], [x + 0.2, y - 0.1, 0.0]],
            ]
            self.text_at(["STOP"], x + 0.25, y - 0.1, "center-left", 0.18)

    def bounds(self) -> tuple[float, float, float, float]:
        steps, transitions = self.step_xy.values(), self.transition_xy.values()
        xs = [v for x, _ in steps for v in (x - BOX_W / 2 - 0.9, x + BOX_W / 2 + 0.3)]
        xs += [x + BAR_W / 2 + 0.08 + self.text_w for x, _ in transitions]
        xs += [v for t in self.text_items for v in (t.x, t.x + t.width)]
        ys = [y for _, y in steps] + [y for _, y in transitions]
        ys += [t.y - t.height for t in self.text_items] + [1.0]
        return (
            min(xs, default=0.0),
            max(xs, default=1.0),
            min(ys, default=0.0) - BOX_H,
            max(ys, default=0.0),
        )


# ---------------------------------------------------------------- into a scene

Click = Callable[[int, Any], None]


class Drawing:
    """``pic`` drawn in ``scene`` under ``root``, shifted by ``offset``; ``on_step(n,
    event)`` / ``on_transition(n, event)`` are called when a step box or a transition (its
    bar or its text) is clicked."""

    def __init__(
        self,
        scene: Any,
        pic: Picture,
        *,
        root: str = "/chart",
        offset: tuple[float, float] = (0.0, 0.0),
        on_step: Click | None = None,
        on_transition: Click | None = None,
    ) -> None:
        self.scene = scene
        self.picture = pic
        self.root = root
        self.offset = offset
        self.boxes: dict[int, Any] = {}
        self.bars: dict[int, Any] = {}
        self._colour: dict[tuple[str, int], Rgb] = {}
        self._nodes: list[Any] = []
        ox, oy = offset
        for n, (x, y) in pic.steps.items():
            box = scene.add_box(
                f"{root}/step/S{n}",
                color=INACTIVE,
                dimensions=(BOX_W, BOX_H, 0.04),
                position=(x + ox, y + oy, 0.0),
                cast_shadow=False,
                receive_shadow=False,
            )
            if on_step is not None:
                box.on_click(functools.partial(_relay, on_step, n))
            self.boxes[n] = box
            self._nodes.append(box)
        for n, (x, y) in pic.transitions.items():
            bar = scene.add_box(
                f"{root}/trans/T{n}",
                color=INK,
                dimensions=(BAR_W, BAR_H, 0.04),
                position=(x + ox, y + oy, 0.0),
                cast_shadow=False,
                receive_shadow=False,
            )
            self.bars[n] = bar
            self._nodes.append(bar)
            if on_transition is not None:
                bar.on_click(functools.partial(_relay, on_transition, n))
        self._on_step, self._on_transition = on_step, on_transition
        shifted = np.array([ox, oy, 0.0], np.float32)
        for name, lines, width in (("lines", pic.segments, 2.0), ("double", pic.double, 1.5)):
            if len(lines):
                self._nodes.append(
                    scene.add_line_segments(
                        f"{root}/{name}",
                        lines + shifted,
                        colors=INK,
                        thickness=width,
                        thickness_units="screen",
                    )
                )
        frames = lines_glb(pic.frames + shifted, FRAME_W, INK)
        if frames is not None:
            self._nodes.append(
                scene.add_glb(f"{root}/frames", frames, cast_shadow=False, receive_shadow=False)
            )
        for i, tile in enumerate(pic.tiles):
            glb = tile_glb(tile)  # rendered now, and kept only as the GLB viser sends
            if glb is None:
                continue
            text = scene.add_glb(
                f"{root}/text{i}",
                glb,
                position=(tile.cx + ox, tile.cy + oy, 0.05),
                cast_shadow=False,
                receive_shadow=False,
            )
            if tile.click and (on_step is not None or on_transition is not None):
                text.on_click(self._clicked)  # its mesh covers only the ink
            self._nodes.append(text)

    def paint(self, steps: dict[int, Rgb], transitions: dict[int, Rgb] | None = None) -> None:
        """Colour each step box (missing: inactive grey) and transition bar (missing:
        ink); only what changed is sent."""
        self.paint_steps(steps)
        for n, bar in self.bars.items():
            self._set(("T", n), bar, (transitions or {}).get(n, INK))

    def paint_steps(self, steps: dict[int, Rgb]) -> bool:
        """Colour each step box (missing: inactive grey), the bars as they are; only what
        changed is sent. True if something was."""
        sent = False
        for n, box in self.boxes.items():
            sent = self._set(("S", n), box, steps.get(n, INACTIVE)) or sent
        return sent

    def _set(self, key: tuple[str, int], handle: Any, colour: Rgb) -> bool:
        if self._colour.get(key) == colour:
            return False
        handle.color = colour
        self._colour[key] = colour
        return True

    def forget_colours(self) -> None:
        """Send every colour again at the next paint."""
        self._colour.clear()

    def _clicked(self, event: Any) -> None:
        """A click on a transition's text (the only texts that take clicks: a step's name
        lets the click through to its box): that transition; a point of it that lies on a
        step box, that step (the bars and boxes have clicks of their own)."""
        at = chart_point(event, self.offset)
        if at is None:
            return
        n = transition_text_at(self.picture, *at)  # None on a step box: it looks first
        if n is not None:
            if self._on_transition is not None:
                self._on_transition(n, event)
            return
        n = step_box_at(self.picture, *at)
        if n is not None and self._on_step is not None:
            self._on_step(n, event)

    def remove(self) -> None:
        self._on_step = self._on_transition = None
        for node in self._nodes:
            try:
                node.remove()
            except Exception:  # a page gone meanwhile
                continue
        self._nodes.clear()
        self.boxes.clear()
        self.bars.clear()


def chart_point(event: Any, offset: tuple[float, float]) -> tuple[float, float] | None:
    """Where a scene click's ray (``ray_origin``, ``ray_direction``) meets the chart's plane
    z = 0, as a point of a picture drawn at ``offset``; None if it never does."""
    (x0, y0, z0), (dx, dy, dz) = event.ray_origin, event.ray_direction
    if dz == 0 or -z0 / dz <= 0:
        return None
    ox, oy = offset
    return x0 - z0 / dz * dx - ox, y0 - z0 / dz * dy - oy


def step_box_at(pic: Picture, x: float, y: float) -> int | None:
    """The step whose box holds the picture point ``(x, y)``."""
    for n, (sx, sy) in pic.steps.items():
        if abs(x - sx) <= BOX_W / 2 and abs(y - sy) <= BOX_H / 2:
            return n
    return None


def on_step_box(pic: Picture, x: float, y: float) -> bool:
    """Whether the picture point ``(x, y)`` is on a step box."""
    return step_box_at(pic, x, y) is not None


def target_at(pic: Picture, x: float, y: float) -> int | None:
    """The transition whose click target (bar and text) holds the picture point ``(x, y)``."""
    for n, (cx, cy, w, h) in pic.targets.items():
        if abs(x - cx) <= w / 2 and abs(y - cy) <= h / 2:
            return n
    return None


def transition_text_at(pic: Picture, x: float, y: float) -> int | None:
    """The transition whose click target (bar and text) holds the picture point ``(x,
    y)``, unless the point is on its bar or on a step box (they are clicked as nodes)."""
    if on_step_box(pic, x, y):
        return None
    n = target_at(pic, x, y)
    if n is None:
        return None
    tx, ty = pic.transitions[n]
    return None if abs(x - tx) <= BAR_W / 2 and abs(y - ty) <= BAR_H / 2 else n


def _relay(callback: Click, number: int, event: Any) -> None:
    callback(number, event)


PAGE_W, PAGE_H = 1280, 800  # the page a camera is aimed for before it says its size
PANEL_W = 380  # the side panel, docked right of the chart (the canvas ends where it starts)
CANVAS_ASPECT = (PAGE_W - PANEL_W) / PAGE_H
Bounds = tuple[float, float, float, float]


def camera_for(
    pic: Picture,
    *,
    offset: tuple[float, float] = (0.0, 0.0),
    fov: float = 1.309,
    aspect: float = CANVAS_ASPECT,
    right: float = 0.0,
    height_px: float = float(PAGE_H),
    whole: bool = False,
    bounds: Bounds | None = None,
) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """Camera position and look-at point showing ``pic`` (at ``offset``; ``bounds``: only
    that part of it, a sequence) on a canvas ``aspect`` wide per height, ``height_px``
    high, of which a panel covers ``right`` (none: the side panel is docked beside the
    canvas): the whole of it if its text stays readable (``READABLE_PX`` screen pixels per
    scene unit) or ``whole`` is asked for, else its top-left part at that zoom."""
    x0, x1, y0, y1 = bounds or pic.bounds
    x0, x1, y0, y1 = x0 - 0.2, x1 + 0.2, y0 - 0.2, y1 + 0.2
    tan = math.tan(fov / 2)
    usable = aspect * (1 - right)
    fit = max((y1 - y0) / 2 / tan, (x1 - x0) / 2 / (tan * usable)) * 1.05
    readable = fit if whole else height_px / (READABLE_PX * 2 * tan)
    z = min(fit, readable)
    half_h, half_w = z * tan, z * tan * usable
    cx = (x0 + x1) / 2 if fit <= readable or x1 - x0 <= 2 * half_w else x0 + half_w
    cy = (y0 + y1) / 2 if fit <= readable or y1 - y0 <= 2 * half_h else y1 - half_h
    cx += z * tan * aspect * right  # a panel over the right of the canvas
    ox, oy = offset
    return (cx + ox, cy + oy, z), (cx + ox, cy + oy, 0.0)


def canvas_of(client: Any) -> tuple[float, float]:
    """The aspect and pixel height of ``client``'s canvas as its page last said (the side
    panel docked beside it is not part of it); the default page's until it has."""
    try:
        cam = client.camera
        height = float(cam.image_height)
        if height > 0 and cam.image_width > 0:
            return float(cam.image_width) / height, height
    except Exception:  # the page has not told its camera yet, or is gone
        pass
    return CANVAS_ASPECT, float(PAGE_H)


def same_canvas(before: tuple[float, float], now: tuple[float, float]) -> bool:
    """Whether a page's canvas reported ``now`` (its drawing buffer: device pixels) is the
    one it reported ``before`` drawn at another resolution: of the same shape, a
    pixel's rounding apart. viser's page lowers its resolution while it draws slowly (its
    adaptive pixel ratio, down to 0.75 of the screen's) and raises it again; the canvas on
    the page keeps its size."""
    (w0, h0), (w1, h1) = before, now
    if min(w0, h0, w1, h1) <= 0:
        return False
    return abs(w0 / h0 - w1 / h1) <= 1.5 / min(h0, h1) + 1.5 * max(w0, w1) / min(h0, h1) ** 2


def aim_camera(
    client: Any,
    pic: Picture,
    *,
    whole: bool,
    offset: tuple[float, float] = (0, 0),
    bounds: Bounds | None = None,
) -> tuple[float, float, float] | None:
    """Aim ``client``'s camera at ``pic`` (``bounds``: a part of it): the whole of it, or
    the default readable zoom, fitted to the page's canvas; where the camera was put
    (None: the page is gone)."""
    aspect, height = canvas_of(client)
    position, look = camera_for(
        pic, offset=offset, whole=whole, aspect=aspect, height_px=height, bounds=bounds
    )
    try:
        cam = client.camera
        x, y, z = position
        if all(abs(float(a) - b) < 1e-6 for a, b in zip(cam.position, position, strict=True)):
            # viser sends nothing for a position equal to the one the page last reported,
            # which may be older than one sent since (a report crossed it): move it first
            cam.position = (x, y, z + 1e-3)
        cam.position = position
        cam.look_at = look
        cam.up_direction = (0.0, 1.0, 0.0)
    except Exception:  # the page has not told its camera yet, or is gone
        return None
    return position


def scale_px(z: float, fov: float = 1.309, height_px: float = 800.0) -> float:
    """Screen pixels per scene unit for a camera ``z`` above the chart."""
    return height_px / (2 * z * math.tan(fov / 2))
