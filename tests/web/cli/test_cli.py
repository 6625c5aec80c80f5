"""The command line: usage errors are one line on stderr naming the problem, exit 2."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from s7graph.web.cli import main
from tests.paths import EXAMPLES


@pytest.mark.parametrize(
    ("argv", "expected"),
    [
        (["run", "--max-cycle-ms", "abc", "x.py"], "Invalid value for '--max-cycle-ms'"),
        (["frob"], "No such command 'frob'"),
        (["sim"], "Missing argument 'chart'"),
    ],
)
def test_a_usage_error_is_one_stderr_line_and_exit_2(
    argv: list[str], expected: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(argv) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("s7graph: error: ") and expected in err[0]


def test_version_prints_the_distribution_version(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--version"]) == 0
    assert capsys.readouterr().out.startswith("s7graph ")


def test_a_command_is_built_alone_and_the_help_lists_them_all(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The command line builds the command it runs, not the others (typer reads each
    command's signature); ``--help`` and a misspelled name get the whole group."""
    from s7graph.web.cli import root

    assert list(root._command("check").commands) == ["check"]
    assert {"check", "run", "sim", "ack", "mode", "opcua"} <= set(root._command("").commands)
    assert main(["mode", "--help"]) == 0
    assert " mode [OPTIONS]" in capsys.readouterr().out
    assert main(["--help"]) == 0
    assert "download" in capsys.readouterr().out
    assert main(["chek"]) == 2
    assert "No such command 'chek'" in capsys.readouterr().err


def test_check_loads_no_viser_zenoh_or_numpy() -> None:
    """``s7graph check`` starts fast: it imports only what checking a chart needs (the
    view's and the bus's libraries are imported by ``run`` alone)."""
    drill = EXAMPLES / "drill"
    args = [str(drill / "drill.s7g"), "--symbols", str(drill / "symbols.txt")]
    probe = (
        "import sys\n"
        "from s7graph.web.cli import main\n"
        f"rc = main(['check', *{args!r}])\n"
        "print(rc, *(m for m in ('viser', 'zenoh', 'numpy') if m in sys.modules))\n"
    )
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True)
    assert out.stdout.splitlines()[-1] == "0"


def test_an_internal_error_of_a_command_is_one_line_in_words(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """A defect of ours that reaches the command line's last guard: which command, what
    it said, a request to report it — never the exception's class name nor a traceback."""
    from s7graph.web.cli import root

    def broken(**kwargs: object) -> int:
        raise KeyError("x")

    monkeypatch.setattr(root, "_command", lambda name="": broken)
    assert main(["check", "--quiet", "drill.s7g"]) == 2
    err = capsys.readouterr().err
    assert err == (
        "s7graph: an internal error while running s7graph check: 'x' (please report it)\n"
    )


def test_download_says_a_syntax_error_in_its_own_files_name_before_the_bus(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    chart = tmp_path / "mine.s7g"
    chart.write_text(
        'FUNCTION_BLOCK "X" FB 1 DB 1\nSEQUENCE 1 "s"\n  INITIAL_STEP S1: END_STEP\n'
        "  TRANSITION T1 FROM S1 TO S1 := I0.0 AND (;\nEND_SEQUENCE\nEND_FUNCTION_BLOCK\n",
        encoding="utf-8",
    )
    assert main(["download", str(chart), "--user", "u", "--connect", "tcp/127.0.0.1:1"]) == 2
    err = capsys.readouterr().err.splitlines()
    assert err[0].startswith(f"{chart}:4:44: error[E001]: unexpected ';'")
    assert err[-1].startswith(f"s7graph: error: {chart}: not downloaded: ")
    assert not any("join the bus" in line for line in err)
