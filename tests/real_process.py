"""Shared helpers of the tests that run ``s7graph run`` as a real process and read its
SQLite state store from outside while it runs, imported as ``tests.real_process``
(tests/engine/test_persistence.py, tests/web/harness/test_message_persistence.py)."""

from __future__ import annotations

import signal
import sqlite3
import subprocess
import sys
import textwrap
import time
from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

ROOT = Path(__file__).resolve().parent.parent

T = TypeVar("T")


def run_command(tmp_path: Path, program: str) -> tuple[list[str], Path]:
    """Write ``program`` (dedented) to ``tmp_path``; the ``s7graph run`` command line running
    it at a 5 ms cycle (start it with ``cwd=ROOT``) and the path of its state store."""
    path = tmp_path / "prog.py"
    path.write_text(textwrap.dedent(program))
    state = tmp_path / "state.sqlite"
    cmd = [sys.executable, "-m", "s7graph", "run", str(path), "--state", str(state)]
    cmd += ["--cycle-ms", "5"]
    return cmd, state


def query_store(path: Path, query: Callable[[sqlite3.Connection], T]) -> T | None:
    """``query`` on a read-only connection to the store at ``path``; None while the file does
    not exist yet or SQLite refuses (busy, tables not created yet)."""
    if not path.exists():
        return None
    try:
        con = sqlite3.connect(f"file:{path}?mode=ro", uri=True, timeout=1)
        try:
            return query(con)
        finally:
            con.close()
    except sqlite3.Error:
        return None


def wait_for(
    read: Callable[[Path], T | None],
    path: Path,
    pred: Callable[[T], bool],
    proc: subprocess.Popen[bytes],
) -> T:
    """Poll ``read(path)`` until ``pred`` holds (30 s); fail at once if ``proc`` ended."""
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:
        state = read(path)
        if state is not None and pred(state):
            return state
        assert proc.poll() is None, proc.stderr.read() if proc.stderr else b""
        time.sleep(0.05)
    raise AssertionError(f"timed out; last state {read(path)}")


def descendants(pid: int) -> list[int]:
    """The processes below ``pid`` (``s7graph run``'s CPU, its view and compiler)."""
    found: list[int] = []
    for task in Path(f"/proc/{pid}/task").glob("*"):
        try:
            children = (task / "children").read_text().split()
        except OSError:
            continue
        for child in map(int, children):
            found += [child, *descendants(child)]
    return found


def _running(pid: int) -> bool:
    """Whether any thread of process ``pid`` still runs. A zombie thread-group leader is not
    enough: when a process is SIGKILLed its main thread may be a zombie while another thread
    (the CPU's state writer, preempted inside its ``write`` under load) has yet to finish the
    system call it was in — and that write may complete a commit."""
    try:
        tasks = list(Path(f"/proc/{pid}/task").iterdir())
    except OSError:
        return False
    for task in tasks:
        try:
            state = (task / "stat").read_text().rsplit(")", 1)[1].split()[0]
        except (OSError, IndexError):
            continue
        if state != "Z":
            return True
    return False


def wait_gone(pids: list[int], timeout: float = 30.0) -> None:
    """Until none of ``pids`` runs any more: every thread of each ended (a zombie counts as
    gone, once all its threads are)."""
    deadline = time.monotonic() + timeout
    for pid in pids:
        while _running(pid):
            assert time.monotonic() < deadline, f"process {pid} still runs {timeout:g} s on"
            time.sleep(0.01)


def kill_run(proc: subprocess.Popen[bytes], timeout: float = 30.0) -> None:
    """SIGKILL ``s7graph run`` and wait until its CPU is gone too, every thread of it: the
    CPU dies with its supervisor (parent-death signal) but its writer thread may still be in
    its last commit's write or fsync when the run is reaped — that commit is durable, and a
    reader must not miss it."""
    below = descendants(proc.pid)
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout)
    wait_gone(below, timeout)
