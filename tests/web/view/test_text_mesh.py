"""A text image as a mesh over its ink (``web.view.text_mesh``): the quads cover every
inked pixel and no block without ink; the GLB is what glTF 2.0 says (a header, a JSON and a
binary chunk) and maps each quad onto its own pixels of the image. Lines as one opaque
mesh of quads."""

from __future__ import annotations

import io
import json
import struct
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from PIL import Image

from s7graph.web.view.glyphs import TEXT_PX, Text, tiles
from s7graph.web.view.text_mesh import BLOCK, _packed, inked_runs, lines_glb, tile_glb
from tests.paths import EXAMPLES
from tests.web.view.test_glyphs import chart_picture


def covered(runs: list[tuple[int, int, int, int]], shape: tuple[int, int]) -> Any:
    mask = np.zeros(shape, np.int32)
    for x0, y0, x1, y1 in runs:
        mask[y0:y1, x0:x1] += 1
    return mask


@st.composite
def sparse_ink(draw: st.DrawFn) -> tuple[Any, int]:
    """An alpha image of up to 100 × 100 pixels with up to 60 inked dots, and a block size."""
    h, w = draw(st.integers(1, 100)), draw(st.integers(1, 100))
    dots = draw(st.lists(st.tuples(st.integers(0, 99), st.integers(0, 99)), max_size=60))
    alpha = np.zeros((h, w), np.uint8)
    for y, x in dots:
        alpha[y % h, x % w] = 128 + (x * 7 + y) % 128
    return alpha, draw(st.sampled_from([4, 8, 32]))


@settings(max_examples=60, deadline=None)
@given(sparse_ink())
def test_the_quads_cover_every_inked_pixel_once_and_only_inked_blocks(
    sample: tuple[Any, int],
) -> None:
    alpha, block = sample
    h, w = alpha.shape
    runs = inked_runs(alpha, block)
    mask = covered(runs, (h, w))
    assert mask.max(initial=0) <= 1  # no pixel drawn twice
    assert np.all(mask[alpha > 0] == 1)  # every inked pixel drawn
    for x0, y0, x1, y1 in runs:  # each block of a quad holds ink
        assert 0 <= x0 < x1 <= w and 0 <= y0 < y1 <= h
        for bx in range(x0, x1, block):
            assert alpha[y0:y1, bx : bx + block].any()


@settings(max_examples=60, deadline=None)
@given(sparse_ink())
def test_the_packed_texture_holds_each_run_whole_and_is_never_taller_than_the_image(
    sample: tuple[Any, int],
) -> None:
    """Each run's pixels are found at its place in the packed texture; nothing else there
    is ink; the texture is lower than the image, or else it is the image itself with the
    runs where they are."""
    alpha, block = sample
    h, w = alpha.shape
    image = np.zeros((h, w, 4), np.uint8)
    image[..., 3] = alpha
    runs = inked_runs(image[..., 3], block)
    sheet, places = _packed(image, runs, block)
    assert sheet.shape[1] == w and sheet.shape[0] <= h
    if sheet.shape[0] == h:  # packing would not have saved a row: the image itself
        assert sheet is image and places == [(x0, y0) for x0, y0, _, _ in runs]
    inked = np.zeros(sheet.shape[:2], bool)
    for (ax, ay), (x0, y0, x1, y1) in zip(places, runs, strict=True):
        assert np.array_equal(sheet[ay : ay + y1 - y0, ax : ax + x1 - x0], image[y0:y1, x0:x1])
        inked[ay : ay + y1 - y0, ax : ax + x1 - x0] = True
    assert not sheet[..., 3][~inked].any()


def test_an_image_inked_all_over_keeps_its_own_pixels() -> None:
    """Two full rows of blocks would pack into a taller texture (a gutter between the
    shelves): the image is used as it is."""
    image = np.full((2 * BLOCK, 2 * BLOCK, 4), 255, np.uint8)
    runs = inked_runs(image[..., 3])
    sheet, places = _packed(image, runs, BLOCK)
    assert sheet is image and places == [(0, 0), (0, BLOCK)]


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
        (primitive,) = doc["meshes"][0]["primitives"]
        attributes = primitive["attributes"]
        pos = view(doc, binary, attributes["POSITION"], np.float32, 3)
        uv = view(doc, binary, attributes["TEXCOORD_0"], np.float32, 2)
        idx = np.frombuffer(view(doc, binary, primitive["indices"], np.uint32, 1), np.uint32)
        image_bv = doc["bufferViews"][doc["images"][0]["bufferView"]]
        png = binary[image_bv["byteOffset"] : image_bv["byteOffset"] + image_bv["byteLength"]]
        sheet = np.asarray(Image.open(io.BytesIO(png)))
        h, w = tile.alpha.shape  # the tile's pixels, top row first: black, its opacity
        image = np.zeros((h, w, 4), np.uint8)
        image[..., 3] = tile.alpha
        sh, sw = sheet.shape[:2]
        assert sh < h and sw <= w  # the texture holds the inked runs only, packed
        assert len(idx) % 6 == 0 and idx.max() < len(pos) and np.all(pos[:, 2] == 0)
        assert tile.scale == TEXT_PX
        # each quad: where it lies on the tile (pixels), and its texture's pixels
        at = np.stack(
            [
                (pos[:, 0] + tile.width / 2) * w / tile.width,
                (tile.height / 2 - pos[:, 1]) * h / tile.height,
            ],
            axis=1,
        )
        tex = uv * (sw, sh)
        runs = []
        for q in range(len(pos) // 4):
            (x0, y0), (x1, y1) = np.round(at[4 * q]), np.round(at[4 * q + 2])
            (u0, v0), (u1, v1) = np.round(tex[4 * q]), np.round(tex[4 * q + 2])
            assert np.allclose(at[4 * q : 4 * q + 4], np.round(at[4 * q : 4 * q + 4]), atol=1e-3)
            x0, y0, x1, y1, u0, v0, u1, v1 = (int(v) for v in (x0, y0, x1, y1, u0, v0, u1, v1))
            assert np.array_equal(sheet[v0:v1, u0:u1], image[y0:y1, x0:x1])  # its own pixels
            runs.append((x0, y0, x1, y1))
        mask = covered(runs, (h, w))
        assert np.all(mask[image[..., 3] > 0] == 1)  # every inked pixel on a quad, once
        assert mask.sum() < 0.6 * w * h  # and much of the empty space left out
        assert len(runs) <= -(-h // BLOCK) * -(-w // BLOCK)
        # between packed runs only transparent pixels: a mipmap blends in no other run
        owned = covered(
            [
                (int(u0), int(v0), int(u1), int(v1))
                for u0, v0, u1, v1 in (
                    np.round(np.r_[tex[4 * q], tex[4 * q + 2]]) for q in range(len(runs))
                )
            ],
            (sh, sw),
        )
        assert owned.max() == 1 and not sheet[owned == 0, 3].any()


def test_lines_are_one_opaque_mesh_of_quads_that_close_at_the_corners() -> None:
    """A step box's four lines: four quads of the given width, each reaching half of it
    past its ends (the corners are closed), opaque in the ink's colour."""
    box = [
        [[0.0, 0.0, 0.03], [2.0, 0.0, 0.03]],
        [[2.0, 0.0, 0.03], [2.0, 1.0, 0.03]],
        [[2.0, 1.0, 0.03], [0.0, 1.0, 0.03]],
        [[0.0, 1.0, 0.03], [0.0, 0.0, 0.03]],
        [[5.0, 5.0, 0.03], [5.0, 5.0, 0.03]],  # no length: nothing drawn
    ]
    data = lines_glb(np.array(box, np.float32), 0.1, (30, 30, 30))
    assert data is not None
    doc, binary = read_glb(data)
    (material,) = doc["materials"]
    assert material.get("alphaMode", "OPAQUE") == "OPAQUE" and "images" not in doc
    r, g, b, a = material["pbrMetallicRoughness"]["baseColorFactor"]
    assert r == g == b == pytest.approx(0.0130, abs=1e-3) and a == 1.0  # sRGB 30, linear
    (primitive,) = doc["meshes"][0]["primitives"]
    pos = view(doc, binary, primitive["attributes"]["POSITION"], np.float32, 3)
    assert len(pos) == 16 and np.allclose(pos[:, 2], 0.03)
    xs, ys = pos[:, 0], pos[:, 1]
    assert xs.min() == pytest.approx(-0.05) and xs.max() == pytest.approx(2.05)
    assert ys.min() == pytest.approx(-0.05) and ys.max() == pytest.approx(1.05)
    first = pos[:4, :2]  # the bottom line: 2.1 long, 0.1 wide
    assert np.ptp(first[:, 0]) == pytest.approx(2.1) and np.ptp(first[:, 1]) == pytest.approx(0.1)
    assert lines_glb(np.zeros((0, 2, 3), np.float32), 0.1, (0, 0, 0)) is None
