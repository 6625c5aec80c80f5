"""Hostile S7-SCL sources and DB names on the command line (``--blocks``, ``--watch``,
stimuli): each ends in located diagnostics, one ``s7graph: error:`` line or a STOP by
cycle monitoring — never in an internal error or a traceback."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from s7graph.web.cli import main

FB = """
FUNCTION_BLOCK FB17
VAR_INPUT go : BOOL; END_VAR
VAR n : INT; a : ARRAY[1..3] OF INT; END_VAR
  IF go THEN n := n + 1; END_IF;
END_FUNCTION_BLOCK
"""
CHART = """FUNCTION_BLOCK "Seq" FB 1 DB 1
SEQUENCE 1 "S"
  INITIAL_STEP S1 "run":
    CALL FB 17, DB {db} (go := TRUE);
  END_STEP
  STEP S2 "never": END_STEP
  TRANSITION T1 FROM S1 TO S2 := FALSE;
  TRANSITION T2 FROM S2 TO S1 := FALSE;
END_SEQUENCE
END_FUNCTION_BLOCK
"""


def _quiet(err: str) -> None:
    assert "internal error" not in err and "Traceback" not in err, err


def _files(tmp_path: Path, blocks: str | bytes, db: int = 10) -> tuple[Path, Path]:
    chart = tmp_path / "seq.s7g"
    chart.write_text(CHART.format(db=db), encoding="utf-8")
    scl = tmp_path / "blocks.scl"
    if isinstance(blocks, bytes):
        scl.write_bytes(blocks)
    else:
        scl.write_text(blocks, encoding="utf-8")
    return chart, scl


@pytest.mark.parametrize("command", ["sim", "check"])
@pytest.mark.parametrize(
    "blocks",
    [
        b"FUNCTION_BLOCK FB17\n\xff\xfe\nEND_FUNCTION_BLOCK\n",
        "FUNCTION_BLOCK FB17\nVAR n : INT; END_VAR\n  n := " + "(" * 5000 + "1" + ")" * 5000,
        "FUNCTION_BLOCK FB17\n" + "IF TRUE THEN " * 400 + "END_IF; " * 400,
        "DATA_BLOCK DB10\nSTRUCT x : INT; END_STRUCT\nBEGIN\nEND_DATA_BLOCK\n" + FB,
        "FUNCTION_BLOCK FB17\nVAR a : ARRAY[1..100000000] OF INT; END_VAR\nEND_FUNCTION_BLOCK",
        "",
    ],
    ids=["not-utf8", "deep-parens", "deep-ifs", "db-is-global", "huge-array", "empty"],
)
def test_a_hostile_blocks_source_ends_in_diagnostics_never_an_internal_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], command: str, blocks: str | bytes
) -> None:
    chart, scl = _files(tmp_path, blocks)
    more = ["--cycles", "2"] if command == "sim" else []
    rc = main([command, str(chart), "--blocks", str(scl), *more])
    out, err = capsys.readouterr()
    _quiet(out + err)
    assert rc in (0, 1, 2)
    if rc == 2 and command == "sim":
        lines = err.splitlines()
        assert lines and all(line.startswith(("s7graph:", str(tmp_path))) for line in lines)


def test_a_missing_blocks_source_is_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    chart, _ = _files(tmp_path, FB)
    gone = tmp_path / "gone.scl"
    for command in ("sim", "check"):
        assert main([command, str(chart), "--blocks", str(gone)]) == 2
        err = capsys.readouterr().err
        assert err == f"s7graph: error: cannot read {gone}: No such file or directory\n"


def test_a_loop_in_a_block_the_chart_calls_stops_the_cpu_by_cycle_monitoring(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    chart, scl = _files(tmp_path, FB.replace("n := n + 1;", "WHILE TRUE DO n := 1; END_WHILE;"))
    assert main(["sim", str(chart), "--blocks", str(scl), "--cycles", "3"]) == 1
    out, err = capsys.readouterr()
    _quiet(err)
    assert len(out.splitlines()) == 1 and json.loads(out)["active"] == ["S1"]
    assert "cycle 0: the CPU went to STOP" in err and "a loop still running" in err


def test_a_call_naming_a_global_db_of_the_blocks_refuses_the_chart_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    data = "DATA_BLOCK DB20\nSTRUCT x : INT; END_STRUCT\nBEGIN\nEND_DATA_BLOCK\n"
    chart, scl = _files(tmp_path, data + FB, db=20)
    assert main(["sim", str(chart), "--blocks", str(scl)]) == 2
    err = capsys.readouterr().err
    assert err.splitlines() == [
        f"{chart}:4:5: error: CALL FB 17, DB 20: DB20 is a global DB (step S1 row 1)"
    ]


@pytest.mark.parametrize(
    "name",
    [
        "DB99999999999999999999.n",
        "DB10." + "a" * 200,
        "DB10.a[" + "9" * 60 + "]",
        "DB10.a" + "[1]" * 50,
        "DB10.n.x",
        '"' + "x" * 500 + '".n',
        "DB10.a[1,2]",
        "DB1.G7_STATE.x",
    ],
)
def test_a_hostile_db_name_is_one_line_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], name: str
) -> None:
    chart, scl = _files(tmp_path, FB)
    assert main(["sim", str(chart), "--blocks", str(scl), "--watch", name]) == 2
    err = capsys.readouterr().err
    _quiet(err)
    assert err.count("\n") == 1 and err.startswith("s7graph: error: ")


@pytest.mark.parametrize("value", ["abc", 70000, [1, 2], {"x": 1}, None, 1.5])
def test_a_stimulus_of_the_wrong_type_for_a_db_variable_is_one_line_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], value: object
) -> None:
    chart, scl = _files(tmp_path, FB)
    stim = tmp_path / "stim.jsonl"
    stim.write_text(json.dumps({"at_ms": 0, "set": {"DB10.n": value}}) + "\n", encoding="utf-8")
    assert main(["sim", str(chart), "--blocks", str(scl), "--stimulus", str(stim)]) == 2
    err = capsys.readouterr().err
    _quiet(err)
    assert err.startswith(f"s7graph: error: {stim}:1: DB10.n: ") and err.count("\n") == 1
