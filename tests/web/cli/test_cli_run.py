"""``s7graph run PROGRAM.py`` (web/cli/run_program.py): runs, stops cleanly, fails in one line."""

from __future__ import annotations

import itertools
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
        ("--rt-priority", "-1"),
        ("--rt-priority", "99"),
    ],
)
def test_max_cycle_time_and_rt_priority_out_of_range_are_usage_errors(
    tmp_path: Path, option: str, value: str
) -> None:
    """A maximum cycle time of 0 ms or less, a real-time priority outside 0..98: a usage
    error, exit 2, never a traceback."""
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
