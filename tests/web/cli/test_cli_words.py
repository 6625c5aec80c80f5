"""The command line in a shell user's words: a closed pipe ends quietly, a numeric option
given no number says what it takes, sim's refusals name their option, the usage line names
arguments in capitals (docs/cli.md)."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from s7graph.web.cli import main
from tests.paths import EXAMPLES

DRILL = [
    str(EXAMPLES / "drill" / "drill.s7g"),
    "--symbols",
    str(EXAMPLES / "drill" / "symbols.txt"),
]


def test_sim_piped_into_head_ends_quietly_with_sigpipes_status_when_the_reader_closes() -> None:
    """``s7graph sim CHART | head -3``: no traceback, no error line, exit 141 (128 + SIGPIPE)
    as ``yes | head``'s writer."""
    argv = [sys.executable, "-m", "s7graph.web.cli.root", "sim", *DRILL, "--cycles", "100000"]
    with subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE) as sim:
        assert sim.stdout is not None and sim.stderr is not None
        lines = [sim.stdout.readline() for _ in range(3)]
        sim.stdout.close()  # the reader goes away, as head does after 3 lines
        err = sim.stderr.read().decode()
        rc = sim.wait(60)
    assert [line.startswith(b'{"cycle": ') for line in lines] == [True] * 3
    assert (rc, err) == (141, "")


def test_a_short_trace_whose_reader_is_gone_ends_quietly_too(tmp_path) -> None:
    """The trace still buffered when the command ends meets the closed pipe at the last
    flush: the same quiet end, not Python's ``Exception ignored`` lines."""
    read_end, write_end = os.pipe()
    os.close(read_end)  # no reader at all
    argv = [sys.executable, "-m", "s7graph.web.cli.root", "sim", *DRILL, "--cycles", "3"]
    done = subprocess.run(argv, stdout=write_end, stderr=subprocess.PIPE, timeout=60, check=False)
    os.close(write_end)
    assert (done.returncode, done.stderr.decode()) == (141, "")


@pytest.mark.parametrize(
    ("argv", "said"),
    [
        (["sim", "--cycles", "abc"], "a whole number from 0 to 100,000,000, not 'abc'"),
        (["sim", "--cycles", "1.5"], "a whole number from 0 to 100,000,000, not '1.5'"),
        (["sim", "--cycle-ms", "x"], "a number from 0 to 3,600,000 ms, not 'x'"),
        (["run", "--duration-s", "x"], "a number from 0 to 1,000,000,000 s, not 'x'"),
        (["run", "--port", "x"], "a whole number from 0 (a free one) to 65535, not 'x'"),
        (["diag", "-n", "x"], "a whole number from 1 to 1,000, not 'x'"),
        (["run", "--rt-priority", "x"], "a whole number from 0 (normal scheduling) to 98, not 'x'"),
        (["watch", "--interval-ms", "x"], "a number from 20 to 3,600,000 ms, not 'x'"),
    ],
)
def test_a_numeric_option_given_no_number_says_what_it_takes_in_one_line(
    argv: list[str], said: str, capsys: pytest.CaptureFixture[str]
) -> None:
    command, *rest = argv
    given = {"watch": ["--address", "MW0"], "diag": []}.get(command, DRILL)
    assert main([command, *given, *rest]) == 2
    err = capsys.readouterr().err
    assert (
        err.startswith(f"s7graph: error: Invalid value for '{rest[0]}': {said} (see s7graph ")
        and err.count("\n") == 1
    ), err


@pytest.mark.parametrize(
    ("argv", "usage"),
    [
        (["sim", "--help"], "s7graph sim [OPTIONS] CHART"),
        (["run", "--help"], "s7graph run [OPTIONS] PROGRAM"),
        (["certs", "issue", "--help"], "s7graph certs issue [OPTIONS] DIRECTORY NAME"),
        (["send", "--help"], "s7graph send [OPTIONS] OP [NAME=VALUE]..."),
    ],
)
def test_the_usage_line_names_each_argument_in_capitals_as_a_user_expects(
    argv: list[str], usage: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert f"Usage: {usage} " in out and "{" not in out.split("Usage:")[1].splitlines()[0], out


@pytest.mark.parametrize(
    ("argv", "said"),
    [
        (["run", *DRILL, "--port", "70000"], "'--port': from 0 (a free one) to 65535, not 70000"),
        (["run", *DRILL, "--port", "-1"], "'--port': from 0 (a free one) to 65535, not -1"),
        (["web", "--port", "65536"], "'--port': from 0 (a free one) to 65535, not 65536"),
        (["diag", "-n", "0"], "'-n': from 1 to 1,000, not 0"),
        (["diag", "-n", "1001"], "'-n': from 1 to 1,000, not 1001"),
        (["run", *DRILL, "--comm-load", "0"], "'--comm-load': from 1 to 100 %, not 0"),
        (["watch", "--address", "MW0", "--interval-ms", "1"], "'--interval-ms': from 20 to"),
    ],
)
def test_a_number_out_of_its_options_range_is_refused_in_the_same_words_by_every_command(
    argv: list[str], said: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """Before: ``--port 70000 is out of range (0-65535)``, ``-n 0: give 1 to 1000 entries``
    and ``Invalid value: --interval-ms: …``, each its own way; now each as a range check
    says it, pointing at the command's help."""
    assert main(argv) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1, err
    assert err.startswith(f"s7graph: error: Invalid value for {said}"), err
    assert err.endswith(f" (see s7graph {argv[0]} --help)\n"), err


@pytest.mark.parametrize(
    ("argv", "said"),
    [
        (["sim"], "give CHART: a chart in .s7g source, or an .scl source"),
        (["run"], "give PROGRAM: a Python program of blocks (.py), an S7-SCL program (.scl)"),
        (["certs", "issue", "ca"], "give NAME: the node's name: a CPU's is its --cpu"),
        (["modify"], "give ADDRESS VALUE: an I, Q, M or DB address or a symbol"),
        (["audit"], "give --state: the CPU's SQLite state file"),
        (["export", "x.s7g"], "give --to: plcopen or simaticml"),
    ],
)
def test_a_missing_argument_or_required_option_is_asked_for_with_what_it_is(
    argv: list[str], said: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """Named as the usage line names it (capitals for an argument), with its help; before,
    click's ``Missing argument 'chart'.`` in lower case and without a word of what it is."""
    assert main(argv) == 2
    (line,) = capsys.readouterr().err.splitlines()
    assert line.startswith(f"s7graph: error: {said}"), line
    command = " ".join(argv[:2] if argv[0] == "certs" else argv[:1])
    assert line.endswith(f" (see s7graph {command} --help)"), line
    assert "Missing" not in line


def test_a_commands_own_refusal_is_said_without_clicks_invalid_value_before_it(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Before: ``Invalid value: give the user to log in as with --user``."""
    assert main(["force", "I0.3", "TRUE", "--connect", "tcp/127.0.0.1:9"]) == 2
    assert capsys.readouterr().err == (
        "s7graph: error: give the user to log in as with --user (see s7graph force --help)\n"
    )
