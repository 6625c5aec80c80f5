"""A placed chart drawn as S7-GRAPH draws it, into a viser scene: the picture (computed once
per chart) and its drawing (the scene nodes of one scene, recoloured live).

:func:`picture` turns a :class:`~web.view.layout.Placement` into scene geometry: steps as
boxes (the initial step double-framed, ``C``/``V`` marks), transitions as bars with their
number, name and whole condition wrapped beside them (a transition row grows when its text
needs more lines), lines, jumps, stops and the continuation arrows of wrapped sequences.
Every text is fitted: a step's name wraps inside its box and its size shrinks until it fits,
so it is never cut nor spills out; all texts are rendered into a few images (one per band of
the chart: labels are slow under software WebGL, an image is not). :class:`Drawing` puts a
picture into one scene (the shared live scene, or one page's edit scene at an offset) with
click handlers on steps and on transitions (an invisible target over bar and text), and
recolours its steps and transitions. :func:`camera_for` aims a camera at a picture at a
zoom where its text is readable: the whole chart when it fits, else its top-left part.
"""

from __future__ import annotations

import functools
import itertools
import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from s7graph.web.view import texts
from s7graph.web.view.layout import Placement

__all__ = [
    "ACTIVE",
    "DISCONNECTED",
    "DISTURBED",
    "FLAT_LIGHT",
    "FLAWED",
    "INACTIVE",
    "INK",
    "READABLE_PX",
    "SELECTED",
    "Drawing",
    "Picture",
    "aim_camera",
    "camera_for",
    "contrast",
    "fit_text",
    "picture",
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

LANE = 3.6  # scene units per lane
ROW = 0.8  # scene units per row (more under a transition whose text needs it)
BOX_W, BOX_H = 1.9, 0.6
BAR_W = 0.55
STEP_SIZES = (0.22, 0.19, 0.16, 0.13, 0.11, 0.09, 0.075)  # text heights tried in a box
TRANSITION_SIZE = 0.18
TEXT_W = LANE - BAR_W / 2 - 0.08 - BOX_W / 2 - 0.35  # beside a bar, short of the next lane
TEXT_TOP = 0.32  # a transition's text starts this far above its bar
TEXT_ROOM = 0.64  # and has this much height before its row grows
LINE = 1.25  # line height / text height
TEXT_PX = 90  # text image pixels per scene unit
BAND_PX = 2048  # the widest text image (WebGL textures stay small)
MAX_TRANSITION_LINES = 24  # beyond: "…", the whole condition is in the details panel
READABLE_PX = 55.0  # screen pixels per scene unit at the default zoom: text of 10-12 px


@functools.cache
def _font(px: int) -> ImageFont.FreeTypeFont | ImageFont.ImageFont:
    return ImageFont.load_default(size=max(px, 6))


def _width(text: str, size: float) -> float:
    """The width of ``text`` in scene units at text height ``size``."""
    return float(_font(round(size * TEXT_PX)).getlength(text)) / TEXT_PX


def wrap(text: str, width: float, size: float) -> list[str]:
    """``text`` in lines no wider than ``width`` at ``size``: broken at blanks, a word too
    long for a line broken inside; every character kept (line breaks start new lines)."""
    lines: list[str] = []
    for para in text.split("\n"):
        line = ""
        for word in para.split(" "):
            candidate = f"{line} {word}" if line else word
            if _width(candidate, size) <= width:
                line = candidate
                continue
            if line:
                lines.append(line)
            line = ""
            while word and _width(word, size) > width:
                cut = max(1, _fits(word, width, size))
                lines.append(word[:cut])
                word = word[cut:]
            line = word
        lines.append(line)
    return lines


def _fits(word: str, width: float, size: float) -> int:
    """How many leading characters of ``word`` fit in ``width``."""
    lo, hi = 0, len(word)
    while lo < hi:
        mid = (lo + hi + 1) // 2
        if _width(word[:mid], size) <= width:
            lo = mid
        else:
            hi = mid - 1
    return lo


def fit_text(
    text: str, width: float, height: float, sizes: Iterable[float]
) -> tuple[list[str], float]:
    """The lines and the largest of ``sizes`` at which ``text`` fits in ``width`` ×
    ``height``; the smallest size when none does (its lines then are all there)."""
    best: tuple[list[str], float] | None = None
    for size in sizes:
        lines = wrap(text, width, size)
        best = (lines, size)
        if len(lines) * size * LINE <= height:
            return best
    assert best is not None
    return best


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
class Text:
    lines: tuple[str, ...]
    x: float  # left
    y: float  # top
    size: float


@dataclass(frozen=True, slots=True)
class Tile:
    image: Any  # RGBA numpy array, rows bottom-up
    width: float
    height: float
    cx: float
    cy: float


@dataclass(frozen=True, slots=True)
class Picture:
    """The scene geometry of one placed chart (scene units, y up), computed once per chart."""

    placement: Placement
    steps: dict[int, tuple[float, float]]
    transitions: dict[int, tuple[float, float]]
    targets: dict[int, tuple[float, float, float, float]]  # transition: cx, cy, w, h
    segments: Any  # float32 (n, 2, 3)
    double: Any
    tiles: tuple[Tile, ...]
    bounds: tuple[float, float, float, float]  # x0, x1, y0 (bottom), y1 (top)


def _rect(cx: float, cy: float, w: float, h: float) -> list[list[list[float]]]:
    x0, x1, y0, y1 = cx - w / 2, cx + w / 2, cy - h / 2, cy + h / 2
    corners = [(x0, y0), (x1, y0), (x1, y1), (x0, y1), (x0, y0)]
    return [[[a[0], a[1], 0.03], [b[0], b[1], 0.03]] for a, b in itertools.pairwise(corners)]


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
    trans_text, rows = _transition_texts(p)
    d = _Drawing(rows)
    d.links(p)
    d.steps(p)
    d.transitions(p, trans_text)
    d.jumps(p)
    d.incoming_jumps(p)
    d.continuations(p)
    d.stops(p)
    for q in p.sequences:
        x, _ = d.xy(q.x0, 0)
        title = f"Sequence {q.number}  {q.name}".rstrip()
        d.text_at([title], x - BOX_W / 2, 0.75, "bottom-left", 0.22)
    return Picture(
        placement=p,
        steps=d.step_xy,
        transitions=d.transition_xy,
        targets=d.targets,
        segments=np.array(d.segments, np.float32).reshape(-1, 2, 3),
        double=np.array(d.double, np.float32).reshape(-1, 2, 3),
        tiles=tuple(_tiles(d.text_items)),
        bounds=d.bounds(),
    )


def _transition_texts(p: Placement) -> tuple[dict[int, tuple[list[str], float]], _Rows]:
    """Each transition's wrapped title and condition with its text size, and the rows, each
    as high as the longest transition text on it needs."""
    trans_text: dict[int, tuple[list[str], float]] = {}
    extra: dict[int, float] = {}
    for t in p.transitions.values():
        title = texts.title("T", t.number, t.name, 10_000)
        lines = wrap(title, TEXT_W, TRANSITION_SIZE)
        if t.condition:
            lines += wrap(t.condition, TEXT_W, TRANSITION_SIZE)
        if len(lines) > MAX_TRANSITION_LINES:
            lines = [*lines[: MAX_TRANSITION_LINES - 1], "… (whole condition: click)"]
        trans_text[t.number] = (lines, TRANSITION_SIZE)
        need = len(lines) * TRANSITION_SIZE * LINE - TEXT_ROOM
        if need > 0:
            row = int(t.y)
            extra[row] = max(extra.get(row, 0.0), need)
    return trans_text, _Rows(extra)


class _Drawing:
    """The line segments and texts of a picture as they are drawn, element kind by kind."""

    def __init__(self, rows: _Rows) -> None:
        self.rows = rows
        self.text_items: list[Text] = []
        self.segments: list[list[list[float]]] = []
        self.double: list[list[list[float]]] = []
        self.step_xy: dict[int, tuple[float, float]] = {}
        self.transition_xy: dict[int, tuple[float, float]] = {}
        self.targets: dict[int, tuple[float, float, float, float]] = {}

    def xy(self, x: float, y: float, *, from_above: bool = False) -> tuple[float, float]:
        return x * LANE, self.rows.at(y, from_above=from_above)

    def text_at(self, lines: list[str], x: float, y: float, anchor: str, size: float) -> None:
        w = max((_width(line, size) for line in lines), default=0.0)
        h = size * LINE * len(lines)
        vertical, _, horizontal = anchor.partition("-")
        left = x - {"left": 0.0, "center": w / 2, "right": w}[horizontal]
        top = y + {"top": 0.0, "center": h / 2, "bottom": h}[vertical]
        self.text_items.append(Text(tuple(lines), left, top, size))

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
            self.segments += _rect(x, y, BOX_W, BOX_H)
            if s.initial:  # S7-GRAPH draws the initial step with a double frame
                self.segments += _rect(x, y, BOX_W + 0.12, BOX_H + 0.12)
            label = texts.title("S", s.number, s.name, 10_000)
            lines, size = fit_text(label, BOX_W - 0.12, BOX_H - 0.08, STEP_SIZES)
            self.text_at(lines, x, y, "center-center", size)
            if s.interlock:
                self.segments += _rect(x - BOX_W / 2 - 0.14, y, 0.22, 0.28)
                self.text_at(["C"], x - BOX_W / 2 - 0.14, y, "center-center", 0.2)
            if s.supervision:
                self.segments += _rect(x + BOX_W / 2 + 0.14, y, 0.22, 0.28)
                self.text_at(["V"], x + BOX_W / 2 + 0.14, y, "center-center", 0.2)

    def transitions(self, p: Placement, trans_text: dict[int, tuple[list[str], float]]) -> None:
        for t in p.transitions.values():
            x, y = self.xy(t.x, t.y)
            self.transition_xy[t.number] = (x, y)
            lines, size = trans_text[t.number]
            left, top = x + BAR_W / 2 + 0.08, y + TEXT_TOP
            self.text_at(lines, left, top, "top-left", size)
            h = max(size * LINE * len(lines), 0.3)
            x0, x1 = x - BAR_W / 2 - 0.05, left + TEXT_W
            y0, y1 = min(top - h, y - 0.15), max(top, y + 0.15)
            self.targets[t.number] = ((x0 + x1) / 2, (y0 + y1) / 2, x1 - x0, y1 - y0)

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
        xs += [x + BAR_W / 2 + 0.08 + TEXT_W for x, _ in transitions]
        ys = [y for _, y in steps] + [y for _, y in transitions]
        ys += [t.y - t.size * LINE * len(t.lines) for t in self.text_items] + [1.0]
        return (
            min(xs, default=0.0),
            max(xs, default=1.0),
            min(ys, default=0.0) - BOX_H,
            max(ys, default=0.0),
        )


def _tiles(items: list[Text]) -> list[Tile]:
    """The texts rendered onto transparent images, one per band of at most ``BAND_PX``
    pixels of width (a text belongs to the band where it starts)."""
    band_w = BAND_PX / TEXT_PX
    if not items:
        return []
    x_min = min(t.x for t in items)
    bands: dict[int, list[Text]] = {}
    for t in items:
        bands.setdefault(int((t.x - x_min) // band_w), []).append(t)
    return [_render(group) for _, group in sorted(bands.items())]


def _render(items: list[Text]) -> Tile:
    def width(t: Text) -> float:
        return max((_width(line, t.size) for line in t.lines), default=0.0)

    x0 = min(t.x for t in items) - 0.1
    x1 = max(t.x + width(t) for t in items) + 0.1
    y1 = max(t.y for t in items) + 0.1
    y0 = min(t.y - t.size * LINE * len(t.lines) for t in items) - 0.1
    size = (max(round((x1 - x0) * TEXT_PX), 1), max(round((y1 - y0) * TEXT_PX), 1))
    image = Image.new("RGBA", size, (255, 255, 255, 0))
    draw = ImageDraw.Draw(image)
    for t in items:
        font = _font(round(t.size * TEXT_PX))
        for i, line in enumerate(t.lines):
            px = (t.x - x0) * TEXT_PX
            py = (y1 - t.y + i * t.size * LINE) * TEXT_PX
            draw.text((px, py), line, font=font, fill=(0, 0, 0, 255))
    pixels = np.ascontiguousarray(np.asarray(image)[::-1])  # the plane shows rows bottom-up
    return Tile(pixels, x1 - x0, y1 - y0, (x0 + x1) / 2, (y0 + y1) / 2)


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
                dimensions=(BAR_W, 0.07, 0.04),
                position=(x + ox, y + oy, 0.0),
                cast_shadow=False,
                receive_shadow=False,
            )
            self.bars[n] = bar
            self._nodes.append(bar)
            if on_transition is not None:
                cx, cy, w, h = pic.targets[n]
                hit = scene.add_box(
                    f"{root}/hit/T{n}",
                    color=(255, 255, 255),
                    opacity=0.0,
                    dimensions=(w, h, 0.01),
                    position=(cx + ox, cy + oy, -0.02),
                    cast_shadow=False,
                    receive_shadow=False,
                )
                hit.on_click(functools.partial(_relay, on_transition, n))
                bar.on_click(functools.partial(_relay, on_transition, n))
                self._nodes.append(hit)
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
        for i, tile in enumerate(pic.tiles):
            self._nodes.append(
                scene.add_image(
                    f"{root}/text{i}",
                    tile.image,
                    render_width=tile.width,
                    render_height=tile.height,
                    format="png",
                    position=(tile.cx + ox, tile.cy + oy, 0.05),
                    cast_shadow=False,
                    receive_shadow=False,
                )
            )

    def paint(self, steps: dict[int, Rgb], transitions: dict[int, Rgb] | None = None) -> None:
        """Colour each step box (missing: inactive grey) and transition bar (missing:
        ink); only what changed is sent."""
        for n, box in self.boxes.items():
            self._set(("S", n), box, steps.get(n, INACTIVE))
        for n, bar in self.bars.items():
            self._set(("T", n), bar, (transitions or {}).get(n, INK))

    def _set(self, key: tuple[str, int], handle: Any, colour: Rgb) -> None:
        if self._colour.get(key) != colour:
            handle.color = colour
            self._colour[key] = colour

    def forget_colours(self) -> None:
        """Send every colour again at the next paint."""
        self._colour.clear()

    def remove(self) -> None:
        for node in self._nodes:
            try:
                node.remove()
            except Exception:  # a page gone meanwhile
                continue
        self._nodes.clear()
        self.boxes.clear()
        self.bars.clear()


def _relay(callback: Click, number: int, event: Any) -> None:
    callback(number, event)


def camera_for(
    pic: Picture,
    *,
    offset: tuple[float, float] = (0.0, 0.0),
    fov: float = 1.309,
    aspect: float = 1.6,
    right: float = 0.28,
    height_px: float = 800.0,
    whole: bool = False,
) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """Camera position and look-at point showing ``pic`` (at ``offset``) left of the side
    panel covering ``right`` of the canvas' width (``aspect``: width / height): the whole
    chart if its text stays readable (``READABLE_PX`` screen pixels per scene unit on a
    page ``height_px`` high) or ``whole`` is asked for, else its top-left part at that zoom."""
    x0, x1, y0, y1 = pic.bounds
    x0, x1, y0, y1 = x0 - 0.2, x1 + 0.2, y0 - 0.2, y1 + 0.2
    tan = math.tan(fov / 2)
    usable = aspect * (1 - right)
    fit = max((y1 - y0) / 2 / tan, (x1 - x0) / 2 / (tan * usable)) * 1.05
    readable = fit if whole else height_px / (READABLE_PX * 2 * tan)
    z = min(fit, readable)
    half_h, half_w = z * tan, z * tan * usable
    cx = (x0 + x1) / 2 if fit <= readable else x0 + half_w
    cy = (y0 + y1) / 2 if fit <= readable else y1 - half_h
    cx += z * tan * aspect * right  # the side panel covers the right of the canvas
    ox, oy = offset
    return (cx + ox, cy + oy, z), (cx + ox, cy + oy, 0.0)


def aim_camera(
    client: Any,
    pic: Picture,
    *,
    whole: bool,
    offset: tuple[float, float] = (0, 0),
    aspect: float = 1.6,
    right: float = 0.28,
) -> None:
    """Aim ``client``'s camera at ``pic``: the whole chart, or the default readable zoom
    (``aspect`` of the canvas, ``right``: the part of its width the side panel covers)."""
    position, look = camera_for(pic, offset=offset, whole=whole, aspect=aspect, right=right)
    try:
        cam = client.camera
        cam.position = position
        cam.look_at = look
        cam.up_direction = (0.0, 1.0, 0.0)
    except Exception:  # the page has not told its camera yet, or is gone
        return


def scale_px(z: float, fov: float = 1.309, height_px: float = 800.0) -> float:
    """Screen pixels per scene unit for a camera ``z`` above the chart."""
    return height_px / (2 * z * math.tan(fov / 2))
