"""``s7graph run`` supervises its CPU from outside the process (real processes, real hangs in
C code): a block or plant looping in ``sum(range(10**13))`` holds the interpreter's lock, so
only the supervisor can end it — it kills the CPU's process and starts it again in STOP from
its last durable state, with the cause in the diagnostic buffer, on stderr and in
``status``; an engineer starts it again (``s7graph start``, audited)."""

from __future__ import annotations

import functools
import os
import signal
import sqlite3
import subprocess
import sys
import textwrap
import time
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from s7graph.engine.diagnostics import EventId
from s7graph.engine.marks import EXIT_HUNG, GRACE_S
from s7graph.web.cli.supervisor import KILL_AFTER_S, STOP_EXTRA_S, die_with_parent
from tests.paths import ROOT
from tests.web.helpers import free_port

if TYPE_CHECKING:
    from tests.conftest import BusCerts

DRILL = ROOT / "examples" / "drill"
PASSWORD = "correct horse battery"

HANGING_BLOCK = """
from s7graph.engine import fc, ob

CPU = {"max_cycle_ms": 100}
calls = [0]

@fc(7, name="crunch")
def crunch(ctx, params):
    return sum(range(10**13))  # C code: no abort reaches it

@ob(1)
def main(ctx):
    calls[0] += 1
    if calls[0] == 30:
        ctx.call(crunch)
"""

HANGING_PLANT = """
from pathlib import Path

FLAG = Path(__file__).with_name("hung.flag")

class Plant:
    n = 0
    def cycle(self, io, t_ms, dt_ms):
        self.n += 1
        if self.n == 30 and not FLAG.exists():  # once: the restarted CPU runs on
            FLAG.write_text("hung")
            sum(range(10**13))
"""


def _s7graph(*args: str, **kw: object) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "s7graph", *args],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        **kw,  # type: ignore[call-overload]
    )


def _diagnostics(state: Path) -> list[tuple[int, str, str]]:
    with sqlite3.connect(state) as con:
        rows = con.execute("SELECT event_id, block, message FROM diagnostics ORDER BY seq")
        found = [(int(e), str(b), str(m)) for e, b, m in rows]
    con.close()
    return found


@pytest.mark.timeout(60)
def test_a_block_hanging_in_c_code_is_killed_and_the_run_ends_in_stop_naming_it(
    tmp_path: Path,
) -> None:
    program = tmp_path / "hang.py"
    program.write_text(textwrap.dedent(HANGING_BLOCK))
    state = tmp_path / "hang.sqlite"
    started = time.monotonic()
    proc = _s7graph("run", str(program), "--state", str(state), "--cycle-ms", "5")
    _, err = proc.communicate(timeout=45)
    took = time.monotonic() - started
    assert proc.returncode == 1, err
    assert took < 2 * 0.1 + KILL_AFTER_S + 8  # the hang itself would take hours
    errors = [line for line in err.splitlines() if line.startswith("s7graph: error")]
    assert len(errors) == 2 and "Traceback" not in err
    assert 'the scan hung in FC7 "crunch"' in errors[0] and "killed" in errors[0]
    assert 'the CPU went to STOP: FC7 "crunch": no scan ended for' in errors[1]
    assert "hang.py in STOP (from its last durable state" in err
    event, block, message = _diagnostics(state)[-1]
    assert (event, block) == (EventId.STOP_KILLED, 'FC7 "crunch"')
    assert "past twice the maximum cycle time (200 ms)" in message and "in STOP" in message


def _users(tmp_path: Path) -> Path:
    users = tmp_path / "users.json"
    for name, role in (("olga", "operator"), ("eng", "engineer")):
        add = ["users", "add", name, "--role", role, "--file", str(users), "--password-stdin"]
        done = subprocess.run(
            [sys.executable, "-m", "s7graph", *add],
            cwd=ROOT,
            input=PASSWORD + "\n",
            capture_output=True,
            text=True,
        )
        assert done.returncode == 0, done.stderr
    return users


def _shell(bus: list[str], *args: str) -> subprocess.CompletedProcess[str]:
    env = dict(os.environ, S7GRAPH_PASSWORD=PASSWORD)
    return subprocess.run(
        [sys.executable, "-m", "s7graph", *args, *bus],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=30,
    )


def _wait_line(proc: subprocess.Popen[str], text: str) -> list[str]:
    assert proc.stderr is not None
    seen: list[str] = []
    for line in proc.stderr:
        seen.append(line)
        if text in line:
            return seen
    raise AssertionError(f"the run ended without {text!r}: {''.join(seen)}")


@pytest.mark.timeout(120)
def test_a_plant_hanging_in_c_code_comes_back_in_stop_on_the_bus_and_an_engineer_starts_it(
    tmp_path: Path, bus_certs: BusCerts
) -> None:
    plant = tmp_path / "hangplant.py"
    plant.write_text(textwrap.dedent(HANGING_PLANT))
    state = tmp_path / "drill.sqlite"
    endpoint = f"tls/localhost:{free_port()}"  # a users file: every node has a certificate
    bus = ["--connect", endpoint, *bus_certs.args("client.olga")]
    users = _users(tmp_path)
    proc = _s7graph(
        "run",
        str(DRILL / "drill.s7g"),
        "--symbols",
        str(DRILL / "symbols.txt"),
        "--plant",
        str(plant),
        "--state",
        str(state),
        "--listen",
        endpoint,
        "--users",
        str(users),
        "--max-cycle-ms",
        "500",  # a loaded machine's long cycle must not stop the restarted CPU again
        *bus_certs.args("cpu.cpu1"),
    )
    failure: AssertionError | None = None
    try:
        seen = _wait_line(proc, "in STOP (from its last durable state")
        assert any("the scan hung in plant hangplant.py" in line for line in seen)
        status = _shell(bus, "status")
        assert status.returncode == 0, status.stderr
        lines = status.stdout.splitlines()
        assert lines[0].startswith("CPU cpu1: STOP")
        assert lines[1].startswith("STOP: plant hangplant.py: no scan ended for")
        refused = _shell(bus, "start", "--user", "olga")
        assert refused.returncode == 1 and "start refused" in refused.stderr
        assert _shell(bus, "status").stdout.startswith("CPU cpu1: STOP")
        started = _shell(bus, "start", "--user", "eng")
        assert started.returncode == 0, started.stderr
        deadline = time.monotonic() + 10
        while not _shell(bus, "status").stdout.startswith("CPU cpu1: RUN"):
            assert time.monotonic() < deadline, "the CPU did not go to RUN"
        assert _shell(bus, "stop", "--user", "eng").returncode == 0
        assert _shell(bus, "status").stdout.startswith("CPU cpu1: STOP")
    except AssertionError as exc:
        failure = exc
    finally:
        proc.send_signal(signal.SIGTERM)
        _, rest = proc.communicate(timeout=30)
    if failure is not None:  # with what the CPU said
        raise AssertionError(f"{failure}\nthe CPU's stderr:\n{rest}") from failure
    assert proc.returncode == 0, rest  # stopped by the switch, not by an error
    rows = _diagnostics(state)
    killed = [r for r in rows if r[0] == EventId.STOP_KILLED]
    assert len(killed) == 1 and killed[0][1] == "plant hangplant.py"
    assert any(r[0] == EventId.STARTUP_TO_RUN for r in rows[rows.index(killed[0]) :])
    with sqlite3.connect(state) as con:
        audit = con.execute("SELECT user, action, detail FROM audit").fetchall()
    con.close()
    actions = [(user, action) for user, action, _ in audit]
    assert ("olga", "start") in actions and ("eng", "start") in actions
    assert ("eng", "stop") in actions


@pytest.mark.timeout(60)
def test_a_cpu_hanging_in_c_code_after_sigterm_is_killed_with_exit_hung(tmp_path: Path) -> None:
    program = tmp_path / "slow.py"
    program.write_text(
        textwrap.dedent(HANGING_BLOCK).replace('"max_cycle_ms": 50', '"max_cycle_ms": 6000')
    )
    state = tmp_path / "slow.sqlite"
    proc = _s7graph("run", str(program), "--state", str(state), "--cycle-ms", "5")
    assert proc.stderr is not None
    assert "in RUN" in proc.stderr.readline()
    time.sleep(1.0)  # scan 30 hangs; the watchdog would wait 13 s
    sent = time.monotonic()
    proc.send_signal(signal.SIGTERM)
    code = proc.wait(GRACE_S + STOP_EXTRA_S + 10)
    waited = time.monotonic() - sent
    err = proc.stderr.read()
    assert code == EXIT_HUNG, err
    assert GRACE_S + STOP_EXTRA_S <= waited < GRACE_S + STOP_EXTRA_S + 5
    assert "did not end within" in err and "killed" in err


BLINK = ROOT / "examples" / "blink.py"


@pytest.mark.timeout(60)
def test_ctrl_c_at_the_terminal_ends_a_supervised_run_cleanly_with_its_state_saved(
    tmp_path: Path,
) -> None:
    state = tmp_path / "blink.sqlite"
    proc = _s7graph("run", str(BLINK), "--state", str(state), start_new_session=True)
    assert proc.stderr is not None
    assert "in RUN" in proc.stderr.readline()
    os.killpg(proc.pid, signal.SIGINT)  # as the terminal does: the supervisor and the CPU
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == 0, err
    assert "stopped (state saved in" in err and "error" not in err
    with sqlite3.connect(state) as con:
        clean = con.execute("SELECT value FROM meta WHERE key='clean'").fetchone()
    con.close()
    assert clean == ("1",)


@pytest.mark.timeout(60)
def test_ctrl_c_pressed_again_while_the_run_ends_is_one_more_stop_request(
    tmp_path: Path,
) -> None:
    """Three quick Ctrl-C at the terminal (each reaching the supervisor and the CPU) while
    the run closes its page: exit 0 with the state saved, never a hang killed after the
    grace (exit 3) nor a traceback of the interrupted ending (docs/cli.md, "s7graph run")."""
    state = tmp_path / "blink.sqlite"
    proc = _s7graph(
        "run", str(BLINK), "--state", str(state), "--web", "--port", "0", start_new_session=True
    )
    assert proc.stderr is not None
    assert "in RUN" in proc.stderr.readline()
    time.sleep(0.5)
    sent = time.monotonic()
    for _ in range(3):
        os.killpg(proc.pid, signal.SIGINT)
        time.sleep(0.05)
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == 0, err
    assert time.monotonic() - sent < GRACE_S
    assert "stopped (state saved in" in err
    assert "Traceback" not in err and "KeyboardInterrupt" not in err and "error" not in err


@pytest.mark.timeout(60)
def test_sigterm_to_the_supervisor_reaches_the_cpu_which_ends_cleanly(tmp_path: Path) -> None:
    state = tmp_path / "blink.sqlite"
    proc = _s7graph("run", str(BLINK), "--state", str(state))
    assert proc.stderr is not None
    assert "in RUN" in proc.stderr.readline()
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == 0, err
    assert "stopped (state saved in" in err


CRASHING_BLOCK = """
import ctypes
from s7graph.engine import fc, ob

calls = [0]

@fc(8, name="driver")
def driver(ctx, params):
    ctypes.string_at(0)  # a crash in C code: SIGSEGV

@ob(1)
def main(ctx):
    calls[0] += 1
    if calls[0] == 30:
        ctx.call(driver)
"""


@pytest.mark.timeout(60)
def test_a_block_crashing_in_c_code_brings_the_cpu_back_in_stop_naming_the_signal(
    tmp_path: Path,
) -> None:
    program = tmp_path / "crash.py"
    program.write_text(textwrap.dedent(CRASHING_BLOCK))
    state = tmp_path / "crash.sqlite"
    proc = _s7graph("run", str(program), "--state", str(state), "--cycle-ms", "5")
    _, err = proc.communicate(timeout=45)
    assert proc.returncode == 1, err
    assert 'the CPU\'s process ended by SIGSEGV in FC8 "driver"; starting it again in STOP' in err
    event, block, message = _diagnostics(state)[-1]
    assert (event, block) == (EventId.STOP_KILLED, 'FC8 "driver"') and "SIGSEGV" in message


@pytest.mark.timeout(90)
def test_sigterm_while_the_hung_cpu_is_restarted_ends_the_run_with_the_cause_on_record(
    tmp_path: Path,
) -> None:
    plant = tmp_path / "hangplant.py"
    plant.write_text(textwrap.dedent(HANGING_PLANT))
    state = tmp_path / "drill.sqlite"
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    proc = _s7graph(
        "run",
        str(DRILL / "drill.s7g"),
        "--symbols",
        str(DRILL / "symbols.txt"),
        "--plant",
        str(plant),
        "--state",
        str(state),
        "--listen",
        endpoint,
    )
    _wait_line(proc, "starting it again in STOP")
    proc.send_signal(signal.SIGTERM)  # the new CPU is not listening yet: it gets it once it is
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 1, err  # it ended in STOP by an error
    assert "in STOP (from its last durable state" in err
    assert [r for r in _diagnostics(state) if r[0] == EventId.STOP_KILLED]
    with sqlite3.connect(state) as con:
        clean = con.execute("SELECT value FROM meta WHERE key='clean'").fetchone()
    con.close()
    assert clean == ("1",)  # the new CPU ended as by Ctrl-C: its state saved


def test_a_cpu_spawned_as_its_supervisor_dies_ends_instead_of_running_on_orphaned() -> None:
    # the parent-death signal is set after the fork: a supervisor SIGKILLed in between would
    # leave the CPU running, writing the state file the next run reads
    sleeper = [sys.executable, "-c", "import time; time.sleep(60)"]
    mine = os.getpid()
    kept = subprocess.Popen(sleeper, preexec_fn=functools.partial(die_with_parent, mine))
    orphan = subprocess.Popen(sleeper, preexec_fn=functools.partial(die_with_parent, mine + 1))
    try:
        assert orphan.wait(30) == -signal.SIGKILL  # its parent was not the one it was given
        assert kept.poll() is None
    finally:
        kept.kill()
        kept.wait()
