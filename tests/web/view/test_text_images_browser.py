"""The chart's text images reach a page that connects after they were drawn: the view keeps
no pixels of them (each is sent as a GLB, ``web.view.text_mesh``, its PNG inside), and
viser replays them to the new page from its own message buffer. A real viser server and a
real headless Chromium on loopback."""

from __future__ import annotations

import io
from typing import Any

import numpy as np
import pytest

from s7graph.web.view.chart_view import make_server
from s7graph.web.view.drawing import BOX_H, BOX_W, Drawing, camera_for
from tests.paths import EXAMPLES
from tests.web.helpers import chromium_page, needs_chromium, page_point, wait_until
from tests.web.view.test_glyphs import chart_picture

pytestmark = [pytest.mark.timeout(120), needs_chromium]
pytest.importorskip("playwright.sync_api", reason="playwright is not installed")


def _dark_pixels(png: bytes, box: tuple[int, int, int, int]) -> int:
    """Pixels of black text (every channel under 90) in ``box`` (left, top, right, bottom)."""
    from PIL import Image

    rgb = np.asarray(Image.open(io.BytesIO(png)).convert("RGB").crop(box)).astype(np.int16)
    return int(np.count_nonzero((rgb < 90).all(axis=-1)))


def test_a_page_that_connects_after_the_chart_was_drawn_shows_its_texts() -> None:
    pic = chart_picture((EXAMPLES / "drill" / "drill.s7g").read_text(), "drill.s7g")
    server, _ = make_server(port=0)
    try:
        server.scene.set_up_direction("+y")  # as the view's scene
        drawing = Drawing(server.scene, pic)
        meshes: list[Any] = [n for n in drawing._nodes if "/text" in n.name]
        assert len(meshes) == len(pic.tiles)  # each text image a mesh over its ink
        assert all(type(n).__name__ == "GlbHandle" for n in meshes)
        assert not any(type(n).__name__ == "ImageHandle" for n in drawing._nodes)
        cam = server.initial_camera
        cam.position, cam.look_at = camera_for(pic)
        cam.up = (0.0, 1.0, 0.0)
        with chromium_page(f"http://127.0.0.1:{server.get_port()}") as page:
            assert wait_until(lambda: len(server.get_clients()) == 1, 30)
            (client,) = server.get_clients().values()
            aimed = np.array(cam.position)
            assert wait_until(
                lambda: (
                    client.camera.image_height > 0
                    and np.allclose(client.camera.position, aimed, atol=1e-3)
                ),
                30,
            ), (client.camera.position, aimed)
            inside = []  # the middle of each step box: its name, and no frame line
            for x, y in pic.steps.values():
                left, top = page_point(client, x - BOX_W * 0.35, y + BOX_H * 0.3, page=page)
                right, bottom = page_point(client, x + BOX_W * 0.35, y - BOX_H * 0.3, page=page)
                inside.append((left, top, right, bottom))
            seen: list[int] = []

            def names_shown() -> bool:
                shot = page.screenshot()
                seen[:] = [_dark_pixels(shot, box) for box in inside]
                return all(n > 15 for n in seen)

            assert wait_until(names_shown, 60, poll=0.5), seen
    finally:
        server.stop()
