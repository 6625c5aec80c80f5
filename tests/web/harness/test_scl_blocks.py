"""An S7-SCL program beside a chart in one session (``web/harness/session.py``:
``ChartSession.load(…, blocks=…)``, ``web/harness/scl.py``): compiled with the chart's
symbol table, loaded into the chart's CPU before start, so the chart calls its FBs and FCs
and its OBs run as the CPU's — an OB1 or OB100 after the chart's own (docs/scl.md,
"Loading and running"; docs/chart-format.md)."""

from __future__ import annotations

from pathlib import Path

import pytest

from s7graph.engine.clock import VirtualClock
from s7graph.engine.errors import S7Error
from s7graph.web.harness.scl import SclLoadError, compile_sources
from s7graph.web.harness.session import ChartSession

CHART = """FUNCTION_BLOCK "Seq" FB 1 DB 1
SYMBOLS "Go" : I0.0 : BOOL; "Count" : MW20 : INT; END_SYMBOLS
SEQUENCE 1 "Main"
  INITIAL_STEP S1 "Wait":
    S1 N "Count" := 7;
  END_STEP
  STEP S2 "Run":
    CALL FB 17, DB 10 (FINALVAL := 3);
  END_STEP
  TRANSITION T1 FROM S1 TO S2 := "Go";
  TRANSITION T2 FROM S2 TO S1 := M1.0;
END_SEQUENCE
END_FUNCTION_BLOCK
"""

SCL = """
FUNCTION_BLOCK FB17
VAR_INPUT FINALVAL : INT; END_VAR
VAR n : INT; END_VAR
  n := n + 1;
  M1.0 := n >= FINALVAL;
END_FUNCTION_BLOCK

DATA_BLOCK DB10 FB17        // the instance DB of the chart's call, downloaded with FB17
BEGIN
END_DATA_BLOCK

ORGANIZATION_BLOCK OB100
  "Count" := "Count" * 10;  // a symbol of the chart's own table, after the chart's S1 row
END_ORGANIZATION_BLOCK

ORGANIZATION_BLOCK OB1
  "Count" := "Count" + 1;   // after the chart's call in every cycle
  M2.1 := M1.0;
END_ORGANIZATION_BLOCK
"""


def files(tmp_path: Path, scl: str = SCL) -> tuple[Path, Path]:
    chart, blocks = tmp_path / "seq.s7g", tmp_path / "prog.scl"
    chart.write_text(CHART, encoding="utf-8")
    blocks.write_text(scl, encoding="utf-8")
    return chart, blocks


def test_a_chart_calls_an_scl_fb_and_the_programs_obs_run_after_the_charts(
    tmp_path: Path,
) -> None:
    chart, blocks = files(tmp_path)
    session = ChartSession.load(chart, None, VirtualClock(), blocks=[blocks])
    assert session.missing == []  # FB17 is in the CPU: no warning
    session.start()
    assert session.get("Count") == 70  # OB100: the chart's startup call, then the program's
    session.set("Go", True)
    seen = []
    for _ in range(4):
        session.scan()
        seen.append((session.get("S2.X"), session.get("Count")))
        session.clock.advance(10)
    # FB17's third call sets M1.0, T2 goes back to S1 in the next cycle; OB1 adds 1 to
    # Count in every cycle, after the chart's call: S1's row sets 7 first
    assert seen == [(True, 71), (True, 72), (True, 73), (False, 8)]
    assert session.cpu.instance_db(10)["n"] == 3
    assert session.cpu.mode.name == "RUN"


def test_an_scl_source_that_does_not_compile_is_a_load_error_with_its_places(
    tmp_path: Path,
) -> None:
    chart, blocks = files(tmp_path, "ORGANIZATION_BLOCK OB35\n  x := 1;\nEND_ORGANIZATION_BLOCK\n")
    with pytest.raises(SclLoadError) as caught:
        ChartSession.load(chart, None, VirtualClock(), blocks=[blocks])
    assert caught.value.lines[0].startswith(f"{blocks}:2:3: error[E211]")


def test_an_scl_source_that_cannot_be_read_is_a_load_error(tmp_path: Path) -> None:
    with pytest.raises(S7Error, match="cannot read"):
        compile_sources([tmp_path / "none.scl"])
    bad = tmp_path / "latin1.scl"
    bad.write_bytes(b"// caf\xe9\n")
    with pytest.raises(S7Error, match="not UTF-8"):
        compile_sources([bad])
