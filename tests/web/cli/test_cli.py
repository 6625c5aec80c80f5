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


def test_download_says_bytes_that_are_not_utf8_where_they_are_as_check_does(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    chart = tmp_path / "mine.s7g"
    chart.write_bytes(b'FUNCTION_BLOCK "X" FB 1 DB 1\n(* caf\xff *)\n')
    assert main(["download", str(chart), "--user", "u", "--connect", "tcp/127.0.0.1:1"]) == 2
    assert capsys.readouterr().err == (
        f"s7graph: error: {chart}:2:7: not UTF-8: byte 0xff (invalid start byte)\n"
    )


def test_a_watcher_whose_reader_went_ends_quietly(monkeypatch: pytest.MonkeyPatch) -> None:
    """``s7graph watch … | head -1``: the next line meets a closed pipe — the watch ends
    (its stop set), no traceback of a broken pipe."""
    import os
    import threading

    from s7graph.web.cli.stopping import say

    read, write = os.pipe()
    os.close(read)
    out = os.fdopen(write, "w")
    monkeypatch.setattr(sys, "stdout", out)
    stop = threading.Event()
    say("cycle 1 RUN  MW0=W#16#0000", stop)
    assert stop.is_set()
    say("cycle 2 RUN  MW0=W#16#0001", stop)  # stdout is /dev/null now: nothing raised
    out.close()


def test_a_download_sent_without_an_answer_says_it_may_have_taken_effect(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """The CPU may swap the chart, then go before it answers: no answer is not a refusal
    (docs/durability.md) — the download is *not confirmed*, and says where to look."""
    import contextlib

    from s7graph.web.bus.protocol import CommandReply
    from s7graph.web.cli import remote
    from s7graph.web.cli.net import NetOptions

    class Shell:
        fb = "Seq"

        def send(self, kind: object, args: object, timeout: float) -> CommandReply:
            if getattr(args, "preview", False):
                return CommandReply(applied=True, version=3, lines=["S2: renamed"])
            return CommandReply(applied=False, reason="no answer from CPU 'cpu1' within 30 s")

    @contextlib.contextmanager
    def logged_in(*_: object, **__: object):  # type: ignore[no-untyped-def]
        yield Shell()

    monkeypatch.setattr(remote, "_logged_in", logged_in)
    chart = tmp_path / "c.s7g"
    chart.write_text((EXAMPLES / "drill" / "drill.s7g").read_text(encoding="utf-8"))
    rc = remote.download_command(NetOptions(), chart, fb=None, user="eng", yes=True)
    assert rc == 1
    err = capsys.readouterr().err
    assert err.startswith("s7graph: download not confirmed: no answer from CPU 'cpu1'")
    assert "may or may not have taken effect" in err and "refused" not in err
