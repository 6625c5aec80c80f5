"""``s7graph check CHART.s7g --blocks BLOCKS.scl``: a chart's calls of user FBs and FCs
checked against the S7-SCL blocks' interfaces (E047: block, pin, direction, type, instance
DB), located in the chart's style; ``s7graph check PROGRAM.scl --blocks MORE.scl``."""

from __future__ import annotations

from pathlib import Path

import pytest

from s7graph.web.cli import main

BLOCKS = """
FUNCTION_BLOCK FB17
VAR_INPUT FINALVAL : INT; SPEED : REAL; END_VAR
VAR_OUTPUT CONTROL : BOOL; END_VAR
VAR_IN_OUT count : DINT; END_VAR
VAR n : INT; table : ARRAY[1..3] OF INT; END_VAR
  n := n + 1;
  CONTROL := n >= FINALVAL;
END_FUNCTION_BLOCK

FUNCTION_BLOCK FB18
VAR_INPUT data : ARRAY[1..2] OF INT; END_VAR
END_FUNCTION_BLOCK

FUNCTION FC5 : INT
VAR_INPUT x : INT; END_VAR
VAR_OUTPUT twice : INT; END_VAR
  twice := 2 * x;
  FC5 := x;
END_FUNCTION

DATA_BLOCK DB20
STRUCT avg : REAL; END_STRUCT
BEGIN
END_DATA_BLOCK

DATA_BLOCK DB30 FB18
BEGIN
END_DATA_BLOCK
"""

CHART = """FUNCTION_BLOCK "Seq" FB 1 DB 1
VAR done : BOOL; level : INT; END_VAR
PERMANENT BEFORE
  {before}
END_PERMANENT
SEQUENCE 1 "S"
  INITIAL_STEP S1 "wait":
    {row}
  END_STEP
  STEP S2 "count": END_STEP
  TRANSITION T1 FROM S1 TO S2 := done;
  TRANSITION T2 FROM S2 TO S1 := NOT done;
END_SEQUENCE
END_FUNCTION_BLOCK
"""
GOOD_ROW = "CALL FB 17, DB 10 (FINALVAL := level, SPEED := 1.5, CONTROL => done);"
GOOD_BEFORE = "CALL FC 5 (x := MW10, twice => MW12, RET_VAL => MW14);"


def _check(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    row: str = GOOD_ROW,
    before: str = GOOD_BEFORE,
    blocks: str = BLOCKS,
) -> tuple[int, list[str]]:
    chart = tmp_path / "seq.s7g"
    chart.write_text(CHART.format(row=row, before=before), encoding="utf-8")
    scl = tmp_path / "blocks.scl"
    scl.write_text(blocks, encoding="utf-8")
    rc = main(["check", str(chart), "--blocks", str(scl)])
    lines = capsys.readouterr().out.splitlines()
    prefix = f"{tmp_path}/"
    return rc, [line.removeprefix(prefix) for line in lines]


def test_calls_that_fit_the_blocks_check_clean(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert _check(tmp_path, capsys) == (0, ["seq.s7g: 0 errors, 0 warnings"])


@pytest.mark.parametrize(
    ("row", "message"),
    [
        (
            "CALL FB 19, DB 10;",
            "8:5: error[E047]: FB 19 is not in the program's blocks "
            "({dir}/blocks.scl; FBs: FB17 FB18) (step S1 row 1)",
        ),
        (
            "CALL FB 17, DB 10 (LEVEL := 3);",
            "8:5: error[E047]: FB17 has no parameter LEVEL "
            "(parameters: FINALVAL, SPEED, CONTROL, count) (step S1 row 1)",
        ),
        (
            "CALL FB 17, DB 10 (CONTROL := TRUE);",
            "8:5: error[E047]: FB17: CONTROL is an output, use CONTROL => ... (step S1 row 1)",
        ),
        (
            "CALL FB 17, DB 10 (FINALVAL => level);",
            "8:5: error[E047]: FB17: FINALVAL is an input, use FINALVAL := ... (step S1 row 1)",
        ),
        (
            "CALL FB 17, DB 10 (FINALVAL := T#2S);",
            "8:36: error[E047]: FB17: FINALVAL is INT, TIME does not fit it (step S1 row 1)",
        ),
        (
            "CALL FB 17, DB 10 (CONTROL => level);",
            "8:35: error[E047]: FB17: CONTROL is BOOL, INT does not fit it (step S1 row 1)",
        ),
        (
            "CALL FB 17;",
            "8:5: error[E047]: FB17 is an FB and needs an instance DB (CALL FB 17, DB n) "
            "(step S1 row 1)",
        ),
        (
            "CALL FB 17, DB 20;",
            "8:5: error[E047]: DB20 is a global DB of the program, not an instance DB of FB17 "
            "(step S1 row 1)",
        ),
        (
            "CALL FB 17, DB 30;",
            "8:5: error[E047]: DB30 is the instance DB of FB18 in the program, not of FB17 "
            "(step S1 row 1)",
        ),
        (
            "CALL FB 17, DB 1;",
            "8:5: error[E047]: DB1 is the instance DB of FB1 (this chart) already (step S1 row 1)",
        ),
        (
            "CALL FB 18, DB 31 (data := MW0);",
            "8:32: error[E047]: FB18: data is an ARRAY or STRUCT; a chart passes elementary "
            "values (step S1 row 1)",
        ),
        (
            "CALL FC 5, DB 3 (x := 1, twice => level);",
            "8:5: error[E047]: FC5 is an FC and takes no instance DB (step S1 row 1)",
        ),
        (
            "CALL FC 5 (x := 1);",
            "8:5: error[E047]: FC5: an FC takes every parameter; twice missing (step S1 row 1)",
        ),
    ],
)
def test_a_call_that_does_not_fit_the_blocks_is_a_located_e047(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], row: str, message: str
) -> None:
    rc, lines = _check(tmp_path, capsys, row=row)
    assert rc == 2
    assert f"seq.s7g:{message.format(dir=tmp_path)}" in lines, lines


def test_two_calls_naming_one_db_for_two_blocks_are_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    before = "CALL SFB 4, DB 10 (IN := I0.0, PT := T#1S);"
    rc, lines = _check(tmp_path, capsys, before=before)
    assert rc == 2
    assert lines == [
        "seq.s7g:4:3: error[E046]: DB10 is the instance DB of FB17 already (permanent before)",
        "seq.s7g: 1 error, 0 warnings",
    ]


def test_without_blocks_a_users_call_is_not_checked_as_before(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    chart = tmp_path / "seq.s7g"
    chart.write_text(CHART.format(row="CALL FB 19, DB 1;", before=""), encoding="utf-8")
    assert main(["check", str(chart)]) == 0


def test_the_blocks_diagnostics_come_first_and_count(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rc, lines = _check(tmp_path, capsys, blocks=BLOCKS.replace("n + 1", "n + m"))
    assert rc == 2
    assert lines[0] == "blocks.scl:7:12: error[E211]: unknown name 'm' (FB17)"
    assert lines[-1] == "seq.s7g: 1 error, 0 warnings"


def test_an_scl_program_is_checked_with_the_blocks_of_an_earlier_source(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    lib = tmp_path / "lib.scl"
    lib.write_text(BLOCKS, encoding="utf-8")
    program = tmp_path / "main.scl"
    program.write_text(
        "ORGANIZATION_BLOCK OB1\n  FB17.DB3(FINALVAL := 2, SPEED := 1.0);\n"
        "END_ORGANIZATION_BLOCK\n",
        encoding="utf-8",
    )
    assert main(["check", str(program), "--blocks", str(lib)]) == 0
    assert capsys.readouterr().out == f"{program}: 0 errors, 0 warnings\n"
    assert main(["check", str(program)]) == 2  # FB17 unknown without its source


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (
            "FUNCTION_BLOCK FB1\nVAR x : INT; END_VAR\nEND_FUNCTION_BLOCK\n",
            "FB1, the chart's FB, is a block of the program too",
        ),
        (
            "DATA_BLOCK DB1\nSTRUCT x : INT; END_STRUCT\nBEGIN\nEND_DATA_BLOCK\n",
            "DB1, the chart's instance DB, is a DB of the program too",
        ),
    ],
)
def test_blocks_that_write_the_charts_own_fb_or_db_are_an_e047_at_its_header(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], extra: str, message: str
) -> None:
    rc, lines = _check(tmp_path, capsys, blocks=BLOCKS + extra)
    assert rc == 2
    assert f"seq.s7g:1:1: error[E047]: {message} ({tmp_path}/blocks.scl)" in lines, lines
