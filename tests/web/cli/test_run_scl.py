"""``s7graph run PROGRAM.scl`` and ``s7graph run CHART.s7g --blocks BLOCKS.scl`` as real
processes: the state file keeps the instance DBs of S7-SCL FBs and the global DBs; a warm
restart comes back with them, a cold one with every DB at its initial values (an instance
DB's own ``BEGIN`` values included); an FB whose interface changed keeps its variables by
name and type (docs/state-file.md, docs/scl.md)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from s7graph.engine.persistence import unpack_instance
from s7graph.web.cli import main
from tests.paths import ROOT
from tests.real_process import query_store
from tests.web.helpers import CALLS_FB17, cpu_process, wait_until

PROGRAM = """
FUNCTION_BLOCK FB1
VAR n : DINT; base : INT; peak : INT; hist : ARRAY[1..3] OF INT; END_VAR
  n := n + 1;
  IF n = 1 THEN base := base + 1; END_IF;
  IF DB20.warm > peak THEN peak := DB20.warm; END_IF;
  hist[2] := peak;
END_FUNCTION_BLOCK

DATA_BLOCK DB10 FB1
BEGIN base := 7;
END_DATA_BLOCK

DATA_BLOCK DB20
STRUCT warm : INT; END_STRUCT
BEGIN
END_DATA_BLOCK

ORGANIZATION_BLOCK OB100
  DB20.warm := DB20.warm + 1;
END_ORGANIZATION_BLOCK

ORGANIZATION_BLOCK OB1
  FB1.DB10();
END_ORGANIZATION_BLOCK
"""


def _run(path: Path, *args: str, seconds: float = 0.3) -> subprocess.CompletedProcess[str]:
    cmd = [sys.executable, "-m", "s7graph", "run", str(path), "--duration-s", str(seconds)]
    return subprocess.run(
        [*cmd, "--rt-priority", "0", *args],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
    )


def _instance(state: Path, number: int) -> dict[str, Any]:
    def read(con: Any) -> Any:
        row = con.execute("SELECT data FROM instances WHERE number = ?", (number,)).fetchone()
        return unpack_instance(row[0])

    found = query_store(state, read)
    assert found is not None
    return found


def test_a_warm_restart_keeps_the_dbs_and_a_cold_one_brings_their_initial_values(
    tmp_path: Path,
) -> None:
    path = tmp_path / "prog.scl"
    path.write_text(PROGRAM, encoding="utf-8")
    state = tmp_path / "prog.scl.state.sqlite"
    first = _run(path)
    assert first.returncode == 0, first.stderr
    one = _instance(state, 10)
    assert one["base"] == 8 and one["peak"] == 1 and one["n"] >= 1  # BEGIN base := 7
    warm = _run(path)
    assert warm.returncode == 0, warm.stderr
    assert "warm restart from" in warm.stderr
    two = _instance(state, 10)
    assert two["n"] > one["n"] and two["peak"] == 2  # DB20 kept: OB100 counted on
    assert two["hist"] == [0, 2, 0] and two["base"] == 8
    cold = _run(path, "--restart", "cold")
    assert cold.returncode == 0, cold.stderr
    three = _instance(state, 10)
    assert three["peak"] == 0 and three["hist"] == [0, 0, 0]  # DB20 and DB10 anew
    assert three["base"] == 8  # from the instance's own 7, not the FB's 0


def test_an_fb_whose_interface_changed_keeps_its_variables_by_name_and_type(
    tmp_path: Path,
) -> None:
    path = tmp_path / "prog.scl"
    path.write_text(PROGRAM, encoding="utf-8")
    assert _run(path).returncode == 0
    before = _instance(tmp_path / "prog.scl.state.sqlite", 10)
    path.write_text(
        PROGRAM.replace("hist : ARRAY[1..3] OF INT;", "hist : ARRAY[1..5] OF INT; x : REAL;"),
        encoding="utf-8",
    )
    changed = _run(path)
    assert changed.returncode == 0, changed.stderr
    notes = [line for line in changed.stderr.splitlines() if "note: DB10" in line]
    assert notes == [
        "s7graph: note: DB10 FB1 'FB1': interface changed; variables kept by name (3)",
        "s7graph: note: DB10 FB1 'FB1': of another type, at their initial values: hist",
        "s7graph: note: DB10 FB1 'FB1': new, at their initial values: x",
    ]
    after = _instance(tmp_path / "prog.scl.state.sqlite", 10)
    assert after["n"] > before["n"] and len(after["hist"]) == 5


BLOCKS = """
FUNCTION_BLOCK FB17
VAR_INPUT go : BOOL; END_VAR
VAR n : DINT; END_VAR
  IF go THEN n := n + 1; END_IF;
END_FUNCTION_BLOCK
"""
CHART = CALLS_FB17


def test_a_chart_run_with_its_blocks_keeps_their_instance_db_across_a_restart(
    tmp_path: Path,
) -> None:
    chart = tmp_path / "seq.s7g"
    chart.write_text(CHART, encoding="utf-8")
    blocks = tmp_path / "blocks.scl"
    blocks.write_text(BLOCKS, encoding="utf-8")
    first = _run(chart, "--blocks", str(blocks))
    assert first.returncode == 0, first.stderr
    state = tmp_path / "seq.state.sqlite"
    n1 = _instance(state, 10)["n"]
    again = _run(chart, "--blocks", str(blocks))
    assert again.returncode == 0, again.stderr
    assert _instance(state, 10)["n"] > n1 >= 1


def test_a_plant_or_a_recording_beside_an_scl_program_is_refused_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "prog.scl"
    path.write_text(PROGRAM, encoding="utf-8")
    assert main(["run", str(path), "--plant", str(path), "--duration-s", "0.1"]) == 2
    err = capsys.readouterr().err
    assert err == "s7graph: error: --plant is for a chart (.s7g), not a program\n"
    assert not (tmp_path / "prog.scl.state.sqlite").exists()


def test_a_program_that_does_not_compile_is_its_diagnostics_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "prog.scl"
    path.write_text(PROGRAM.replace("n + 1", "n + nn"), encoding="utf-8")
    assert main(["run", str(path), "--duration-s", "0.1"]) == 2
    assert capsys.readouterr().err.splitlines() == [
        f"{path}:4:12: error[E211]: unknown name 'nn' (FB1)"
    ]


def test_blocks_beside_a_python_program_are_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "prog.py"
    path.write_text("", encoding="utf-8")
    assert main(["run", str(path), "--blocks", str(path), "--duration-s", "0.1"]) == 2
    assert "--blocks goes with a chart or an .scl program" in capsys.readouterr().err


def test_a_chart_with_its_blocks_runs_on_the_bus_and_serves_their_source(tmp_path: Path) -> None:
    chart = tmp_path / "seq.s7g"
    chart.write_text(CHART, encoding="utf-8")
    blocks = tmp_path / "blocks.scl"
    blocks.write_text(BLOCKS, encoding="utf-8")
    state = tmp_path / "seq.state.sqlite"
    args = [str(chart), "--blocks", str(blocks), "--state", str(state), "--duration-s", "60"]
    with cpu_process(tmp_path, args, fb="Seq", terminate=True) as (proc, client, _):
        update = client.state("Seq")
        assert update is not None and update.active == [1]
        served = client.blocks()  # the sources of --blocks, for the page's CALL links
        assert served is not None and [b.label for b in served.blocks] == ["FB17"]
        assert served.blocks[0].file == "blocks.scl" and "n := n + 1" in served.blocks[0].text
        assert wait_until(lambda: _counted(state) > 0, 30)
    assert proc.wait(timeout=60) == 0


def _counted(state: Path) -> int:
    try:
        return int(_instance(state, 10)["n"])
    except (AssertionError, TypeError):
        return 0


def test_upload_of_an_scl_program_gives_its_sources_back(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A CPU that runs a program of S7-SCL blocks and no chart: ``s7graph upload`` prints
    its one source, or writes it into ``--to``; ``--fb`` names no chart there."""
    path = tmp_path / "prog.scl"
    path.write_text(PROGRAM, encoding="utf-8")
    args = [str(path), "--state", str(tmp_path / "prog.sqlite"), "--duration-s", "60"]
    with cpu_process(tmp_path, args, terminate=True) as (proc, _, _):
        bus = ["--cpu", "cpu1", "--connect", f"unixsock-stream/{tmp_path}/bus.sock"]
        assert main(["upload", *bus]) == 0
        assert capsys.readouterr().out == PROGRAM
        folder = tmp_path / "back"
        assert main(["upload", *bus, "--to", str(folder)]) == 0
        assert (folder / "prog.scl").read_text(encoding="utf-8") == PROGRAM
        said = capsys.readouterr().out.splitlines()
        lines = len(PROGRAM.splitlines())
        assert said == [
            "s7graph: the program of cpu1 (no GRAPH FB):",
            f"s7graph: an S7-SCL source → {folder / 'prog.scl'} ({lines} lines)",
        ]
        assert main(["upload", *bus, "--fb", "Seq"]) == 2
        assert capsys.readouterr().err == (
            "s7graph: error: cpu1: this CPU runs no GRAPH FB: no chart to upload\n"
        )
    assert proc.wait(timeout=60) == 0
