"""A program's page lists the S7-SCL blocks its CPU runs and opens each one's text
read-only, in real Chromium against ``s7graph run PROGRAM.scl --blocks BLOCKS.scl --web``
(a real process): a button per OB, FB, FC and DB in source order, the library's first,
and the blocks' cross-references, a use opening its block's source (docs/view.md, "A
program's page"; docs/scl.md, "On the bus")."""

from __future__ import annotations

import signal
import subprocess
import sys
from pathlib import Path

import pytest

from tests.paths import ROOT
from tests.web.cli.test_scl_bus import BLOCKS, PROGRAM
from tests.web.helpers import block_source, chromium_page, free_port, needs_chromium, wait_until

pytestmark = [pytest.mark.timeout(240), needs_chromium]
pytest.importorskip("playwright.sync_api", reason="playwright is not installed")

SHOWN = ["FB 17 source", "DB 20 source", "OB 100 source", "OB 1 source"]


def test_a_programs_page_lists_its_blocks_and_opens_each_ones_source(tmp_path: Path) -> None:
    (tmp_path / "blocks.scl").write_text(BLOCKS, encoding="utf-8")
    (tmp_path / "prog.scl").write_text(PROGRAM, encoding="utf-8")
    port = free_port()
    program, blocks, state = (str(tmp_path / n) for n in ("prog.scl", "blocks.scl", "p.sqlite"))
    args = [program, "--blocks", blocks, "--state", state, "--web", "--port", str(port)]
    proc = subprocess.Popen(
        [sys.executable, "-m", "s7graph", "run", *args],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert proc.stdout is not None
        line = proc.stdout.readline()
        assert f"view http://127.0.0.1:{port}/ (bus" in line, proc.stderr and proc.stderr.read()
        with chromium_page(f"http://127.0.0.1:{port}/") as page:
            page.get_by_text("4 blocks · the sources, read-only").wait_for(timeout=60_000)
            buttons = page.get_by_role("button").filter(has_text=" source")
            assert buttons.all_inner_texts() == SHOWN
            page.get_by_role("button", name="OB 1 source", exact=True).click()
            shown = page.locator("pre.s7-block-source")
            shown.wait_for(timeout=30_000)
            assert shown.inner_text() == PROGRAM.strip().split("\n\n")[-1]
            assert "prog.scl, line 11; read-only" in page.inner_text("body")
            page.get_by_role("button", name="Close", exact=True).click()
            assert wait_until(lambda: shown.count() == 0, 30)
            page.get_by_role("button", name="FB 17 source", exact=True).click()
            assert wait_until(lambda: "n := n + 1" in block_source(page), 30)
            page.get_by_role("button", name="Close", exact=True).click()
            page.get_by_text("Cross-references", exact=True).first.click()  # open the folder
            row = "ancestor::div[contains(@class,'mantine-Flex-root')][1]"
            page.locator(f"xpath=//label[text()='Uses of']/{row}//input").first.click()
            page.get_by_role("option", name="DB20.warm", exact=True).click()
            page.get_by_text("DB20.warm: 2 uses").first.wait_for(timeout=30_000)
            page.get_by_role("button", name="OB 100 · write · prog.scl:8", exact=True).click()
            assert wait_until(lambda: "DB20.warm := DB20.warm + 1;" in block_source(page), 30)
    finally:
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=60)
    assert proc.returncode == 0, err
