"""The command line: usage errors are one line on stderr naming the problem, exit 2."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from s7graph.web.cli import main
from tests.paths import EXAMPLES
from tests.web.cli.test_refusal_kind import answering


@pytest.mark.parametrize(
    ("argv", "expected"),
    [
        (["run", "--max-cycle-ms", "abc", "x.py"], "Invalid value for '--max-cycle-ms'"),
        (["frob"], "No such command 'frob'"),
        (["sim"], "give CHART: a chart in .s7g source"),
    ],
)
def test_a_usage_error_is_one_stderr_line_and_exit_2(
    argv: list[str], expected: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(argv) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("s7graph: error: ") and expected in err[0]


@pytest.mark.parametrize(
    ("argv", "help_of"),
    [
        (["sim"], "s7graph sim --help"),
        (["export", "x.s7g", "-o", "x.xml"], "s7graph export --help"),
        (["users", "add"], "s7graph users add --help"),
        (["chek"], "s7graph --help"),
    ],
)
def test_a_usage_error_points_at_the_help_of_its_own_command(
    argv: list[str], help_of: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(argv) == 2
    assert capsys.readouterr().err.rstrip().endswith(f"(see {help_of})")


@pytest.mark.parametrize(("argv", "group"), [([], "s7graph"), (["users"], "s7graph users")])
def test_a_group_given_no_command_prints_its_help_and_asks_for_one(
    argv: list[str], group: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """Never the empty error typer leaves (``s7graph: error:  (see s7graph --help)``)."""
    assert main(argv) == 2
    out, err = capsys.readouterr()
    assert "Commands" in out
    assert err == f"s7graph: error: give a command of {group}: one of those listed above\n"


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
    from s7graph.web.bus.protocol import CommandReply
    from s7graph.web.cli import remote
    from s7graph.web.cli.net import NetOptions

    answering(
        monkeypatch, CommandReply(applied=False, reason="no answer from CPU 'cpu1' within 30 s")
    )
    chart = tmp_path / "c.s7g"
    chart.write_text((EXAMPLES / "drill" / "drill.s7g").read_text(encoding="utf-8"))
    rc = remote.download_command(NetOptions(), chart, fb=None, user="eng", yes=True)
    assert rc == 1
    err = capsys.readouterr().err
    assert err.startswith("s7graph: download not confirmed: no answer from CPU 'cpu1'")
    assert "may or may not have taken effect" in err and "refused" not in err


def test_a_download_refused_for_its_blocks_names_each_source_as_the_command_line_gave_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """The CPU knows a source by its file name; its diagnostics are said in the path given,
    as a chart's are, so an editor finds the place."""
    from s7graph.web.bus.protocol import CommandReply
    from s7graph.web.cli import remote
    from s7graph.web.cli.net import NetOptions

    said = "valve.scl:13:12: error[E201]: unexpected ';'"
    why = f"the S7-SCL blocks do not compile: 1 error(s); {said}"
    answering(
        monkeypatch,
        CommandReply(applied=False, reason=why, lines=[said, "old.valve.scl:1:1: x"]),
    )
    chart = tmp_path / "c.s7g"
    chart.write_text((EXAMPLES / "drill" / "drill.s7g").read_text(encoding="utf-8"))
    (tmp_path / "v2").mkdir()
    valve = tmp_path / "v2" / "valve.scl"
    valve.write_text("FUNCTION FC1 : VOID\nEND_FUNCTION\n", encoding="utf-8")
    rc = remote.download_command(NetOptions(), chart, fb=None, user="eng", yes=True, blocks=[valve])
    assert rc == 1
    assert capsys.readouterr().err.splitlines() == [
        f"s7graph: download refused: the S7-SCL blocks do not compile: 1 error(s); {valve}:13:12:"
        " error[E201]: unexpected ';'",
        f"  {valve}:13:12: error[E201]: unexpected ';'",
        "  old.valve.scl:1:1: x",
    ]


@pytest.mark.parametrize("command", ["check", "sim", "xref"])
def test_a_python_program_given_for_a_chart_is_named_for_what_it_is(
    command: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """Before: the program read as a chart, twenty syntax errors (``unexpected 'MB0';
    expected 'FUNCTION_BLOCK'``)."""
    blink = EXAMPLES / "blink.py"
    assert main([command, str(blink)]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err == (
        f"s7graph: error: {blink}: a Python program of blocks; {command} takes a chart (.s7g) "
        "or an S7-SCL source (.scl) (s7graph run runs a program)\n"
    )


@pytest.mark.parametrize(
    ("command", "suffix"), [("check", ".xml"), ("run", ".xml"), ("sim", ".st")]
)
def test_a_chart_written_elsewhere_is_sent_to_import_first(
    tmp_path: Path, command: str, suffix: str, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / f"Graph{suffix}"
    path.write_text("<Document/>")
    assert main([command, str(path)]) == 2
    (line,) = capsys.readouterr().err.splitlines()
    assert line.startswith(f"s7graph: error: {path}: a chart in ")
    assert line.endswith(f": import it first (s7graph import {path} -o Graph.s7g)")


def test_web_refuses_a_port_out_of_range_before_it_waits_for_a_cpu(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Before: ``waiting for a CPU`` until ``--duration-s`` ended it, the port never said."""
    import time

    began = time.monotonic()
    assert main(["web", "--port", "99999", "--duration-s", "60"]) == 2
    assert time.monotonic() - began < 30
    assert capsys.readouterr().err == (
        "s7graph: error: Invalid value for '--port': from 0 (a free one) to 65535, not 99999 "
        "(see s7graph web --help)\n"
    )


@pytest.mark.parametrize(
    ("text", "name", "said"),
    [
        ("import sys\nsys.exit(5)\n", "quits.py", "quits.py:2: plant: SystemExit: 5"),
        ('{"at_ms": 0, "set": {}}\n', "s.jsonl", "a plant is a Python file (.py)"),
    ],
)
def test_a_plant_file_that_does_not_load_is_one_line_naming_why(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str, name: str, said: str
) -> None:
    """Before: ``sys.exit(5)`` in a plant's file ended ``sim`` silently with exit 5, and a
    file that is no Python was ``cannot load plant file`` without a reason."""
    plant = tmp_path / name
    plant.write_text(text)
    drill = EXAMPLES / "drill"
    argv = ["sim", str(drill / "drill.s7g"), "--symbols", str(drill / "symbols.txt")]
    assert main([*argv, "--cycles", "1", "--plant", str(plant)]) == 2
    out, err = capsys.readouterr()
    assert out == "" and len(err.splitlines()) == 1
    assert err.startswith("s7graph: error: ") and said in err


@pytest.mark.parametrize("command", ["run", "check", "mode", "watch", "users add"])
def test_the_help_says_types_in_words_not_pythons(
    command: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """typer 0.2x prints an option's Python type (``--blocks <list[Path]>``, ``--web
    <bool>``); the help says ``FILE...``, ``NUMBER``, ``TEXT``, and nothing for a flag."""
    assert main([*command.split(), "--help"]) == 0
    out = capsys.readouterr().out
    for python in ("<list[", "<bool>", "<path>", "<float>", "<int>", "<str>", "Path]"):
        assert python not in out
    assert "FILE" in out or "TEXT" in out


@pytest.mark.parametrize(
    ("shown", "words"),
    [
        ("<list[Path]>", "FILE..."),
        ("<list[str]>", "TEXT..."),
        ("<bool>", ""),
        ("<float>", "NUMBER"),
        ("<int>", "INTEGER"),
        ("<warm|hot|cold>", "warm|hot|cold"),
    ],
)
def test_each_python_type_of_the_help_has_its_word(shown: str, words: str) -> None:
    from s7graph.web.cli.root import _type_words

    assert _type_words(shown) == words


def test_export_or_import_onto_its_own_source_is_refused_and_the_source_kept(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Before: ``export drill.s7g --to plcopen -o drill.s7g`` wrote the XML over the chart
    (exit 1: "exported"), and ``import x.xml -o x.xml`` the chart over the XML."""
    drill = EXAMPLES / "drill"
    chart = tmp_path / "drill.s7g"
    chart.write_bytes((drill / "drill.s7g").read_bytes())
    symbols = ["--symbols", str(drill / "symbols.txt")]
    same = str(tmp_path / "." / "drill.s7g")  # another spelling of the same file
    assert main(["export", str(chart), *symbols, "--to", "plcopen", "-o", same]) == 2
    assert capsys.readouterr().err == (
        f"s7graph: error: -o {same} is the chart exported: give the export a file of its own\n"
    )
    assert chart.read_bytes() == (drill / "drill.s7g").read_bytes()
    assert main(["import", str(chart), "-o", str(chart)]) == 2
    assert "is the file imported: give the chart a file of its own" in capsys.readouterr().err
    assert chart.read_bytes() == (drill / "drill.s7g").read_bytes()


@pytest.mark.timeout(120)
def test_ctrl_c_ends_a_sim_between_two_cycles_keeping_the_trace(tmp_path: Path) -> None:
    """Before: the interrupt struck inside the FB's call and was said as its programming
    error (``the CPU went to STOP: OB1: KeyboardInterrupt``, exit 1)."""
    import signal
    import time

    drill = EXAMPLES / "drill"
    trace = tmp_path / "t.jsonl"
    args = ["sim", str(drill / "drill.s7g"), "--symbols", str(drill / "symbols.txt")]
    proc = subprocess.Popen(
        [sys.executable, "-m", "s7graph", *args, "--cycles", "100000000", "--trace", str(trace)],
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    deadline = time.monotonic() + 60
    while (not trace.exists() or trace.stat().st_size < 10_000) and time.monotonic() < deadline:
        time.sleep(0.05)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == 130, err
    lines = trace.read_text().splitlines()
    assert err == f"s7graph: sim stopped by Ctrl-C: the trace holds cycles 0 to {len(lines) - 1}\n"
    assert '"cycle": 0,' in lines[0]
