"""``s7graph sim CHART.s7g --blocks BLOCKS.scl`` and ``s7graph sim PROGRAM.scl --blocks
MORE.scl``: a chart whose CALL rows reach S7-SCL FBs and FCs, and a program of SCL blocks
over several sources, under the trace contract of docs/cli.md, "s7graph sim"."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from s7graph.web.cli import main

BLOCKS = """
FUNCTION_BLOCK FB17
VAR_INPUT FINALVAL : INT; END_VAR
VAR_OUTPUT CONTROL : BOOL; END_VAR
VAR n : INT; hist : ARRAY[1..3] OF INT; END_VAR
  n := n + 1;
  hist[1] := -n;
  CONTROL := n >= FINALVAL;
END_FUNCTION_BLOCK

FUNCTION FC5 : VOID
VAR_INPUT x : INT; END_VAR
VAR_OUTPUT twice : INT; END_VAR
  twice := 2 * x;
END_FUNCTION

ORGANIZATION_BLOCK OB1
  MW20 := INT_TO_WORD(WORD_TO_INT(MW20) + 1);
END_ORGANIZATION_BLOCK

ORGANIZATION_BLOCK OB100
  MW22 := 16#FFFF;
END_ORGANIZATION_BLOCK
"""

CHART = """FUNCTION_BLOCK "Seq" FB 1 DB 1
VAR done : BOOL; END_VAR
PERMANENT BEFORE
  CALL FC 5 (x := MW10, twice => MW12);
END_PERMANENT
SEQUENCE 1 "S"
  INITIAL_STEP S1 "wait": END_STEP
  STEP S2 "count":
    CALL FB 17, DB 10 (FINALVAL := 3, CONTROL => done);
  END_STEP
  STEP S3 "done": N Q0.0; END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.0;
  TRANSITION T2 FROM S2 TO S3 := done;
  TRANSITION T3 FROM S3 TO S1 := FALSE;
END_SEQUENCE
END_FUNCTION_BLOCK
"""


def _write(tmp_path: Path, **files: str) -> dict[str, Path]:
    out = {}
    for name, text in files.items():
        path = tmp_path / name.replace("_", ".")
        path.write_text(text, encoding="utf-8")
        out[name] = path
    return out


def _sim(
    capsys: pytest.CaptureFixture[str], *args: object
) -> tuple[int, list[dict[str, object]], str]:
    rc = main(["sim", *map(str, args)])
    out, err = capsys.readouterr()
    return rc, [json.loads(line) for line in out.splitlines()], err


def test_a_chart_calls_the_fb_and_fc_of_its_blocks_and_their_obs_run_beside_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    f = _write(
        tmp_path,
        seq_s7g=CHART,
        blocks_scl=BLOCKS,
        stim_jsonl='{"at_ms": 0, "set": {"MW10": 21}}\n{"at_ms": 20, "set": {"I0.0": true}}\n',
    )
    watch = "MW12,MW20,MW22,Q0.0,DB10.n,DB10.hist,DB10.hist[1]"
    args = [f["seq_s7g"], "--blocks", f["blocks_scl"], "--stimulus", f["stim_jsonl"]]
    rc, trace, err = _sim(capsys, *args, "--cycles", "7", "--watch", watch)
    assert rc == 0 and err == ""
    assert trace[0] == {
        "cycle": 0,
        "t_ms": 0,
        "active": ["S1"],
        "events": [],
        "mode": "AUTO",
        "values": {
            "MW12": 42,  # FC5 in the permanent instructions
            "MW20": 1,  # the source's OB1, after the chart's call
            "MW22": 65535,  # its OB100: a WORD unsigned
            "Q0.0": False,
            "DB10.n": 0,
            "DB10.hist": [0, 0, 0],
            "DB10.hist[1]": 0,
        },
    }
    assert [line["active"] for line in trace] == [["S1"]] * 2 + [["S2"]] * 3 + [["S3"]] * 2
    assert trace[5]["events"] == [["S2", "S3"]]
    assert trace[-1]["values"]["DB10.n"] == 3  # the instance DB the call named: created
    assert trace[-1]["values"]["DB10.hist[1]"] == -3  # an INT signed
    assert trace[-1]["values"]["DB10.hist"] == [-3, 0, 0]
    assert trace[-1]["values"]["MW20"] == 7


def test_a_stimulus_sets_an_fb_variable_and_a_global_db_member_by_name(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    data = """
DATA_BLOCK DB20
STRUCT avg : REAL; wait : TIME; motor : ARRAY[1..3] OF STRUCT on : BOOL; speed : INT; END_STRUCT;
END_STRUCT
BEGIN avg := 1.5; motor[2].speed := -7;
END_DATA_BLOCK
"""
    stim = '{"at_ms": 10, "set": {"DB10.n": 100, "DB20.motor[3].on": true, "DB20.avg": 2.25}}\n'
    f = _write(tmp_path, seq_s7g=CHART, data_scl=data, blocks_scl=BLOCKS, stim_jsonl=stim)
    watch = "DB10.n,DB20.avg,DB20.wait,DB20.motor[2].speed,DB20.motor[3].on,DB20.motor[3]"
    args = [f["seq_s7g"], "--blocks", f["data_scl"], "--blocks", f["blocks_scl"]]
    args += ["--stimulus", f["stim_jsonl"], "--cycles", "2", "--watch", watch]
    rc, trace, err = _sim(capsys, *args)
    assert rc == 0, err
    assert trace[0]["values"] == {
        "DB10.n": 0,
        "DB20.avg": 1.5,
        "DB20.wait": 0,
        "DB20.motor[2].speed": -7,
        "DB20.motor[3].on": False,
        "DB20.motor[3]": {"on": False, "speed": 0},
    }
    assert trace[1]["values"]["DB10.n"] == 100
    assert trace[1]["values"]["DB20.avg"] == 2.25
    assert trace[1]["values"]["DB20.motor[3]"] == {"on": True, "speed": 0}


@pytest.mark.parametrize(
    ("name", "why"),
    [
        ("DB10.speed", "DB10.speed: FB17 has no member speed; it has FINALVAL, CONTROL, n, hist"),
        ("DB10.hist[4]", "DB10.hist[4]: index 4 outside 1..3"),
        ("DB10.n[1]", "DB10.n[1]: INT is not an ARRAY"),
        ("DB99.x", "DB99.x: DB99 is not in this CPU"),
        (
            '"Oven".x',
            '"Oven".x: no DB is named "Oven" (name it in the symbol table: "Oven" ; DB n)',
        ),
        ("DB10.hist[x]", "DB10.hist[x]: cannot read '[x]'"),
    ],
)
def test_a_db_variable_that_is_not_there_is_one_line_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], name: str, why: str
) -> None:
    f = _write(tmp_path, seq_s7g=CHART, blocks_scl=BLOCKS)
    rc, trace, err = _sim(capsys, f["seq_s7g"], "--blocks", f["blocks_scl"], "--watch", name)
    assert rc == 2 and trace == []
    assert err.splitlines() == [f"s7graph: error: {why}"]


@pytest.mark.parametrize("source", ["seq_s7g", "blocks_scl"])
@pytest.mark.parametrize(
    ("name", "why"),
    [
        ("M10.8", "bit 8 outside 0..7"),
        ("DB10.DBX99999.0", "byte/number 99999 outside 0..65535"),
        ("DB0.DBW0", "DB number 0 outside 1..65535"),
        ("MW1.3", "misaligned: a WORD address has no bit number"),
    ],
)
def test_an_address_out_of_its_range_is_refused_as_the_address_it_is(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], source: str, name: str, why: str
) -> None:
    """Watched or set by a stimulus, in a chart's run as in a program's. Before: ``unknown
    name M10.8: not an address, symbol …``, ``DB10.DBX99999.0: cannot read '.0'``."""
    f = _write(tmp_path, seq_s7g=CHART, blocks_scl=BLOCKS, s_jsonl="")
    said = f"s7graph: error: bad address {name!r}: {why}"
    f["s_jsonl"].write_text(json.dumps({"at_ms": 0, "set": {name: 1}}) + "\n")
    blocks = ["--blocks", f["blocks_scl"]] if source == "seq_s7g" else []
    rc, trace, err = _sim(capsys, f[source], *blocks, "--watch", name)
    assert (rc, trace, err.splitlines()) == (2, [], [said])
    rc, trace, err = _sim(capsys, f[source], *blocks, "--stimulus", f["s_jsonl"])
    assert (rc, trace) == (2, [])
    assert err.splitlines() == [said.replace("error: ", f"error: {f['s_jsonl']}:1: ")]


def test_a_program_calls_the_blocks_of_an_earlier_source(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    program = """
ORGANIZATION_BLOCK OB1
VAR_TEMP t : INT; END_VAR
  FB17.DB3(FINALVAL := 2);
  FC5(x := DB3.n, twice := t);
  MW0 := INT_TO_WORD(t);
END_ORGANIZATION_BLOCK
"""
    lib = BLOCKS.split("ORGANIZATION_BLOCK")[0]
    f = _write(tmp_path, main_scl=program, lib_scl=lib)
    args = [f["main_scl"], "--blocks", f["lib_scl"], "--cycles", "3"]
    rc, trace, err = _sim(capsys, *args, "--watch", "MW0,DB3.n,DB3.CONTROL")
    assert rc == 0 and err == ""
    assert [line["values"] for line in trace] == [
        {"MW0": 2, "DB3.n": 1, "DB3.CONTROL": False},
        {"MW0": 4, "DB3.n": 2, "DB3.CONTROL": True},
        {"MW0": 6, "DB3.n": 3, "DB3.CONTROL": True},
    ]
    assert all(line["active"] == [] and line["events"] == [] for line in trace)


def test_a_block_written_in_two_sources_is_refused_naming_both(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    f = _write(tmp_path, a_scl=BLOCKS, b_scl=BLOCKS.split("FUNCTION FC5")[0])
    rc, trace, err = _sim(capsys, f["b_scl"], "--blocks", f["a_scl"])
    assert rc == 2 and trace == []
    assert err.splitlines() == [f"{f['b_scl']}:2:1: error: FB17 is written in {f['a_scl']}:2:1 too"]


def test_a_source_of_the_chart_that_does_not_compile_is_its_diagnostics_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    f = _write(tmp_path, seq_s7g=CHART, blocks_scl=BLOCKS.replace("n + 1", "n + speed"))
    rc, trace, err = _sim(capsys, f["seq_s7g"], "--blocks", f["blocks_scl"])
    assert rc == 2 and trace == []
    why = "error[E211]: unknown name 'speed' (FB17)"
    assert err.splitlines()[0] == f"{f['blocks_scl']}:6:12: {why}"


def test_a_source_that_writes_the_charts_own_fb_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    clash = "FUNCTION_BLOCK FB1\nVAR x : INT; END_VAR\n  x := 1;\nEND_FUNCTION_BLOCK\n"
    f = _write(tmp_path, seq_s7g=CHART, blocks_scl=clash)
    rc, trace, err = _sim(capsys, f["seq_s7g"], "--blocks", f["blocks_scl"])
    assert rc == 2 and trace == []
    assert err == "s7graph: error: FB1 of the chart is written in a source too\n"


def test_without_blocks_a_chart_calls_nothing_but_the_system_blocks_as_before(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    f = _write(tmp_path, seq_s7g=CHART)
    rc, _, err = _sim(capsys, f["seq_s7g"], "--cycles", "1")
    assert rc == 1  # the permanent instruction's FC5 stops the CPU in cycle 0
    assert "warning: CALL FC 5: FC5 is not in this CPU" in err


TYPES = """
FUNCTION_BLOCK FB1
VAR i : INT := -5; d : DINT := -70000; b : BYTE := 16#FF; w : WORD := 16#FFFF;
  dw : DWORD := 16#FFFFFFFF; r : REAL := 1.5; t : TIME := T#1S500MS;
  tod : TIME_OF_DAY := TOD#01:00:00; da : DATE := D#2026-01-02;
  dt : DATE_AND_TIME := DT#2026-01-02-03:04:05; c : CHAR := 'A'; s : STRING[8] := 'abc';
  x : BOOL := TRUE;
END_VAR
END_FUNCTION_BLOCK
DATA_BLOCK DB2
STRUCT i : INT := -5; w : WORD := 16#FFFF; dw : DWORD := 16#FFFFFFFF; r : REAL := 1.5;
  t : TIME := T#1S500MS; c : CHAR := 'A'; s : STRING[8] := 'abc'; END_STRUCT
BEGIN
END_DATA_BLOCK
ORGANIZATION_BLOCK OB1
  FB1.DB1();
END_ORGANIZATION_BLOCK
"""


def test_trace_values_of_db_variables_keep_their_types(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    f = _write(tmp_path, types_scl=TYPES)
    names = ["i", "d", "b", "w", "dw", "r", "t", "tod", "da", "dt", "c", "s", "x"]
    watch = ",".join(
        [f"DB1.{n}" for n in names] + [f"DB2.{n}" for n in ["i", "w", "dw", "r", "t", "c", "s"]]
    )
    rc, trace, err = _sim(capsys, f["types_scl"], "--cycles", "1", "--watch", watch)
    assert rc == 0, err
    values = trace[0]["values"]
    assert values == {
        "DB1.i": -5,
        "DB1.d": -70000,
        "DB1.b": 255,
        "DB1.w": 65535,
        "DB1.dw": 4294967295,
        "DB1.r": 1.5,
        "DB1.t": 1500,
        "DB1.tod": 3600000,
        "DB1.da": "2026-01-02",
        "DB1.dt": "2026-01-02 03:04:05",
        "DB1.c": "A",
        "DB1.s": "abc",
        "DB1.x": True,
        "DB2.i": -5,
        "DB2.w": 65535,
        "DB2.dw": 4294967295,
        "DB2.r": 1.5,
        "DB2.t": 1500,
        "DB2.c": "A",
        "DB2.s": "abc",
    }


def test_an_scl_programs_global_dbs_are_watched_and_set_by_name_in_their_types(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    program = """
DATA_BLOCK DB20
STRUCT warm : BOOL; count : INT; mask : WORD; wait : TIME;
  motor : ARRAY[1..2] OF STRUCT on : BOOL; END_STRUCT;
END_STRUCT
BEGIN count := -3; mask := 16#8001; wait := T#2S;
END_DATA_BLOCK
DATA_BLOCK DB21
STRUCT temps : ARRAY[1..3] OF REAL; END_STRUCT
BEGIN temps[2] := 1.5;
END_DATA_BLOCK
ORGANIZATION_BLOCK OB1
VAR_TEMP info : ARRAY[0..19] OF BYTE; END_VAR
BEGIN
  DB20.count := DB20.count + 1;
  DB20.motor[2].on := DB20.warm;
END_ORGANIZATION_BLOCK
"""
    stim = '{"at_ms": 10, "set": {"DB20.warm": true, "\\"DB21\\".temps[3]": -2.25}}\n'
    f = _write(tmp_path, prog_scl=program, stim_jsonl=stim)
    watch = 'DB20.warm,DB20.count,DB20.mask,DB20.wait,"DB21".temps[3],DB20.motor[2].on'
    args = [f["prog_scl"], "--stimulus", f["stim_jsonl"], "--cycles", "3", "--watch", watch]
    rc, trace, err = _sim(capsys, *args)
    assert rc == 0, err
    assert trace[0]["values"] == {
        "DB20.warm": False,
        "DB20.count": -2,
        "DB20.mask": 0x8001,
        "DB20.wait": 2000,
        '"DB21".temps[3]': 0.0,
        "DB20.motor[2].on": False,
    }
    assert trace[2]["values"]["DB20.count"] == 0
    assert trace[2]["values"]['"DB21".temps[3]'] == -2.25
    assert trace[2]["values"]["DB20.motor[2].on"] is True


SYMBOLS = """\
"Data" ; DB 21 ; DB 21 ; recipe temperatures
"Plant" ; DB 20 ; DB 20
"Counter" ; FB 17 ; FB 17
"Start" ; I0.0 ; BOOL
"Gone" ; DB 99 ; DB 99
"""

NAMED_DBS = """
DATA_BLOCK DB20
STRUCT warm : BOOL; END_STRUCT
END_DATA_BLOCK
DATA_BLOCK "Data"
STRUCT temps : ARRAY[1..3] OF REAL; END_STRUCT
BEGIN temps[2] := 1.5;
END_DATA_BLOCK
"""


def test_the_symbol_tables_db_rows_name_dbs_for_watch_and_stimulus(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    stim = '{"at_ms": 10, "set": {"\\"Plant\\".warm": true, "\\"Data\\".temps[3]": -2.5}}\n'
    f = _write(
        tmp_path, seq_s7g=CHART, blocks_scl=BLOCKS + NAMED_DBS, sym_txt=SYMBOLS, stim_jsonl=stim
    )
    watch = '"Plant".warm,"Data".temps[2],"Data".temps[3],DB21.temps[3]'
    args = ["--blocks", f["blocks_scl"], "--symbols", f["sym_txt"], "--watch", watch]
    rc, trace, err = _sim(
        capsys, f["seq_s7g"], *args, "--stimulus", f["stim_jsonl"], "--cycles", "3"
    )
    assert rc == 0, err
    assert trace[0]["values"] == {
        '"Plant".warm': False,
        '"Data".temps[2]': 1.5,
        '"Data".temps[3]': 0.0,
        "DB21.temps[3]": 0.0,
    }
    assert trace[2]["values"]['"Plant".warm'] is True
    assert trace[2]["values"]["DB21.temps[3]"] == -2.5


@pytest.mark.parametrize(
    ("name", "why"),
    [
        ('"Counter".n', '"Counter".n: "Counter" is FB 17, not a DB'),
        ('"Start".x', '"Start".x: "Start" is the operand I0.0, not a DB'),
        ('"Gone".x', '"Gone".x: DB99 is not in this CPU'),
    ],
)
def test_a_symbol_that_names_no_loaded_db_is_one_line_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], name: str, why: str
) -> None:
    f = _write(tmp_path, seq_s7g=CHART, blocks_scl=BLOCKS + NAMED_DBS, sym_txt=SYMBOLS)
    args = ["--blocks", f["blocks_scl"], "--symbols", f["sym_txt"], "--watch", name]
    rc, trace, err = _sim(capsys, f["seq_s7g"], *args)
    assert rc == 2 and trace == []
    assert err.splitlines() == [f"s7graph: error: {why}"]


INOUT = """
FUNCTION FC6 : VOID
VAR_IN_OUT io : INT; END_VAR
  io := io + 1;
END_FUNCTION
FUNCTION_BLOCK FB6
VAR_IN_OUT io : INT; END_VAR
  io := io + 10;
END_FUNCTION_BLOCK
FUNCTION FC7 : VOID
VAR_INPUT r : REAL; END_VAR
VAR_OUTPUT twice : REAL; END_VAR
  twice := 2.0 * r;
END_FUNCTION
"""


def test_a_charts_call_passes_its_operand_so_an_in_out_is_written_back(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """S7 hands a block the operand itself: an in/out parameter given ``MW0`` is written
    back there (FC and FB alike), and a REAL parameter given ``MD4`` reads its bits as a
    REAL; a constant or a chart variable for an in/out parameter is E047 at the call."""
    chart = CHART.replace(
        "CALL FB 17, DB 10 (FINALVAL := 3, CONTROL => done);",
        "CALL FC 6 (io := MW0); CALL FB 6, DB 6 (io := MW2); CALL FC 7 (r := MD4, twice => MD8);",
    ).replace("CALL FC 5 (x := MW10, twice => MW12);", "")
    f = _write(
        tmp_path,
        seq_s7g=chart,
        blocks_scl=INOUT,
        stim_jsonl='{"at_ms": 0, "set": {"I0.0": true, "MD4": 1.5}}\n',
    )
    args = [f["seq_s7g"], "--blocks", f["blocks_scl"], "--stimulus", f["stim_jsonl"]]
    rc, trace, err = _sim(capsys, *args, "--cycles", "4", "--watch", "MW0,MW2,MD8")
    assert rc == 0, err
    assert [line["values"]["MW0"] for line in trace] == [1, 2, 3, 4]  # S2 from cycle 0
    assert [line["values"]["MW2"] for line in trace] == [10, 20, 30, 40]
    assert trace[-1]["values"]["MD8"] == 0x40400000  # 3.0
    bad = chart.replace("(io := MW0)", "(io := 5)")
    f = _write(tmp_path, bad_s7g=bad)
    rc = main(["check", str(f["bad_s7g"]), "--blocks", str(tmp_path / "blocks.scl")])
    out, err = capsys.readouterr()
    assert rc == 2 and "error[E047]: FC6: io is an in/out parameter" in out + err
