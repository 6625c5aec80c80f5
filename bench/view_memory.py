"""The view process's memory for a huge chart: the 1,000-step chart of
``bench/big_charts.py`` placed, its picture built and drawn into a real viser server (on
127.0.0.1, a free port, no page), with the process's resident memory after each stage and
its peak (``VmRSS`` / ``VmHWM`` of ``/proc/self/status``, Linux) and the text images' sizes;
with ``--browser``, then a headless Chromium (``bench/page.py``'s, software WebGL) shown the
whole chart, and the memory of its processes (their PSS, each second, until it has not moved
by 5 MB for 10 s, at most 75 s).

    python bench/view_memory.py            # the huge chart (about 30 s)
    python bench/view_memory.py --browser  # and a page showing it (up to 75 s more)
    python bench/view_memory.py --chart examples/drill/drill.s7g
"""

from __future__ import annotations

import argparse
import gc
import sys
import time
from pathlib import Path
from typing import Any

BENCH = Path(__file__).resolve().parent
sys.path.insert(0, str(BENCH))

import viser  # noqa: E402
from big_charts import huge_chart  # noqa: E402
from figures import free_port  # noqa: E402
from page import CHROMIUM, CHROMIUM_ARGS  # noqa: E402

from s7graph.sequencer.text.parse import parse_chart  # noqa: E402
from s7graph.web.bus.protocol import ChartLayout  # noqa: E402
from s7graph.web.view.drawing import Drawing, camera_for, picture  # noqa: E402
from s7graph.web.view.layout import place  # noqa: E402


def _status(key: str) -> float:
    """``key`` of /proc/self/status in MB."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith(key + ":"):
            return int(line.split()[1]) / 1024
    raise SystemExit(f"/proc/self/status has no {key} (Linux only)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--chart", type=Path, help="a .s7g chart (default: the huge chart)")
    ap.add_argument("--browser", action="store_true", help="and a page showing it")
    args = ap.parse_args()
    source = args.chart.read_text() if args.chart else huge_chart()
    started = time.perf_counter()
    placement = place(ChartLayout.from_chart(parse_chart(source), version=1))
    gc.collect()
    print(f"placed: RSS {_status('VmRSS'):.0f} MB, peak {_status('VmHWM'):.0f} MB")
    pic = picture(placement)
    print(f"picture: RSS {_status('VmRSS'):.0f} MB, peak {_status('VmHWM'):.0f} MB")
    server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    try:
        drawing = Drawing(server.scene, pic)
        gc.collect()
        print(f"drawn: RSS {_status('VmRSS'):.0f} MB, peak {_status('VmHWM'):.0f} MB")
        sizes = [_pixels(t) for t in pic.tiles]
        print(
            f"{len(sizes)} text images of {sum(w * h for w, h in sizes) / 1e6:.1f} Mpx in all, "
            f"the largest {max(sizes, default=(0, 0))} px; {len(drawing.boxes)} steps; "
            f"{time.perf_counter() - started:.1f} s"
        )
        if args.browser:
            server.scene.set_up_direction("+y")
            cam = server.initial_camera
            cam.position, cam.look_at = camera_for(pic, whole=True)
            cam.up = (0.0, 1.0, 0.0)
            _browser(f"http://127.0.0.1:{server.get_port()}")
    finally:
        server.stop()


def _browser(url: str) -> None:
    """Open ``url`` in a headless Chromium and print its processes' memory as it settles."""
    import psutil
    from playwright.sync_api import sync_playwright

    me = psutil.Process()

    def pss_mb() -> float:
        total = 0
        for proc in me.children(recursive=True):
            try:
                total += proc.memory_full_info().pss
            except psutil.Error:  # gone meanwhile
                continue
        return total / 2**20

    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, headless=True, args=CHROMIUM_ARGS)
        try:
            page = browser.new_page(viewport={"width": 1280, "height": 800})
            started = time.perf_counter()
            page.goto(url)
            seen: list[float] = []
            while time.perf_counter() - started < 75:
                seen.append(pss_mb())
                if len(seen) > 15 and max(seen[-10:]) - min(seen[-10:]) < 5:
                    break
                time.sleep(1)
            print(
                f"browser: PSS {seen[-1]:.0f} MB, peak {max(seen):.0f} MB, "
                f"{time.perf_counter() - started:.0f} s after opening the page"
            )
        finally:
            browser.close()


def _pixels(tile: Any) -> tuple[int, int]:
    """A text image's width and height in pixels (before the tiles were bounded, the
    image itself)."""
    px = getattr(tile, "px", None)
    if px is not None:
        return (int(px[0]), int(px[1]))
    return (int(tile.image.shape[1]), int(tile.image.shape[0]))


if __name__ == "__main__":
    main()
