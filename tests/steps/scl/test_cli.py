"""``s7graph check PROGRAM.scl`` and ``s7graph sim PROGRAM.scl`` (docs/cli.md, "s7graph
sim"; docs/scl.md)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from s7graph.web.cli import main

PROGRAM = """
FUNCTION_BLOCK FB1
VAR_INPUT start : BOOL; END_VAR
VAR_OUTPUT count : INT; END_VAR
  IF start THEN count := count + 1; END_IF;
END_FUNCTION_BLOCK
ORGANIZATION_BLOCK OB1
  FB1.DB1(start := "Start");
  MW0 := INT_TO_WORD(DB1.count);
  IF DB1.count > 3 THEN Q0.0 := TRUE; END_IF;
  IF M9.0 THEN WHILE TRUE DO END_WHILE; END_IF;
END_ORGANIZATION_BLOCK
"""


def _files(tmp_path: Path, source: str = PROGRAM) -> tuple[Path, Path]:
    scl = tmp_path / "count.scl"
    scl.write_text(source, encoding="utf-8")
    symbols = tmp_path / "symbols.txt"
    symbols.write_text('"Start" ; I0.0 ; BOOL\n', encoding="utf-8")
    return scl, symbols


def test_check_prints_nothing_but_the_summary_for_a_clean_source(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    scl, symbols = _files(tmp_path)
    assert main(["check", str(scl), "--symbols", str(symbols)]) == 0
    assert capsys.readouterr().out.splitlines() == [f"{scl}: 0 errors, 0 warnings"]


def test_check_prints_located_diagnostics_and_exits_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    scl, _ = _files(tmp_path, PROGRAM.replace("count + 1", "count + speed"))
    assert main(["check", str(scl)]) == 2
    out = capsys.readouterr().out.splitlines()
    assert out[0] == f"{scl}:5:34: error[E211]: unknown name 'speed' (FB1)"
    assert out[-1] == f"{scl}: 2 errors, 0 warnings"  # and "Start": no symbol table


def test_sim_traces_an_scl_program_without_steps(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    scl, symbols = _files(tmp_path)
    stimulus = tmp_path / "stim.jsonl"
    stimulus.write_text('{"at_ms": 20, "set": {"Start": true}}\n', encoding="utf-8")
    trace = tmp_path / "trace.jsonl"
    args = ["sim", str(scl), "--symbols", str(symbols), "--stimulus", str(stimulus)]
    args += ["--cycles", "8", "--watch", "MW0,Q0.0,DB1.count", "--trace", str(trace)]
    assert main(args) == 0
    lines = [json.loads(x) for x in trace.read_text(encoding="utf-8").splitlines()]
    assert len(lines) == 8
    assert lines[0] == {
        "cycle": 0,
        "t_ms": 0,
        "active": [],
        "events": [],
        "mode": "RUN",
        "values": {"MW0": 0, "Q0.0": False, "DB1.count": 0},
    }
    assert lines[-1]["values"] == {"MW0": 6, "Q0.0": True, "DB1.count": 6}


def test_sim_of_a_program_that_hangs_ends_with_the_stop(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    scl, symbols = _files(tmp_path)
    stimulus = tmp_path / "stim.jsonl"
    stimulus.write_text('{"at_ms": 10, "set": {"M9.0": true}}\n', encoding="utf-8")
    args = ["sim", str(scl), "--symbols", str(symbols), "--stimulus", str(stimulus)]
    assert main([*args, "--cycles", "5"]) == 1
    captured = capsys.readouterr()
    assert len(captured.out.splitlines()) == 2
    assert "cycle 1: the CPU went to STOP: OB1: aborted: a loop still running" in captured.err


def test_sim_of_a_broken_source_prints_its_diagnostics_and_exits_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    scl, _ = _files(tmp_path, "FUNCTION_BLOCK FB1\n  IF TRUE THEN\nEND_FUNCTION_BLOCK\n")
    assert main(["sim", str(scl)]) == 2
    assert capsys.readouterr().err.splitlines() == [
        f"{scl}:3:19: error[E202]: missing END_IF for the IF at line 2"
    ]


def test_check_prints_every_syntax_error_of_a_source(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    source = "FUNCTION_BLOCK FB1\nVAR n : INT; END_VAR\n  n := 1 +;\n  n := (2;\n  n := 3 4;\n"
    scl, _ = _files(tmp_path, source + "END_FUNCTION_BLOCK\n")
    assert main(["check", str(scl)]) == 2
    out = capsys.readouterr().out.splitlines()
    assert [line.split(": error")[0] for line in out[:-1]] == [
        f"{scl}:3:11",
        f"{scl}:4:10",
        f"{scl}:5:10",
    ]
    assert out[-1] == f"{scl}: 3 errors, 0 warnings"


def test_check_with_blocks_refuses_what_run_refuses_beside_them(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """An FB called with a DB another source declares is refused by ``check`` as by ``run``
    (docs/scl.md, "On the command line")."""
    lib, prog = tmp_path / "lib.scl", tmp_path / "prog.scl"
    lib.write_text("DATA_BLOCK DB20 STRUCT x : INT; END_STRUCT BEGIN END_DATA_BLOCK\n")
    prog.write_text(
        "FUNCTION_BLOCK FB17\nVAR n : INT; END_VAR\n  n := n + 1;\nEND_FUNCTION_BLOCK\n"
        "ORGANIZATION_BLOCK OB1\n  FB17.DB20();\nEND_ORGANIZATION_BLOCK\n"
    )
    assert main(["check", str(prog)]) == 0
    capsys.readouterr()
    assert main(["check", str(prog), "--blocks", str(lib)]) == 2
    assert capsys.readouterr().out.splitlines() == [
        f"{prog}: error: DB20, the instance DB of FB17, is a DB of {lib}:1:12",
        f"{prog}: 1 error, 0 warnings",
    ]
