"""Text on the chart, as images: how wide a text is, how it wraps, and the images it is
rendered into (``web.view.drawing``'s tiles of static text, ``web.view.status_layer``'s
live values).

Texts are rendered with Pillow into images, not drawn as viser labels: a label costs software
WebGL far more per frame than a textured plane. A scene unit is ``TEXT_PX`` image pixels
(fewer for a chart whose texts would exceed ``BUDGET_PX``); a line is ``LINE`` times its
text height.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np
from PIL import Image, ImageDraw, ImageFont

__all__ = [
    "BUDGET_PX",
    "LINE",
    "TEXT_PX",
    "TILE_PX",
    "Text",
    "Tile",
    "fit_text",
    "label_image",
    "line_starts",
    "text_width",
    "tiles",
    "wrap",
]

Rgb = tuple[int, int, int]
LINE = 1.25  # line height / text height
TEXT_PX = 90  # text image pixels per scene unit


@functools.cache
def _font(px: int) -> ImageFont.FreeTypeFont | ImageFont.ImageFont:
    return ImageFont.load_default(size=max(px, 1))


@functools.lru_cache(maxsize=1 << 16)
def _length(px: int, line: str) -> float:
    """The width in pixels of ``line`` at ``px`` pixels high (a chart repeats its names: of
    the 66,000 lines of a 1,000-step chart, 4,000 differ)."""
    return float(_font(px).getlength(line))


def text_width(text: str, size: float) -> float:
    """The width of ``text`` in scene units at text height ``size``."""
    return _length(max(round(size * TEXT_PX), 6), text) / TEXT_PX


def wrap(text: str, width: float, size: float) -> list[str]:
    """``text`` in lines no wider than ``width`` at ``size``: broken at blanks, a word too
    long for a line broken inside; every character kept (line breaks start new lines)."""
    lines: list[str] = []
    for para in text.split("\n"):
        line = ""
        for word in para.split(" "):
            candidate = f"{line} {word}" if line else word
            if text_width(candidate, size) <= width:
                line = candidate
                continue
            if line:
                lines.append(line)
            line = ""
            while word and text_width(word, size) > width:
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
        if text_width(word[:mid], size) <= width:
            lo = mid
        else:
            hi = mid - 1
    return lo


def line_starts(text: str, lines: list[str]) -> list[int]:
    """Where each line of ``wrap(text, …)`` starts in ``text`` (a line of one paragraph of
    single blanks is a slice of it; the blank at a break belongs to no line)."""
    starts, at = [], 0
    for line in lines:
        found = text.find(line, at) if line else at
        at = found if found >= 0 else at
        starts.append(at)
        at += len(line)
    return starts


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


@dataclass(frozen=True, slots=True)
class Text:
    """Lines of text at a place of the chart: ``x`` its left, ``y`` its top. ``click``: a
    click on it means something of its own (a transition's name and condition); its image
    then takes clicks and holds no other text, while the rest let a click through to what
    lies under them (a step's name to its box)."""

    lines: tuple[str, ...]
    x: float
    y: float
    size: float
    click: bool = False

    @property
    def width(self) -> float:
        return max((text_width(line, self.size) for line in self.lines), default=0.0)

    @property
    def height(self) -> float:
        return self.size * LINE * len(self.lines)


@dataclass(frozen=True, slots=True)
class Tile:
    """Texts on one transparent image: its size and centre in scene units, ``scale`` image
    pixels per scene unit. The pixels are rendered when ``alpha`` is read, every time: a
    picture keeps its texts, not their pixels."""

    texts: tuple[Text, ...]
    width: float
    height: float
    cx: float
    cy: float
    scale: float
    origin: tuple[float, float]  # scene x, y of the chart's text grid (top-left)
    offset: tuple[int, int]  # this image's top-left pixel on that grid

    @property
    def click(self) -> bool:
        """Whether the image takes clicks (its texts are the clickable ones, ``Text.click``)."""
        return any(t.click for t in self.texts)

    @property
    def px(self) -> tuple[int, int]:
        """The image's width and height in pixels."""
        return max(round(self.width * self.scale), 1), max(round(self.height * self.scale), 1)

    @property
    def alpha(self) -> Any:
        """The texts' opacity (their colour is black): rows from the top, as glTF reads a
        texture; read-only."""
        return _render(self)


TILE_PX = 2048
"""The widest and highest text image: the least ``MAX_TEXTURE_SIZE`` that OpenGL ES 3.0,
and so WebGL 2, guarantees (larger textures fail on small implementations and cost
software WebGL memory and frame time)."""
CELL_PX = 1536
"""A text belongs to the square cell of this many pixels where it starts; its image is
cropped to the cell's texts, which may reach ``TILE_PX - CELL_PX`` beyond it (a longer
reach is cut into more images)."""
BUDGET_PX = 48_000_000
"""The most pixels a chart's text images may have in all, counted as one image per cell
(the images of the two kinds of text overlap there, and only their inked blocks reach the
page); a chart whose texts need more is rendered at fewer pixels per scene unit
(``Tile.scale``), its scene size the same. 48 Mpx would be 192 MB of RGBA textures in the
page if every pixel held ink, whatever the chart. It keeps charts of a few
hundred steps at ``TEXT_PX`` (a 250-step loop needs 15 Mpx, the drill 1.5) and a loop of
1,000 steps with an action each (99 Mpx) at 59 pixels per unit — still more than the
default zoom shows (``READABLE_PX``, 55); 1,000 steps of 31 action rows each (627 Mpx at
``TEXT_PX``: 2.5 GB) get 24, sharp only when zoomed out."""

_Box = tuple[float, float, float, float]  # x0, x1 (left, right), y0, y1 (bottom, top)


def tiles(items: list[Text]) -> list[Tile]:
    """``items`` rendered onto transparent images of at most ``TILE_PX`` square, one per
    cell of the chart that has texts (a text belongs to the cell where it starts) and per
    kind of text (clickable or not, ``Text.click``), each cropped to its texts; at
    ``TEXT_PX`` pixels per scene unit, or fewer when one image per cell would need more
    than ``BUDGET_PX`` pixels in all (the kinds' images overlap, but only their inked
    blocks reach the page: ``web.view.text_mesh``)."""
    if not items:
        return []
    origin = (min(t.x for t in items) - 0.1, max(t.y for t in items) + 0.1)  # as _box's
    scale = float(TEXT_PX)
    while True:
        boxes = [_box(t, scale) for t in items]
        total = sum(w * h for w, h in (t.px for t in _layout(items, boxes, origin, scale)))
        if total <= BUDGET_PX:
            return _layout(items, boxes, origin, scale, kinds=True)
        scale *= min(0.95, (BUDGET_PX / total) ** 0.5)


def _box(t: Text, scale: float = TEXT_PX) -> _Box:
    """Where ``t``'s image must reach at ``scale`` pixels per unit: its lines and 0.1
    around. Below ``TEXT_PX`` a line may be wider than ``t.width``: its font's pixel size
    is rounded (``_render``), and so its glyphs' widths."""
    width = t.width
    if scale != TEXT_PX:
        px = round(t.size * scale)
        width = max(width, max((_length(px, line) for line in t.lines), default=0.0) / scale)
    return t.x - 0.1, t.x + width + 0.1, t.y - t.height - 0.1, t.y + 0.1


def _layout(
    items: list[Text],
    boxes: list[_Box],
    origin: tuple[float, float],
    scale: float,
    *,
    kinds: bool = False,
) -> list[Tile]:
    """The images of ``items`` at ``scale``: one per cell (``kinds``: per cell and kind)."""
    ox, oy = origin
    cell = CELL_PX / scale
    cells: dict[tuple[int, int, bool], list[int]] = {}
    for i, t in enumerate(items):
        key = (int((t.x - ox) // cell), int((oy - t.y) // cell), kinds and t.click)
        cells.setdefault(key, []).append(i)
    out: list[Tile] = []
    for _, members in sorted(cells.items()):
        out += _cut(items, boxes, members, origin, scale)
    return out


def _cut(
    items: list[Text],
    boxes: list[_Box],
    members: list[int],
    origin: tuple[float, float],
    scale: float,
) -> list[Tile]:
    """The image of one cell's texts (``members``), cut into pieces when it is larger than
    ``TILE_PX``, each piece cropped to the texts that reach into it."""
    tile = _tile(items, boxes, members, origin, scale)
    w, h = tile.px
    if w <= TILE_PX and h <= TILE_PX:
        return [tile]
    ox, oy = origin
    kx, ky = tile.offset
    nx, ny = -(-w // TILE_PX), -(-h // TILE_PX)
    out: list[Tile] = []
    for j in range(ny):
        for i in range(nx):
            x0, x1 = kx + w * i // nx, kx + w * (i + 1) // nx  # pixels on the grid
            y0, y1 = ky + h * j // ny, ky + h * (j + 1) // ny
            inside = [
                m
                for m in members
                if (boxes[m][0] - ox) * scale < x1
                and (boxes[m][1] - ox) * scale > x0
                and (oy - boxes[m][3]) * scale < y1
                and (oy - boxes[m][2]) * scale > y0
            ]
            if inside:
                out.append(_piece(items, boxes, inside, origin, scale, (x0, x1, y0, y1)))
    return out


def _tile(
    items: list[Text],
    boxes: list[_Box],
    members: list[int],
    origin: tuple[float, float],
    scale: float,
) -> Tile:
    """The texts ``members`` on one image cropped to them, its top-left on the pixel grid."""
    ox, oy = origin
    kx = math.floor((min(boxes[m][0] for m in members) - ox) * scale)
    ky = math.floor((oy - max(boxes[m][3] for m in members)) * scale)
    left, top = ox + kx / scale, oy - ky / scale
    width = max(boxes[m][1] for m in members) - left
    height = top - min(boxes[m][2] for m in members)
    texts = tuple(items[m] for m in members)
    return Tile(texts, width, height, left + width / 2, top - height / 2, scale, origin, (kx, ky))


def _piece(
    items: list[Text],
    boxes: list[_Box],
    members: list[int],
    origin: tuple[float, float],
    scale: float,
    pixels: tuple[int, int, int, int],
) -> Tile:
    """The part ``pixels`` (x0, x1, y0, y1 on the grid) of the image of ``members``,
    cropped to where they reach."""
    ox, oy = origin
    x0, x1, y0, y1 = pixels
    x0 = max(x0, math.floor((min(boxes[m][0] for m in members) - ox) * scale))
    y0 = max(y0, math.floor((oy - max(boxes[m][3] for m in members)) * scale))
    x1 = min(x1, math.ceil((max(boxes[m][1] for m in members) - ox) * scale))
    y1 = min(y1, math.ceil((oy - min(boxes[m][2] for m in members)) * scale))
    left, top = ox + x0 / scale, oy - y0 / scale
    width, height = (x1 - x0) / scale, (y1 - y0) / scale
    texts = tuple(items[m] for m in members)
    return Tile(texts, width, height, left + width / 2, top - height / 2, scale, origin, (x0, y0))


def _render(tile: Tile) -> Any:
    """The opacity of ``tile``'s texts (``Tile.alpha``), rows from the top; each text drawn
    where it stands on the chart's pixel grid, so that texts cut across images join."""
    image = Image.new("L", tile.px, 0)
    draw = ImageDraw.Draw(image)
    (ox, oy), (kx, ky), s = tile.origin, tile.offset, tile.scale
    for t in tile.texts:
        font = _font(round(t.size * s))  # below 6 px too: a text keeps its place and width
        for i, line in enumerate(t.lines):
            px = (t.x - ox) * s - kx
            py = (oy - t.y + i * t.size * LINE) * s - ky
            draw.text((px, py), line, font=font, fill=255)
    return np.asarray(image)


def label_image(lines: list[str], size: float, width: float, background: Rgb) -> Any:
    """``lines`` in black on ``background``, an image ``width`` scene units wide and as high
    as the lines (a live value, a step's times); RGBA rows bottom-up."""
    w = max(round(width * TEXT_PX), 1)
    h = max(round(size * LINE * len(lines) * TEXT_PX), 1)
    image = Image.new("RGBA", (w, h), (*background, 255))
    draw = ImageDraw.Draw(image)
    font = _font(round(size * TEXT_PX))
    pad = round(0.04 * TEXT_PX)
    for i, line in enumerate(lines):
        draw.text((pad, i * size * LINE * TEXT_PX), line, font=font, fill=(0, 0, 0, 255))
    return np.ascontiguousarray(np.asarray(image)[::-1])
