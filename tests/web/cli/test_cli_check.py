"""``s7graph check`` prints one line per diagnostic plus a summary; exit 0/1/2
(docs/chart-format.md)."""

from __future__ import annotations

from pathlib import Path

import pytest

from s7graph.web.cli.check import check_command
from tests.sequencer.helpers import BROKEN, CHARTS


def test_clean_chart_exits_0_with_a_summary(capsys: pytest.CaptureFixture[str]) -> None:
    path = CHARTS / "linear.s7g"
    assert check_command(path, None) == 0
    assert capsys.readouterr().out.splitlines() == [f"{path}: 0 errors, 0 warnings"]


def test_warnings_only_exit_1(capsys: pytest.CaptureFixture[str]) -> None:
    path = BROKEN / "W120_empty_condition.s7g"
    assert check_command(path, None) == 1
    lines = capsys.readouterr().out.splitlines()
    assert lines == [
        f"{path}:5:3: warning[W120]: transition T1 has no condition; it switches at once "
        "(transition T1)",
        f"{path}: 0 errors, 1 warning",
    ]


def test_errors_exit_2_syntax_errors_included(capsys: pytest.CaptureFixture[str]) -> None:
    assert check_command(BROKEN / "E010_unknown_step_in_to.s7g", None) == 2
    assert check_command(BROKEN / "E001_missing_semicolon.s7g", None) == 2
    out = capsys.readouterr().out
    assert "error[E010]" in out and "error[E001]" in out


def test_unreadable_file_is_one_stderr_line_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert check_command(tmp_path / "missing.s7g", None) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and len(captured.err.splitlines()) == 1


def test_symbol_file_resolves_quoted_names(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    chart = tmp_path / "c.s7g"
    chart.write_text(
        'FUNCTION_BLOCK "C"\nSEQUENCE 1\n  INITIAL_STEP S1: N "Lamp"; END_STEP\n'
        '  TRANSITION T1 FROM S1 TO S1 := "Go";\nEND_SEQUENCE\nEND_FUNCTION_BLOCK\n',
        encoding="utf-8",
    )
    syms = tmp_path / "s.txt"
    syms.write_text('"Go" ; I0.0 ; BOOL ; go\n"Lamp" ; Q0.0 ; BOOL ; lamp\n', encoding="utf-8")
    assert check_command(chart, None) == 2
    assert check_command(chart, syms) == 0


def test_a_waiting_step_without_actions_is_clean(tmp_path: Path) -> None:
    """A step may hold no action rows (STEP7 comprehensive guide vol. 2, ch. 14): waiting steps are
    idiomatic."""
    chart = tmp_path / "wait.s7g"
    chart.write_text(
        'FUNCTION_BLOCK "W"\nSEQUENCE 1\n  INITIAL_STEP S1: N Q0.0; END_STEP\n'
        "  STEP S2: END_STEP\n  TRANSITION T1 FROM S1 TO S2 := I0.0;\n"
        "  TRANSITION T2 FROM S2 TO S1 := I0.1;\nEND_SEQUENCE\nEND_FUNCTION_BLOCK\n",
        encoding="utf-8",
    )
    assert check_command(chart, None) == 0


def test_an_operand_beyond_a_default_cpus_memory_warns_naming_element_address_and_size(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``check`` knows no CPU: what a default CPU lacks warns (W140) — once per operand, at
    its first use, a symbol with its address; what fits it (M255.7, T255) does not."""
    chart = tmp_path / "far.s7g"
    chart.write_text(
        'FUNCTION_BLOCK "F"\nSEQUENCE 1\n'
        "  INITIAL_STEP S1: N M300.0; N M255.7; N Q0.0; END_STEP\n"
        "  STEP S2: N M300.0; END_STEP\n"
        "  TRANSITION T1 FROM S1 TO S2 := T300 AND T255;\n"
        '  TRANSITION T2 FROM S2 TO S1 := "Far" > 3;\nEND_SEQUENCE\nEND_FUNCTION_BLOCK\n',
        encoding="utf-8",
    )
    syms = tmp_path / "s.txt"
    syms.write_text('"Far" ; MW255 ; INT ; its second byte beyond MB255\n', encoding="utf-8")
    assert check_command(chart, syms) == 1
    tail = (
        ": a download refuses the chart, a run stops the CPU at its first use (unless the CPU "
        "has more)"
    )
    assert capsys.readouterr().out.splitlines() == [
        f"{chart}:3:22: warning[W140]: M300.0 is beyond the M area of a default CPU (256 bytes, "
        f"MB0 to MB255){tail} (step S1 row 1)",
        f"{chart}:5:34: warning[W140]: T300 is beyond the timers of a default CPU (256, T0 to "
        f"T255){tail} (transition T1)",
        f'{chart}:6:34: warning[W140]: "Far" (MW255) is beyond the M area of a default CPU (256 '
        f"bytes, MB0 to MB255){tail} (transition T2)",
        f"{chart}: 0 errors, 3 warnings",
    ]


def test_an_scl_sources_operands_beyond_a_default_cpus_memory_warn_naming_block_and_size(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``check SOURCE.scl`` gives an S7-SCL source the chart's W140: each absolute operand (a
    symbol's with its address) beyond a default CPU's memory, once, at its first use, with
    the block; what fits (MW254, %Q0.1, T255) and DB addresses do not warn."""
    from s7graph.web.cli.scl import check_scl_command

    source = tmp_path / "far.scl"
    source.write_text(
        "ORGANIZATION_BLOCK OB1\nVAR_TEMP x : BOOL; END_VAR\nBEGIN\n"
        "  x := %I200.0;\n  %MW254 := 1;\n  %MW300 := 5;\n  %Q0.1 := x AND %I200.0;\n"
        '  "Far" := 3;\n  %DB1.DBW900 := 2;\nEND_ORGANIZATION_BLOCK\n',
        encoding="utf-8",
    )
    syms = tmp_path / "s.txt"
    syms.write_text('"Far" ; MW255 ; INT ; its second byte beyond MB255\n', encoding="utf-8")
    assert check_scl_command(source, syms) == 1
    tail = ": a run stops the CPU at its first use (unless the CPU has more) (OB1)"
    assert capsys.readouterr().out.splitlines() == [
        f"{source}:4:8: warning[W140]: I200.0 is beyond the I area of a default CPU (128 bytes, "
        f"IB0 to IB127){tail}",
        f"{source}:6:3: warning[W140]: MW300 is beyond the M area of a default CPU (256 bytes, "
        f"MB0 to MB255){tail}",
        f'{source}:8:3: warning[W140]: "Far" (MW255) is beyond the M area of a default CPU (256 '
        f"bytes, MB0 to MB255){tail}",
        f"{source}: 0 errors, 3 warnings",
    ]
