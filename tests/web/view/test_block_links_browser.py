"""A step's ``CALL`` rows link to the S7-SCL source of the blocks they call, in real
Chromium against ``s7graph run CHART.s7g --blocks BLOCKS.scl --web`` (a real process): the
step *Details* shows has a button per block called, which opens the block's text
read-only; a step without calls has none (docs/view.md, "A step's blocks")."""

from __future__ import annotations

import re
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from tests.paths import ROOT
from tests.web.helpers import block_source, chromium_page, field, free_port, wait_until

pytestmark = pytest.mark.timeout(240)

BLOCKS = """// the blocks the chart calls
FUNCTION_BLOCK FB17
VAR_INPUT go : BOOL; END_VAR
VAR n : DINT; END_VAR
  IF go THEN n := n + 1; END_IF;   // counts while S1 is active
END_FUNCTION_BLOCK

FUNCTION FC3 : INT
VAR_INPUT a : INT; END_VAR
  FC3 := a * 2;
END_FUNCTION
"""
CHART = """FUNCTION_BLOCK "Seq" FB 1 DB 1
SEQUENCE 1 "S"
  INITIAL_STEP S1 "count":
    CALL FB 17, DB 10 (go := TRUE);
    CALL FC 3 (a := 2);
  END_STEP
  STEP S2 "never": END_STEP
  TRANSITION T1 FROM S1 TO S2 := FALSE;
END_SEQUENCE
END_FUNCTION_BLOCK
"""


def test_a_steps_call_rows_open_the_scl_source_of_the_blocks_they_call(tmp_path: Path) -> None:
    chart = tmp_path / "seq.s7g"
    chart.write_text(CHART, encoding="utf-8")
    blocks = tmp_path / "blocks.scl"
    blocks.write_text(BLOCKS, encoding="utf-8")
    port = free_port()
    args = [str(chart), "--blocks", str(blocks), "--state", str(tmp_path / "seq.sqlite")]
    proc = subprocess.Popen(
        [sys.executable, "-m", "s7graph", "run", *args, "--web", "--port", str(port)],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert proc.stdout is not None
        line = proc.stdout.readline()
        found = re.search(r"view (\S+) \(bus", line)
        assert found is not None, (line, proc.stderr.read() if proc.stderr else "")
        with chromium_page(found[1]) as page:
            fb17 = page.get_by_role("button", name="FB 17 source", exact=True)
            fb17.wait_for(timeout=60_000)  # Details follows S1, the active step
            assert page.get_by_role("button", name="FC 3 source", exact=True).count() == 1
            fb17.click()
            shown = page.locator("pre.s7-block-source")
            shown.wait_for(timeout=30_000)
            assert shown.inner_text() == BLOCKS.split("\n\n")[0].split("\n", 1)[1]
            assert "blocks.scl, line 2; read-only" in page.inner_text("body")
            page.get_by_role("button", name="Close", exact=True).click()
            assert wait_until(lambda: shown.count() == 0, 30)
            page.get_by_role("button", name="FC 3 source", exact=True).click()
            assert wait_until(lambda: "FC3 := a * 2;" in block_source(page), 30)
            page.get_by_role("button", name="Close", exact=True).click()
            field(page, "Show step").fill("2")
            field(page, "Show step").press("Enter")
            assert wait_until(lambda: fb17.count() == 0, 30)  # S2 calls nothing
    finally:
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=60)
    assert proc.returncode == 0, err
