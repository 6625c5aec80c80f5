"""``s7graph xref`` (``web/cli/xref.py``; docs/cli.md, "s7graph xref"): the drill's
cross-references as text and JSON, one operand's uses by symbol or address, exit 1 for an
operand the chart never uses, exit 2 with the diagnostics for a chart that does not parse
and one line for a file that cannot be read; with the S7-SCL blocks beside a chart
(``--blocks``) their uses too; and through the real command line."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from s7graph.web.cli.xref import xref_command
from tests.paths import ROOT
from tests.sequencer.helpers import BROKEN

DRILL = ROOT / "examples" / "drill" / "drill.s7g"
SYMBOLS = ROOT / "examples" / "drill" / "symbols.txt"
OVEN = ROOT / "examples" / "oven"


def test_one_operand_by_its_symbol_or_address(capsys: pytest.CaptureFixture[str]) -> None:
    assert xref_command(DRILL, symbols=SYMBOLS, operand='"Clamp_workp"') == 0
    by_symbol = capsys.readouterr().out.splitlines()
    assert by_symbol == [
        '"Clamp_workp" (Q0.4)',
        f'  S2 "Clamp" row 1 (S1 S)    set    {DRILL}:24:10',
        f'  S7 "Release" row 3 (S1 R)  reset  {DRILL}:41:51',
    ]
    assert xref_command(DRILL, symbols=SYMBOLS, operand="q0.4") == 0
    assert capsys.readouterr().out.splitlines() == by_symbol


def test_the_whole_list_as_json(capsys: pytest.CaptureFixture[str]) -> None:
    assert xref_command(DRILL, symbols=SYMBOLS, as_json=True) == 0
    found = json.loads(capsys.readouterr().out)
    assert found["unused"] == []
    assert found["operands"]['"Start_button" (I0.7)'] == [
        {"element": 'T1 "Start"', "access": "read", "at": f"{DRILL}:43:42"}
    ]
    assert list(found["operands"]) == sorted(found["operands"], key=str.casefold)


def test_an_unused_operand_exits_1_and_a_broken_chart_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert xref_command(DRILL, operand="M99.0") == 1
    assert capsys.readouterr().err == f"s7graph: no use of M99.0 in {DRILL}\n"
    broken = BROKEN / "E001_missing_semicolon.s7g"
    assert xref_command(broken) == 2
    assert f"{broken}:" in capsys.readouterr().err
    assert xref_command(tmp_path / "none.s7g") == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("s7graph: error: cannot read")


def test_the_command_line_lists_unused_symbols_last(tmp_path: Path) -> None:
    chart = tmp_path / "spare.s7g"
    chart.write_text(
        """FUNCTION_BLOCK "Seq_spare"
SYMBOLS "Go" : I0.0 : BOOL; "Spare" : M9.0 : BOOL; END_SYMBOLS
SEQUENCE 1 "S"
  INITIAL_STEP S1 "A": END_STEP
  STEP S2 "B": END_STEP
  TRANSITION T1 FROM S1 TO S2 := "Go";
  TRANSITION T2 FROM S2 TO S1 := NOT "Go";
END_SEQUENCE
END_FUNCTION_BLOCK
""",
        encoding="utf-8",
    )
    proc = subprocess.run(
        [sys.executable, "-m", "s7graph", "xref", str(chart)],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.splitlines() == [
        '"Go" (I0.0)',
        f"  T1  read  {chart}:6:34",
        f"  T2  read  {chart}:7:38",
        'unused symbols: "Spare"',
    ]


def test_the_blocks_beside_a_chart_list_their_uses_after_the_charts(
    capsys: pytest.CaptureFixture[str],
) -> None:
    chart, scl, symbols = OVEN / "oven.s7g", OVEN / "oven.scl", OVEN / "symbols.txt"
    assert xref_command(chart, symbols=symbols, operand="Oven_temp", blocks=[scl]) == 0
    assert capsys.readouterr().out.splitlines() == [
        '"Oven_temp" (MD14)',
        f'  T2 "Temperature reached"  read   {chart}:42:56',
        f'  T4 "Cooled"               read   {chart}:44:43',
        f"  OB 35                     write  {scl}:32:3",
    ]
    assert xref_command(chart, symbols=symbols, as_json=True) == 0
    assert '"Heater" (Q12.0)' not in json.loads(capsys.readouterr().out)["operands"]
    assert xref_command(chart, symbols=symbols, as_json=True, blocks=[scl]) == 0
    both = json.loads(capsys.readouterr().out)
    assert both["operands"]['"Heater" (Q12.0)'][0]["access"] == "write"
    assert {"element": "OB 35", "access": "read", "at": f"{scl}:34:43"} in both["operands"][
        '"Setpoint" (MD10)'
    ]  # an input of CONT_C (SFB41): its interface says so
    assert [u["access"] for u in both["operands"]["DB 41"]] == ["instance", "instance"]


def test_a_block_source_that_does_not_parse_is_its_diagnostic_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = tmp_path / "bad.scl"
    bad.write_text("FUNCTION FC1 : VOID\nBEGIN\n  M0.0 := ;\nEND_FUNCTION\n", encoding="utf-8")
    assert xref_command(DRILL, blocks=[bad]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"{bad}:3:") and "Traceback" not in err
    assert xref_command(DRILL, blocks=[tmp_path / "none.scl"]) == 2
    assert capsys.readouterr().err.startswith("s7graph: error: cannot read")


def test_an_scl_program_alone_lists_the_uses_in_its_blocks(
    capsys: pytest.CaptureFixture[str],
) -> None:
    program = ROOT / "examples" / "scl_guide" / "setpoint.scl"
    assert xref_command(program, operand="MW0") == 0
    assert capsys.readouterr().out.splitlines() == [
        "MW0",
        f"  OB 100  write  {program}:5:3",
        f"  OB 35   read   {program}:13:20",
        f"  OB 35   write  {program}:22:3",
    ]
    assert xref_command(program, operand="STP") == 0  # stp(): the system's SFC46 by its name
    assert capsys.readouterr().out.splitlines() == ['"STP"', f"  OB 35  call  {program}:20:5"]
    assert xref_command(OVEN / "oven.scl", symbols=OVEN / "symbols.txt", operand='"Heater"') == 0
    assert capsys.readouterr().out.splitlines()[0] == '"Heater" (Q12.0)'
