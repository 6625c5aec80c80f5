"""Text on the chart, as images: how wide a text is, how it wraps, and the images it is
rendered into (``web.view.drawing``'s bands of static text, ``web.view.status_layer``'s
live values).

Texts are rendered with Pillow into images, not drawn as viser labels: a label costs software
WebGL far more per frame than a textured plane. A scene unit is ``TEXT_PX`` image pixels;
a line is ``LINE`` times its text height.
"""

from __future__ import annotations

import functools
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np
from PIL import Image, ImageDraw, ImageFont

__all__ = [
    "BAND_PX",
    "LINE",
    "TEXT_PX",
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
BAND_PX = 2048  # the widest text image (WebGL textures stay small)


@functools.cache
def _font(px: int) -> ImageFont.FreeTypeFont | ImageFont.ImageFont:
    return ImageFont.load_default(size=max(px, 6))


def text_width(text: str, size: float) -> float:
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
    """Lines of text at a place of the chart: ``x`` its left, ``y`` its top."""

    lines: tuple[str, ...]
    x: float
    y: float
    size: float

    @property
    def width(self) -> float:
        return max((text_width(line, self.size) for line in self.lines), default=0.0)

    @property
    def height(self) -> float:
        return self.size * LINE * len(self.lines)


@dataclass(frozen=True, slots=True)
class Tile:
    """An image of texts: RGBA pixels (rows bottom-up), its size and centre in scene units."""

    image: Any
    width: float
    height: float
    cx: float
    cy: float


def tiles(items: list[Text]) -> list[Tile]:
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
    x0 = min(t.x for t in items) - 0.1
    x1 = max(t.x + t.width for t in items) + 0.1
    y1 = max(t.y for t in items) + 0.1
    y0 = min(t.y - t.height for t in items) - 0.1
    size = (max(round((x1 - x0) * TEXT_PX), 1), max(round((y1 - y0) * TEXT_PX), 1))
    image = Image.new("RGBA", size, (0, 0, 0, 0))  # black: filtering blends no white in
    draw = ImageDraw.Draw(image)
    for t in items:
        font = _font(round(t.size * TEXT_PX))
        for i, line in enumerate(t.lines):
            px = (t.x - x0) * TEXT_PX
            py = (y1 - t.y + i * t.size * LINE) * TEXT_PX
            draw.text((px, py), line, font=font, fill=(0, 0, 0, 255))
    pixels = np.ascontiguousarray(np.asarray(image)[::-1])  # the plane shows rows bottom-up
    return Tile(pixels, x1 - x0, y1 - y0, (x0 + x1) / 2, (y0 + y1) / 2)


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
