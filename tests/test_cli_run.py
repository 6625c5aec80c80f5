"""``s7graph run PROGRAM.py`` (web/cmd_run.py): runs, stops cleanly, fails in one line."""

from __future__ import annotations

import itertools
import subprocess
import sys
from pathlib import Path

import pytest

from engine.persistence import StateStore

ROOT = Path(__file__).resolve().parent.parent


def _run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "web.cli", "run", *args],
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
        proc = _run(str(ROOT / "examples/blink.py"), "--state", str(state), "--duration-s", "1.2")
        assert proc.returncode == 0, proc.stderr
        assert "Traceback" not in proc.stderr
    from engine import Cpu, VirtualClock
    from web.cmd_run import build_cpu, import_program

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
    from engine import VirtualClock
    from web.cmd_run import build_cpu, import_program

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
