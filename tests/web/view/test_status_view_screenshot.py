"""The README's screenshot of the status view, taken from the running product: the README's
first command (the drill with its demo plant, ``s7graph run … --web``) as a real process on
the system clock, its page in one headless Chromium, photographed once the demo's slow clamp
has turned S2 red (a supervision fault waiting for acknowledgement, in the Alarms panel).
The maximum cycle time is raised to 60 s: a loaded test machine (Chromium drawing in
software beside it) must not stop the CPU by a slow cycle; timing is not what this checks.

``S7GRAPH_STATUS_SCREENSHOT=docs/status-view.png python -m pytest
tests/web/view/test_status_view_screenshot.py`` writes ``docs/status-view.png``; without it the
picture goes to a temporary folder and is only checked."""

from __future__ import annotations

import os
import queue
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from tests.paths import ROOT
from tests.web.helpers import chromium_page, needs_chromium, wait_until
from tests.web.view.test_edit_browser import screenshot
from tests.web.wiring.test_run_chart_web import _free_port

DRILL = ROOT / "examples" / "drill"

pytestmark = [pytest.mark.timeout(240), needs_chromium]


def _red_pixels(png: bytes) -> int:
    """Pixels of the DISTURBED step colour family (red clearly above green and blue)."""
    import io

    import numpy as np
    from PIL import Image

    rgb = np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(np.int16)
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    return int(np.count_nonzero((r > g + 50) & (r > b + 50)))


def test_the_status_view_of_the_readme_demo_shows_active_and_disturbed_steps(
    tmp_path: Path,
) -> None:
    pytest.importorskip("playwright.sync_api", reason="playwright is not installed")
    command = [sys.executable, "-m", "s7graph", "run", str(DRILL / "drill.s7g")]
    command += ["--plant", str(DRILL / "demo_plant.py"), "--symbols", str(DRILL / "symbols.txt")]
    command += ["--web", "--port", str(_free_port()), "--duration-s", "200"]
    command += ["--max-cycle-ms", "60000"]  # a loaded test machine: no STOP by a slow cycle
    command += ["--state", str(tmp_path / "drill.sqlite")]
    stderr = (tmp_path / "stderr.txt").open("w")
    proc = subprocess.Popen(command, cwd=ROOT, stdout=subprocess.PIPE, stderr=stderr, text=True)
    lines: queue.Queue[str] = queue.Queue()
    assert proc.stdout is not None
    out = proc.stdout
    threading.Thread(target=lambda: [lines.put(line) for line in out], daemon=True).start()
    try:
        found = None
        deadline = time.monotonic() + 30
        while found is None and time.monotonic() < deadline:
            try:
                found = re.search(r"view (\S+) \(bus (\S+)\)", lines.get(timeout=1))
            except queue.Empty:
                assert proc.poll() is None, (tmp_path / "stderr.txt").read_text()
        assert found is not None, "no view URL printed"
        with chromium_page(found[1]) as page:
            page.get_by_role("button", name="Acknowledge", exact=True).wait_for(timeout=30_000)
            # every third piece the clamp is slow: S2's supervision trips and waits
            page.get_by_text("error: S2").first.wait_for(timeout=90_000)
            page.get_by_text("S002 Work piece not clamped").first.wait_for(timeout=30_000)
            page.screenshot(path=str(tmp_path / "seen.png"))  # kept for a failed run
            assert wait_until(lambda: _red_pixels(page.screenshot()) > 200, 30)
            shot = Path(os.environ.get("S7GRAPH_STATUS_SCREENSHOT") or tmp_path / "status.png")
            screenshot(page, shot)
        assert shot.stat().st_size > 10_000
    finally:
        if proc.poll() is None:
            proc.send_signal(signal.SIGINT)
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
        stderr.close()
