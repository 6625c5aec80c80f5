"""``s7graph run PROGRAM.py`` (web/cli/run_program.py): runs, stops cleanly, fails in one line."""

from __future__ import annotations

import itertools
import sqlite3
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from s7graph.engine.persistence import StateStore
from tests.paths import ROOT


def _run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "s7graph", "run", *args],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=60,
    )


@pytest.mark.timeout(120)
def test_blink_example_runs_for_a_duration_and_saves_its_count(tmp_path: Path) -> None:
    """The blink example runs on the system clock, stops, and keeps its count across runs."""
    state = tmp_path / "blink.sqlite"
    for _ in range(2):
        # a generous maximum cycle time: a loaded CI machine must not stop the blink by a
        # time error before its 1.2 s are up
        proc = _run(
            str(ROOT / "examples/blink.py"),
            "--state",
            str(state),
            "--duration-s",
            "1.2",
            "--max-cycle-ms",
            "5000",
        )
        assert proc.returncode == 0, proc.stderr
        assert "Traceback" not in proc.stderr
    from s7graph.engine import Cpu, VirtualClock
    from s7graph.web.cli.run_program import build_cpu, import_program

    cpu = build_cpu(import_program(ROOT / "examples/blink.py"), VirtualClock())
    store = StateStore(state)
    assert store.load(cpu)
    assert isinstance(cpu, Cpu)
    assert int(cpu.mem.get("MW0")) >= 2  # type: ignore[call-overload]  # one blink per 1.2 s run
    assert store.meta("mode") == "STOP"
    assert cpu.mem.periph_out[0] == 0


@pytest.mark.parametrize(
    ("source", "fragment"),
    [
        ("x = (\n", "syntax error"),
        ("import no_such_module_here\n", "ModuleNotFoundError"),
        ("X = 1\n", "defines no OB"),
        (
            "from engine import ob\n@ob(1)\ndef m(ctx): pass\n"
            "def setup(cpu): raise RuntimeError('boom')\n",
            "RuntimeError: boom",
        ),
    ],
)
def test_broken_program_is_one_line_and_exit_2(tmp_path: Path, source: str, fragment: str) -> None:
    """A broken program: one clear line on stderr, exit status 2, never a traceback."""
    program = tmp_path / "bad.py"
    program.write_text(source)
    proc = _run(str(program), "--duration-s", "0.2")
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and fragment in lines[0] and "Traceback" not in proc.stderr


def test_missing_program_file(tmp_path: Path) -> None:
    """A missing file is an error, exit 2."""
    proc = _run(str(tmp_path / "nope.py"))
    assert proc.returncode == 2 and "no such file" in proc.stderr


def test_example_blinks_on_the_virtual_clock() -> None:
    """examples/blink.py: OB35 toggles Q0.0 every 500 ms; MW0 counts the blinks."""
    from s7graph.engine import VirtualClock
    from s7graph.web.cli.run_program import build_cpu, import_program

    clock = VirtualClock()
    cpu = build_cpu(import_program(ROOT / "examples/blink.py"), clock)
    cpu.start()
    q = []
    for _ in range(300):
        clock.advance(10)
        cpu.scan()
        q.append(cpu.mem.periph_out[0] & 1)
    edges = sum(1 for a, b in itertools.pairwise(q) if not a and b)
    assert edges == 3 and cpu.mem.get("MW0") == 3


@pytest.fixture
def max_cycle_seen(monkeypatch: pytest.MonkeyPatch) -> list[float]:
    """The maximum cycle time (ms) of every CPU a ``Runner`` starts scanning."""
    from s7graph.engine.runner import Runner

    seen: list[float] = []
    real_run = Runner.run

    def spy(self: Runner, *args: Any, **kwargs: Any) -> Any:
        seen.append(self.cpu.watchdog.max_cycle_ns / 1e6)
        return real_run(self, *args, **kwargs)

    monkeypatch.setattr(Runner, "run", spy)
    return seen


@pytest.mark.timeout(60)
@pytest.mark.parametrize(
    ("options", "expected"),
    [((), 150.0), (("--max-cycle-ms", "400"), 400.0), (("--max-cycle-ms", "12.5"), 12.5)],
)
def test_max_cycle_time_reaches_the_cpu_of_a_program_run(
    tmp_path: Path, max_cycle_seen: list[float], options: tuple[str, ...], expected: float
) -> None:
    """``--max-cycle-ms`` is the watchdog's limit of a program run; S7's 150 ms by default."""
    from s7graph.web.cli import main

    program = str(ROOT / "examples/blink.py")
    state = str(tmp_path / "blink.sqlite")
    rc = main(["run", program, "--state", state, "--duration-s", "0.2", *options])
    assert rc == 0 or expected < 50  # 12.5 ms: a loaded machine may stop the CPU (exit 1)
    assert max_cycle_seen == [expected]


@pytest.mark.timeout(60)
@pytest.mark.parametrize(
    ("options", "expected"),
    [
        ((), 150.0),
        (("--max-cycle-ms", "400"), 400.0),
        (("--web",), 150.0),
        (("--web", "--max-cycle-ms", "250"), 250.0),
    ],
)
def test_max_cycle_time_reaches_the_cpu_of_a_chart_run(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    max_cycle_seen: list[float],
    options: tuple[str, ...],
    expected: float,
) -> None:
    """``--max-cycle-ms`` is the watchdog's limit of a chart run: 150 ms by default, with
    ``--web`` too (the view has a process of its own; not served here)."""
    import s7graph.web.cli.run_chart
    from s7graph.web.cli import main

    monkeypatch.setattr(s7graph.web.cli.run_chart, "_serve", lambda *args, **kwargs: (None, []))
    drill = ROOT / "examples/drill"
    rc = main(
        [
            "run",
            str(drill / "drill.s7g"),
            "--symbols",
            str(drill / "symbols.txt"),
            "--state",
            str(tmp_path / "drill.sqlite"),
            "--duration-s",
            "0.2",
            *options,
        ]
    )
    assert rc == 0
    assert max_cycle_seen == [expected]


@pytest.mark.parametrize(
    ("option", "value"),
    [
        ("--max-cycle-ms", "0"),
        ("--max-cycle-ms", "-5"),
        ("--max-cycle-ms", "1e99"),
        ("--rt-priority", "-1"),
        ("--rt-priority", "99"),
        ("--comm-load", "0"),
        ("--comm-load", "nan"),
    ],
)
def test_max_cycle_time_and_rt_priority_out_of_range_are_usage_errors(
    tmp_path: Path, option: str, value: str
) -> None:
    """A maximum cycle time of 0 ms or less or over an hour (1e99 was an internal error), a
    real-time priority outside 0..98, a communication load outside 1..100 %: a usage error
    naming the range and the value given, exit 2, never a traceback."""
    proc = _run(
        str(ROOT / "examples/blink.py"),
        "--state",
        str(tmp_path / "s.sqlite"),
        "--duration-s",
        "0.2",
        option,
        value,
    )
    assert proc.returncode == 2
    assert option.lstrip("-") in proc.stderr and "Traceback" not in proc.stderr
    assert f", not {float(value):g} (see s7graph run --help)" in proc.stderr


def test_rt_priority_0_runs_at_the_normal_priority(tmp_path: Path) -> None:
    proc = _run(
        str(ROOT / "examples/blink.py"),
        "--state",
        str(tmp_path / "s.sqlite"),
        "--duration-s",
        "0.2",
        "--rt-priority",
        "0",
    )
    assert proc.returncode == 0, proc.stderr


RECURRING = """
from s7graph.engine import ob

CPU = {"max_cycle_ms": 5000}

@ob(1)
def main(ctx):
    1 / 0

@ob(121)
def programming_error(ctx):
    pass  # the CPU stays in RUN: the error recurs every cycle
"""


@pytest.mark.timeout(120)
def test_an_error_that_ob121_handles_every_cycle_is_said_once(tmp_path: Path) -> None:
    """Before: one stderr line per cycle (100 a second at 10 ms) for as long as it ran; the
    diagnostic buffer keeps every entry (``s7graph diag``)."""
    program = tmp_path / "faulty.py"
    program.write_text(RECURRING, encoding="utf-8")
    proc = _run(str(program), "--state", str(tmp_path / "s.sqlite"), "--duration-s", "1")
    assert proc.returncode == 0, proc.stderr
    said = [line for line in proc.stderr.splitlines() if "ZeroDivisionError" in line]
    assert len(said) == 1 and " 16#25FF OB1: " in said[0]
    assert said[0].endswith("(said once; s7graph diag lists each)")
    with sqlite3.connect(tmp_path / "s.sqlite") as con:
        (kept,) = con.execute("SELECT COUNT(*) FROM diagnostics WHERE event_id = ?", (0x25FF,))
    con.close()
    assert kept[0] > 5  # the buffer has them all


@pytest.mark.parametrize(
    ("value", "shown"), [("1e99", "1e+99"), ("-5", "-5"), ('"fast"', "'fast'")]
)
def test_a_programs_max_cycle_time_out_of_range_is_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], value: str, shown: str
) -> None:
    """``CPU = {"max_cycle_ms": 1e99}`` was an internal error (``memoryview: invalid value
    for format 'Q'``), -5 a bare ``ValueError``: now the option, its range and the value."""
    from s7graph.web.cli import main

    program = tmp_path / "p.py"
    program.write_text(
        f'from s7graph.engine import ob\nCPU = {{"max_cycle_ms": {value}}}\n'
        "@ob(1)\ndef main(ctx):\n    pass\n",
        encoding="utf-8",
    )
    assert main(["run", str(program), "--state", str(tmp_path / "s.sqlite")]) == 2
    assert capsys.readouterr().err == (
        f"s7graph: error: {program}: CPU option max_cycle_ms: from more than 0 to 3,600,000 "
        f"ms, not {shown}\n"
    )


@pytest.mark.timeout(120)
def test_a_run_on_no_bus_says_how_a_shell_would_reach_it(tmp_path: Path) -> None:
    """A shell's ``s7graph status`` finds no CPU of a run without --web, --listen or
    --connect (docs/cli.md, "The bus from a shell"): the run says so as it starts, after its
    ``in RUN`` line; on a bus it does not."""
    blink = str(ROOT / "examples/blink.py")
    alone = _run(blink, "--state", str(tmp_path / "a.sqlite"), "--duration-s", "0.5")
    assert alone.returncode == 0, alone.stderr
    lines = alone.stderr.splitlines()
    assert " in RUN (" in lines[0]
    assert lines[1] == (
        "s7graph: on no bus: s7graph status, watch and the other commands of a shell reach a "
        "run started with --web, --listen or --connect"
    )
    sock = f"unixsock-stream/{tmp_path}/bus.sock"
    listening = _run(
        blink, "--state", str(tmp_path / "b.sqlite"), "--duration-s", "0.5", "--listen", sock
    )
    assert listening.returncode == 0, listening.stderr
    assert "on no bus" not in listening.stderr and " in RUN (" in listening.stderr
