"""``s7graph export CHART.s7g --blocks BLOCKS.scl``: a chart that reads a user FB's instance
DB by name (``"Motor_DB".Running``) compiles only with that FB's source, so the export takes
the sources as ``check``, ``sim`` and ``run`` do (docs/cli.md, "s7graph import, s7graph
export")."""

from __future__ import annotations

from pathlib import Path

import pytest

from s7graph.web.cli import main

BLOCKS = """
FUNCTION_BLOCK FB17
VAR_INPUT Start : BOOL; END_VAR
VAR_OUTPUT Running : BOOL; END_VAR
VAR calls : INT; END_VAR
  calls := calls + 1;
  Running := Start AND calls >= 3;
END_FUNCTION_BLOCK
"""

CHART = """FUNCTION_BLOCK "Seq_motor" FB 1 DB 1
SYMBOLS "Motor_DB" : DB12 : FB17; END_SYMBOLS
SEQUENCE 1 "Motor"
  INITIAL_STEP S1 "Idle": END_STEP
  STEP S2 "Run":
    CALL FB 17, DB 12 (Start := TRUE);
  END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.0;
  TRANSITION T2 FROM S2 TO S1 := {read};
END_SEQUENCE
END_FUNCTION_BLOCK
"""


def _files(tmp_path: Path, read: str) -> tuple[Path, Path]:
    chart, blocks = tmp_path / "motor.s7g", tmp_path / "motor.scl"
    chart.write_text(CHART.format(read=read))
    blocks.write_text(BLOCKS)
    return chart, blocks


@pytest.mark.parametrize("to", ["simaticml", "plcopen"])
def test_export_of_a_chart_reading_a_user_fbs_variable_takes_its_blocks(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], to: str
) -> None:
    """Without ``--blocks`` the read is E048, which says to give them; with them the
    chart goes out, the read written as its format writes a DB member."""
    chart, blocks = _files(tmp_path, '"Motor_DB".Running')
    out = tmp_path / f"motor.{to}.xml"
    assert main(["export", str(chart), "--to", to, "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "error[E048]" in err and "(--blocks): give them" in err
    assert not out.exists()
    rc = main(["export", str(chart), "--to", to, "-o", str(out), "--blocks", str(blocks)])
    assert rc == 1, capsys.readouterr().err  # the CALL row's warning
    written = out.read_text(encoding="utf-8")
    if to == "simaticml":
        assert '<Component Name="Motor_DB" /><Component Name="Running" />' in written
    else:
        assert "Motor_DB.Running" in written
    assert capsys.readouterr().err.splitlines()[-1].startswith(f"{chart}: exported to {out}")


def test_export_with_blocks_checks_the_read_against_the_fb(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A variable the FB lacks is E048 naming what it has, and nothing is written."""
    chart, blocks = _files(tmp_path, '"Motor_DB".Runing')
    out = tmp_path / "motor.xml"
    args = ["export", str(chart), "--to", "simaticml", "-o", str(out), "--blocks", str(blocks)]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert 'error[E048]: "Motor_DB".Runing: Runing is not a variable of FB17' in err
    assert not out.exists()


def test_export_says_which_block_source_does_not_compile(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    chart, blocks = _files(tmp_path, '"Motor_DB".Running')
    blocks.write_text(BLOCKS.replace("calls + 1;", "calls + 1"))
    out = tmp_path / "motor.xml"
    args = ["export", str(chart), "--to", "plcopen", "-o", str(out), "--blocks", str(blocks)]
    assert main(args) == 2
    assert f"{blocks}:6:" in capsys.readouterr().err
    assert not out.exists()


def test_export_prints_the_warnings_of_its_block_sources_as_check_does(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The sources are compiled as ``check --blocks`` compiles them: their warnings (an
    unused label, W301) are the very lines ``check`` prints, first on stderr, counted in
    the summary."""
    chart, blocks = _files(tmp_path, '"Motor_DB".Running')
    out = tmp_path / "motor.xml"
    args = ["export", str(chart), "--to", "plcopen", "-o", str(out), "--blocks", str(blocks)]
    assert main(args) == 1  # the export's own warnings (the CALL row's)
    clean = capsys.readouterr().err.splitlines()
    blocks.write_text(BLOCKS.replace("VAR calls", "LABEL spare; END_LABEL\nVAR calls"))
    assert main(["check", str(chart), "--blocks", str(blocks)]) == 1
    checked = [line for line in capsys.readouterr().out.splitlines() if "warning[W301]" in line]
    assert checked == [
        f"{blocks}:5:7: warning[W301]: label SPARE is declared but never placed (FB17)"
    ]
    assert main(args) == 1
    err = capsys.readouterr().err.splitlines()
    assert err[0] == checked[0] and err[1:-1] == clean[:-1]
    assert clean[-1].endswith(", 2 warnings") and err[-1].endswith(", 3 warnings"), err


def test_check_sim_and_export_compile_the_blocks_with_the_chart_s_symbols(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A source reading a symbol only the chart's ``SYMBOLS`` declare (``"Go"``) compiles
    alike in the three commands; ``check`` compiled it without them (E211)."""
    chart, blocks = _files(tmp_path, '"Motor_DB".Running')
    chart.write_text(
        chart.read_text().replace("END_SYMBOLS", '"Go" : M0.0 : BOOL; END_SYMBOLS'),
    )
    blocks.write_text(BLOCKS.replace("Start AND", 'Start AND "Go" AND'))
    assert main(["check", str(chart), "--blocks", str(blocks)]) == 0
    assert capsys.readouterr().out == f"{chart}: 0 errors, 0 warnings\n"
    assert main(["sim", str(chart), "--blocks", str(blocks), "--cycles", "2"]) == 0
    out = tmp_path / "motor.xml"
    args = ["export", str(chart), "--to", "plcopen", "-o", str(out), "--blocks", str(blocks)]
    assert main(args) == 1 and out.exists()  # the export's own warnings
    assert "error" not in capsys.readouterr().err
