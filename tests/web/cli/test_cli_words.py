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
        (["run", "--port", "x"], "a whole number from 0 to 65535, not 'x'"),
        (["run", "--rt-priority", "x"], "a whole number from 0 (normal scheduling) to 98, not 'x'"),
        (["watch", "--interval-ms", "x"], "a number from 20 to 3,600,000 ms, not 'x'"),
    ],
)
def test_a_numeric_option_given_no_number_says_what_it_takes_in_one_line(
    argv: list[str], said: str, capsys: pytest.CaptureFixture[str]
) -> None:
    command, *rest = argv
    given = DRILL if command != "watch" else ["--address", "MW0"]
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
