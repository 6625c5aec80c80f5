"""A text image drawn as a mesh over its ink only: the chart's text tiles as glTF (GLB).

A tile (``web.view.glyphs.Tile``) is mostly transparent: the space between a step's name,
its action table and the next transition's condition. Drawn as one textured plane, every
one of its pixels is shaded and blended in every frame, which is what a page costs under
software WebGL (``bench/page.py``). :func:`tile_glb` instead cuts the tile's image into
``BLOCK`` × ``BLOCK`` pixel blocks and draws a quad only over the blocks that hold ink
(runs of them along a row merged), textured with those runs' pixels packed into a smaller
image (shelves of runs, transparent gutters between them): what shows is the same, pixel
for pixel, but the empty blocks cost nothing, neither per frame nor as texture memory.

The GLB holds one mesh whose material is unlit (``KHR_materials_unlit``, so no light
changes the black of the text), blended (``alphaMode: BLEND``) and two-sided; its image
is the packed PNG; the sampler is linear with mipmaps, as a textured plane's. Positions are
in scene units about the tile's centre, the chart's plane at z = 0 (glTF 2.0
specification, Khronos Group, sections 3.6 "Geometry", 3.8 "Texture Data" and 3.9
"Materials"; the extension's own page for ``KHR_materials_unlit``).
"""

from __future__ import annotations

import io
import json
import struct
from typing import Any

import numpy as np
from PIL import Image

from s7graph.web.view.glyphs import Tile

__all__ = ["BLOCK", "inked_runs", "lines_glb", "tile_glb"]

BLOCK = 32
"""The side of a block, in image pixels: a quad covers whole blocks that hold ink."""
GUTTER = 4
"""Transparent pixels between the packed runs of a tile's texture."""

_FLOAT, _UINT32 = 5126, 5125  # glTF component types
_ARRAY, _ELEMENTS = 34962, 34963  # buffer view targets
_LINEAR, _LINEAR_MIPMAP_LINEAR, _CLAMP = 9729, 9987, 33071
Run = tuple[int, int, int, int]  # x0, y0, x1, y1: image pixels, rows from the top


def inked_runs(alpha: Any, block: int = BLOCK) -> list[Run]:
    """The pixel rectangles that cover every non-zero pixel of ``alpha`` (rows from the
    top): its ``block``-square blocks that hold ink, consecutive ones of a row of blocks
    joined into one rectangle, each clipped to the image."""
    h, w = alpha.shape
    # each block's most opaque pixel (one pass over the image, the last blocks cut short)
    most = np.maximum.reduceat(alpha, np.arange(0, h, block), axis=0)
    inked: Any = np.maximum.reduceat(most, np.arange(0, w, block), axis=1) > 0
    runs: list[Run] = []
    for r in range(len(inked)):
        row = inked[r]
        # where runs of inked blocks start and end: the edges of a 0/1 sequence
        edges = np.flatnonzero(np.diff(np.concatenate(([0], row.astype(np.int8), [0]))))
        for start, end in zip(edges[::2], edges[1::2], strict=True):
            x0, x1 = int(start) * block, min(int(end) * block, w)
            y0, y1 = r * block, min((r + 1) * block, h)
            runs.append((x0, y0, x1, y1))
    return runs


def tile_glb(tile: Tile, block: int = BLOCK) -> bytes | None:
    """``tile`` as a GLB whose mesh covers the inked blocks of its image, centred on the
    tile's centre (place the node at ``(tile.cx, tile.cy, z)``); None if it has no ink."""
    alpha = tile.alpha  # rows from the top, as glTF reads them
    h, w = alpha.shape
    runs = inked_runs(alpha, block)
    if not runs:
        return None
    sx, sy = tile.width / w, tile.height / h  # scene units per pixel
    left, top = -tile.width / 2, tile.height / 2
    corners = np.array(
        [(x, y) for x0, y0, x1, y1 in runs for x, y in ((x0, y0), (x1, y0), (x1, y1), (x0, y1))],
        np.float64,
    )
    positions = np.zeros((len(corners), 3), np.float32)
    positions[:, 0] = left + corners[:, 0] * sx
    positions[:, 1] = top - corners[:, 1] * sy
    packed, places = _packed(alpha, runs, block)
    ah, aw = packed.shape
    sheet = np.zeros((ah, aw, 4), np.uint8)  # black, as opaque as the texts
    sheet[..., 3] = packed
    # each run's corners, moved to where the packing put the run
    moved = np.array(
        [(ax - x0, ay - y0) for (ax, ay), (x0, y0, _, _) in zip(places, runs, strict=True)],
        np.float64,
    )
    uvs = ((corners + np.repeat(moved, 4, axis=0)) / (aw, ah)).astype(np.float32)
    indices = _quads(len(runs), (0, 3, 2, 0, 2, 1))  # counter-clockwise seen from +z
    png = io.BytesIO()
    Image.fromarray(sheet, "RGBA").save(png, format="PNG", compress_level=1)
    return _glb(positions, uvs, indices, png.getvalue())


def _packed(image: Any, runs: list[Run], block: int) -> tuple[Any, list[tuple[int, int]]]:
    """The pixels of ``runs`` (each at most ``block`` high) packed into shelves, left to
    right, ``GUTTER`` transparent pixels between runs and between shelves (a mipmap blends
    transparency into a run's edge, never another run's ink), no wider than ``image``;
    the packed image and each run's top-left in it. If that is no lower than ``image``,
    the image itself and the runs where they are."""
    h, w = image.shape[:2]
    places: list[tuple[int, int]] = []
    x = y = 0
    for x0, _, x1, _ in runs:
        if x and x + (x1 - x0) > w:
            x, y = 0, y + block + GUTTER
        places.append((x, y))
        x += x1 - x0 + GUTTER
    height = y + block
    if height >= h:
        return image, [(x0, y0) for x0, y0, _, _ in runs]
    sheet = np.zeros((height, *image.shape[1:]), image.dtype)
    for (ax, ay), (x0, y0, x1, y1) in zip(places, runs, strict=True):
        sheet[ay : ay + y1 - y0, ax : ax + x1 - x0] = image[y0:y1, x0:x1]
    return sheet, places


def lines_glb(segments: Any, width: float, colour: tuple[int, int, int]) -> bytes | None:
    """``segments`` (n × 2 points, x and y used, z the first point's) as one opaque mesh of
    quads ``width`` scene units wide in ``colour`` (sRGB), each reaching ``width / 2`` past
    its ends so that corners close; None if there are none."""
    seg = np.asarray(segments, np.float64).reshape(-1, 2, 3)
    d = seg[:, 1, :2] - seg[:, 0, :2]
    length = np.hypot(d[:, 0], d[:, 1])
    seg, d, length = seg[length > 0], d[length > 0], length[length > 0]
    if not len(seg):
        return None
    along = d / length[:, None] * (width / 2)
    across = np.stack([-along[:, 1], along[:, 0]], axis=1)
    a, b = seg[:, 0, :2] - along, seg[:, 1, :2] + along
    corners = np.stack([a - across, b - across, b + across, a + across], axis=1)
    positions = np.zeros((len(seg) * 4, 3), np.float32)
    positions[:, :2] = corners.reshape(-1, 2)
    positions[:, 2] = np.repeat(seg[:, 0, 2], 4)
    return _glb(positions, None, _quads(len(seg), (0, 1, 2, 0, 2, 3)), None, colour)


def _quads(count: int, order: tuple[int, ...]) -> Any:
    """The triangle indices (uint32) of ``count`` quads of 4 vertices each, every quad's
    two triangles taking its corners in ``order``."""
    quad = np.array(order, np.uint32)
    return (np.arange(count, dtype=np.uint32)[:, None] * 4 + quad).ravel()


def _linear(channel: int) -> float:
    """An sRGB channel (0–255) as the linear value glTF's colour factors hold."""
    c = channel / 255
    return c / 12.92 if c <= 0.04045 else float(((c + 0.055) / 1.055) ** 2.4)


def _glb(
    positions: Any,
    uvs: Any,
    indices: Any,
    png: bytes | None,
    colour: tuple[int, int, int] | None = None,
) -> bytes:
    """One mesh of ``positions`` (float32 n × 3) and triangle ``indices`` (uint32): textured
    by ``png`` at ``uvs`` (float32 n × 2) and blended, or else opaque in ``colour``; the GLB
    container (header, JSON chunk, binary chunk)."""
    parts = [positions.tobytes(), indices.tobytes()]
    if png is not None:
        parts += [uvs.tobytes(), png]
    views, offset = [], 0
    for data in parts:
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": len(data)})
        offset += len(data) + (-len(data)) % 4
    views[0]["target"], views[1]["target"] = _ARRAY, _ELEMENTS
    accessors: list[dict[str, Any]] = [
        {
            "bufferView": 0,
            "componentType": _FLOAT,
            "count": len(positions),
            "type": "VEC3",
            "min": positions.min(axis=0).tolist(),
            "max": positions.max(axis=0).tolist(),
        },
        {"bufferView": 1, "componentType": _UINT32, "count": len(indices), "type": "SCALAR"},
    ]
    attributes = {"POSITION": 0}
    material: dict[str, Any] = {
        "doubleSided": True,
        "extensions": {"KHR_materials_unlit": {}},
    }
    textured: dict[str, Any] = {}
    if png is not None:
        views[2]["target"] = _ARRAY
        accessors.append(
            {"bufferView": 2, "componentType": _FLOAT, "count": len(uvs), "type": "VEC2"}
        )
        attributes["TEXCOORD_0"] = 2
        material["pbrMetallicRoughness"] = {
            "baseColorTexture": {"index": 0},
            "metallicFactor": 0.0,
            "roughnessFactor": 1.0,
        }
        material["alphaMode"] = "BLEND"
        textured = {
            "textures": [{"sampler": 0, "source": 0}],
            "samplers": [
                {
                    "magFilter": _LINEAR,
                    "minFilter": _LINEAR_MIPMAP_LINEAR,
                    "wrapS": _CLAMP,
                    "wrapT": _CLAMP,
                }
            ],
            "images": [{"bufferView": 3, "mimeType": "image/png"}],
        }
    else:
        rgb = colour if colour is not None else (0, 0, 0)
        material["pbrMetallicRoughness"] = {
            "baseColorFactor": [*(_linear(c) for c in rgb), 1.0],
            "metallicFactor": 0.0,
            "roughnessFactor": 1.0,
        }
    doc = {
        "asset": {"version": "2.0", "generator": "s7graph"},
        "extensionsUsed": ["KHR_materials_unlit"],
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": attributes, "indices": 1, "material": 0}]}],
        "materials": [material],
        **textured,
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": offset}],
    }
    binary = b"".join(data + b"\0" * ((-len(data)) % 4) for data in parts)
    text = json.dumps(doc, separators=(",", ":")).encode()
    text += b" " * ((-len(text)) % 4)
    total = 12 + 8 + len(text) + 8 + len(binary)
    return b"".join(
        (
            struct.pack("<4sII", b"glTF", 2, total),
            struct.pack("<I4s", len(text), b"JSON"),
            text,
            struct.pack("<I4s", len(binary), b"BIN\0"),
            binary,
        )
    )
