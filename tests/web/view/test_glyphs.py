"""The chart's texts as images (``web.view.glyphs.tiles``): every image at most 2048 pixels
square and made only where there is text; all of a chart's images within a pixel budget,
at fewer pixels per scene unit when its texts need more, in the same place and size in the
scene; a small chart's texts pixel for pixel as one image of the whole chart shows them."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from PIL import Image, ImageDraw, ImageFont

from bench.big_charts import huge_chart
from s7graph.sequencer.text.parse import parse_chart
from s7graph.web.bus.protocol import ChartLayout
from s7graph.web.view import glyphs
from s7graph.web.view.drawing import Picture, picture
from s7graph.web.view.glyphs import BUDGET_PX, LINE, TEXT_PX, TILE_PX, Text, Tile, tiles
from s7graph.web.view.layout import place
from tests.paths import EXAMPLES

pytestmark = pytest.mark.timeout(240)

CHARTS = sorted(EXAMPLES.glob("*/*.s7g"))


def chart_picture(source: str, name: str = "chart.s7g") -> Picture:
    return picture(place(ChartLayout.from_chart(parse_chart(source, name), version=1)))


def texts_of(tiles_: Sequence[Tile]) -> list[Text]:
    """Every text once, in the order drawn."""
    seen: dict[int, Text] = {}
    for tile in tiles_:
        for t in tile.texts:
            seen.setdefault(id(t), t)
    return list(seen.values())


def one_image(
    texts: list[Text], scale: float, frame: list[Text] | None = None
) -> tuple[Any, float, float]:
    """All ``texts`` on one image of the whole chart (as the view drew them before its
    images were bounded; as large as the texts ``frame``, default ``texts``), top row first,
    and the scene x, y of its top-left corner."""
    frame = texts if frame is None else frame
    x0 = min(t.x for t in frame) - 0.1
    x1 = max(t.x + t.width for t in frame) + 0.1
    y1 = max(t.y for t in frame) + 0.1
    y0 = min(t.y - t.height for t in frame) - 0.1
    image = Image.new("RGBA", (round((x1 - x0) * scale) + 2, round((y1 - y0) * scale) + 2))
    draw = ImageDraw.Draw(image)
    for t in texts:
        font = ImageFont.load_default(size=max(round(t.size * scale), 1))
        for i, line in enumerate(t.lines):
            at = ((t.x - x0) * scale, (y1 - t.y + i * t.size * LINE) * scale)
            draw.text(at, line, font=font, fill=(0, 0, 0, 255))
    return np.asarray(image), x0, y1


def pasted(tiles_: Sequence[Tile], shape: tuple[int, ...], x0: float, y1: float) -> Any:
    """The opacity of ``tiles_`` laid over each other where the scene shows them, on an
    image of ``shape`` whose top-left is the scene point ``(x0, y1)``."""
    alpha = np.zeros(shape[:2], np.float64)
    for tile in tiles_:
        scale = tile.scale
        image = tile.alpha  # top row first
        h, w = image.shape
        assert (w, h) == (round(tile.width * scale), round(tile.height * scale))
        left = (tile.cx - tile.width / 2 - x0) * scale
        top = (y1 - tile.cy - tile.height / 2) * scale
        assert abs(left - round(left)) < 1e-6 and abs(top - round(top)) < 1e-6  # on the grid
        kx, ky = round(left), round(top)
        region = alpha[ky : ky + h, kx : kx + w]
        a = image[: region.shape[0], : region.shape[1]] / 255
        region[...] = a + region * (1 - a)  # one over the other
    return np.round(alpha * 255).astype(np.uint8)


@pytest.mark.parametrize("path", CHARTS, ids=[p.stem for p in CHARTS])
def test_a_small_charts_texts_are_drawn_as_before_pixel_for_pixel(path: Path) -> None:
    pic = chart_picture(path.read_text(), path.name)
    assert pic.tiles and all(t.scale == TEXT_PX for t in pic.tiles)  # the size it had
    assert all(w <= TILE_PX and h <= TILE_PX for w, h in (t.px for t in pic.tiles))
    texts = texts_of(pic.tiles)
    whole, x0, y1 = one_image(texts, TEXT_PX)
    assert np.array_equal(pasted(pic.tiles, whole.shape, x0, y1), whole[..., 3])


def test_the_drill_is_one_image_of_its_transitions_texts_and_one_of_the_rest() -> None:
    """The texts a click means something on (``Text.click``: the transitions') never share
    an image with the others, which let a click through to what lies under them."""
    pic = chart_picture((EXAMPLES / "drill" / "drill.s7g").read_text(), "drill.s7g")
    rest, transitions = pic.tiles
    assert not rest.click and all(not t.click for t in rest.texts)
    assert transitions.click and all(t.click for t in transitions.texts)
    assert {t.lines[0].split()[0] for t in transitions.texts} == {f"T{n}" for n in range(1, 9)}
    assert any(t.lines[0].startswith("S1 ") for t in rest.texts)  # a step's name


def test_a_text_wider_and_higher_than_an_image_is_cut_and_its_parts_join() -> None:
    long = Text(("W" * 300,) * 3, 0.0, 0.0, 0.3)  # about 5,000 pixels wide
    tall = Text(tuple(f"line {i}" for i in range(90)), 0.0, -2.0, 0.25)  # 2,500 high
    out = tiles([long, tall, Text(("far away",), 400.0, -300.0, 0.2)])
    sizes = [t.px for t in out]
    assert len(out) > 4 and all(w <= TILE_PX and h <= TILE_PX for w, h in sizes)
    assert sum(w * h for w, h in sizes) < 0.5 * 400 * 300 * TEXT_PX**2  # empty area: nothing
    near = [t for t in out if t.cx < 100]
    whole, x0, y1 = one_image([long, tall], TEXT_PX)
    assert np.array_equal(pasted(near, whole.shape, x0, y1), whole[..., 3])


def one_per_cell(texts: list[Text], scale: float) -> int:
    """The pixels of ``texts``' images with one image per cell (no kinds apart), which the
    budget bounds, at ``scale`` (the images of both kinds overlap; only their ink reaches
    the page)."""
    union = tiles([dataclasses.replace(t, click=False) for t in texts])
    assert all(t.scale == pytest.approx(scale) for t in union)
    return sum(w * h for w, h in (t.px for t in union))


def test_texts_over_the_budget_are_drawn_smaller_in_the_same_place(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    pic = chart_picture((EXAMPLES / "drill" / "drill.s7g").read_text(), "drill.s7g")
    texts = texts_of(pic.tiles)
    monkeypatch.setattr(glyphs, "BUDGET_PX", 400_000)  # the drill needs 1.5 Mpx
    out = tiles(texts)
    scale = out[0].scale
    assert scale < TEXT_PX * 0.6 and all(t.scale == scale for t in out)
    assert one_per_cell(texts, scale) <= 400_000
    assert len(out) == len(pic.tiles)  # the same place: each covers what it covered, its
    for tile, before in zip(out, pic.tiles, strict=True):  # top-left where it was, and
        # reaches as far as the rounded font sizes' lines do (a little wider than before)
        left, top = tile.cx - tile.width / 2, tile.cy + tile.height / 2
        assert (left, top) == pytest.approx(
            (before.cx - before.width / 2, before.cy + before.height / 2), abs=1 / scale
        )
        assert tile.height == pytest.approx(before.height, abs=1 / scale)
        assert before.width - 1 / scale <= tile.width <= before.width * 1.1
    for click in (False, True):  # each kind's images hold its texts as one image would
        whole, x0, y1 = one_image([t for t in texts if t.click is click], scale, texts)
        kind = [t for t in out if t.click is click]
        assert np.array_equal(pasted(kind, whole.shape, x0, y1), whole[..., 3])


def test_the_huge_charts_texts_stay_within_the_budget_in_images_of_2048_square() -> None:
    pic = chart_picture(huge_chart())
    sizes = [t.px for t in pic.tiles]
    assert all(w <= TILE_PX and h <= TILE_PX for w, h in sizes)
    scale = pic.tiles[0].scale
    assert scale < TEXT_PX / 2 and all(t.scale == scale for t in pic.tiles)
    assert one_per_cell(texts_of(pic.tiles), scale) <= BUDGET_PX
    for tile in pic.tiles[:: max(len(pic.tiles) // 5, 1)]:  # a few: rendering takes time
        w, h = tile.px
        alpha = tile.alpha
        assert alpha.shape == (h, w) and np.count_nonzero(alpha) > 0.01 * w * h
    texts = texts_of(pic.tiles)
    placed = {  # each text on an image that covers where it starts, in scene units
        id(t)
        for tile in pic.tiles
        for t in tile.texts
        if abs(t.x - tile.cx) <= tile.width / 2 and abs(t.y - tile.cy) <= tile.height / 2
    }
    assert placed == {id(t) for t in texts}
    assert len(texts) > 60_000
    right = max(t.cx + t.width / 2 for t in pic.tiles)  # the widest line as rendered, + 0.1
    assert right == pytest.approx(max(glyphs._box(t, scale)[1] for t in texts), abs=1 / scale)
    assert right >= max(t.x + t.width for t in texts) + 0.1 - 1 / scale
