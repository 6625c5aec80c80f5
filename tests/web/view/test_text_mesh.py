"""A text image as a mesh over its ink (``web.view.text_mesh``): the quads cover every
inked pixel and no block without ink; the GLB is what glTF 2.0 says (a header, a JSON and a
binary chunk) and maps each quad onto its own pixels of the image."""

from __future__ import annotations

import io
import json
import struct
from typing import Any

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from PIL import Image

from s7graph.web.view.glyphs import TEXT_PX, Text, tiles
from s7graph.web.view.text_mesh import BLOCK, inked_runs, tile_glb
from tests.paths import EXAMPLES
from tests.web.view.test_glyphs import chart_picture


def covered(runs: list[tuple[int, int, int, int]], shape: tuple[int, int]) -> Any:
    mask = np.zeros(shape, np.int32)
    for x0, y0, x1, y1 in runs:
        mask[y0:y1, x0:x1] += 1
    return mask


@settings(max_examples=60, deadline=None)
@given(
    h=st.integers(1, 100),
    w=st.integers(1, 100),
    block=st.sampled_from([4, 8, 32]),
    dots=st.lists(st.tuples(st.integers(0, 99), st.integers(0, 99)), max_size=40),
)
def test_the_quads_cover_every_inked_pixel_once_and_only_inked_blocks(
    h: int, w: int, block: int, dots: list[tuple[int, int]]
) -> None:
    alpha = np.zeros((h, w), np.uint8)
    for y, x in dots:
        alpha[y % h, x % w] = 255
    runs = inked_runs(alpha, block)
    mask = covered(runs, (h, w))
    assert mask.max(initial=0) <= 1  # no pixel drawn twice
    assert np.all(mask[alpha > 0] == 1)  # every inked pixel drawn
    for x0, y0, x1, y1 in runs:  # each block of a quad holds ink
        assert 0 <= x0 < x1 <= w and 0 <= y0 < y1 <= h
        for bx in range(x0, x1, block):
            assert alpha[y0:y1, bx : bx + block].any()


def test_an_image_without_ink_has_no_mesh() -> None:
    assert inked_runs(np.zeros((40, 70), np.uint8)) == []
    (tile,) = tiles([Text(("",), 0.0, 0.0, 0.2)])
    assert tile_glb(tile) is None


def read_glb(data: bytes) -> tuple[dict[str, Any], bytes]:
    magic, version, total = struct.unpack_from("<4sII", data, 0)
    assert (magic, version, total) == (b"glTF", 2, len(data))
    n, kind = struct.unpack_from("<I4s", data, 12)
    assert kind == b"JSON" and n % 4 == 0
    doc = json.loads(data[20 : 20 + n])
    m, kind = struct.unpack_from("<I4s", data, 20 + n)
    assert kind == b"BIN\0" and m % 4 == 0 and 28 + n + m == len(data)
    return doc, data[28 + n : 28 + n + m]


def view(doc: dict[str, Any], binary: bytes, accessor: int, dtype: Any, width: int) -> Any:
    acc = doc["accessors"][accessor]
    bv = doc["bufferViews"][acc["bufferView"]]
    raw = binary[bv["byteOffset"] : bv["byteOffset"] + bv["byteLength"]]
    return np.frombuffer(raw, dtype).reshape(acc["count"], width) if width > 1 else raw


def test_the_drills_texts_are_meshes_that_show_their_own_pixels() -> None:
    pic = chart_picture((EXAMPLES / "drill" / "drill.s7g").read_text(), "drill.s7g")
    for tile in pic.tiles:
        data = tile_glb(tile)
        assert data is not None
        doc, binary = read_glb(data)
        (material,) = doc["materials"]
        assert material["alphaMode"] == "BLEND" and "KHR_materials_unlit" in material["extensions"]
        pos = np.frombuffer(view(doc, binary, 0, np.float32, 3).tobytes(), np.float32).reshape(
            -1, 3
        )
        uv = np.frombuffer(view(doc, binary, 1, np.float32, 2).tobytes(), np.float32).reshape(-1, 2)
        idx = np.frombuffer(view(doc, binary, 2, np.uint32, 1), np.uint32)
        image_bv = doc["bufferViews"][doc["images"][0]["bufferView"]]
        png = binary[image_bv["byteOffset"] : image_bv["byteOffset"] + image_bv["byteLength"]]
        image = np.asarray(Image.open(io.BytesIO(png)))
        assert np.array_equal(image, tile.image[::-1])  # the tile's own pixels, top row first
        h, w = image.shape[:2]
        assert len(idx) % 6 == 0 and idx.max() < len(pos) and np.all(pos[:, 2] == 0)
        # each corner's texture pixel is where the corner lies on the tile, at TEXT_PX
        px = uv * (w, h)
        x = -tile.width / 2 + px[:, 0] * tile.width / w
        y = tile.height / 2 - px[:, 1] * tile.height / h
        assert np.allclose(pos[:, 0], x, atol=1e-4) and np.allclose(pos[:, 1], y, atol=1e-4)
        assert tile.scale == TEXT_PX
        runs = [
            (round(a[0]), round(a[1]), round(c[0]), round(c[1]))
            for a, c in zip(px[0::4], px[2::4], strict=True)
        ]
        mask = covered(runs, (h, w))
        assert np.all(mask[image[..., 3] > 0] == 1)  # every inked pixel on a quad, once
        assert mask.sum() < 0.6 * w * h  # and much of the empty space left out
        assert len(runs) <= -(-h // BLOCK) * -(-w // BLOCK)
