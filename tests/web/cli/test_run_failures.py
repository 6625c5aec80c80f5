"""``s7graph run`` when things go wrong (real processes): a scan that swallows every abort
cannot hold the process against SIGTERM; a chart run that goes to STOP by an error says why
and exits non-zero, in its startup too (where the chart uses the operand named); a STOP the
program requested (SFC46) is said and exits 0; a plant's SystemExit is a plant error, not an
exit."""

from __future__ import annotations

import signal
import sqlite3
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from s7graph.engine.diagnostics import EventId
from s7graph.engine.marks import EXIT_HUNG, GRACE_S
from tests.paths import ROOT

DRILL = ROOT / "examples" / "drill"

SWALLOWER = """
from pathlib import Path
from s7graph.engine import ob

CPU = {"max_cycle_ms": 50}
calls = [0]
SWALLOWED = Path(__file__).with_suffix(".swallowed")

@ob(1)
def main(ctx):
    calls[0] += 1
    if calls[0] < 20:
        return
    while True:          # hangs, and swallows every abort the runner raises
        try:
            while True:
                pass
        except BaseException:
            try:             # (an abort while it is said is swallowed too)
                if not SWALLOWED.exists():
                    SWALLOWED.write_text("an abort")
            except BaseException:
                pass
"""


def _start(*args: str) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "s7graph", "run", *args],
        cwd=ROOT,
        stderr=subprocess.PIPE,
        text=True,
    )


@pytest.mark.timeout(60)
def test_a_scan_swallowing_every_abort_cannot_hold_the_process_against_sigterm(
    tmp_path: Path,
) -> None:
    program = tmp_path / "hang.py"
    program.write_text(textwrap.dedent(SWALLOWER))
    state = tmp_path / "hang.sqlite"
    proc = _start(str(program), "--state", str(state), "--cycle-ms", "5")
    assert proc.stderr is not None
    assert "in RUN" in proc.stderr.readline()
    # scan 20 hangs, aborts are raised and swallowed: SIGTERM then, at once — its supervisor
    # kills a scan hung 1 s past the first abort (a later SIGTERM, on a loaded machine, would
    # find a CPU started again in STOP)
    swallowed = program.with_suffix(".swallowed")
    deadline = time.monotonic() + 30
    while not swallowed.exists():
        assert proc.poll() is None and time.monotonic() < deadline, proc.stderr.read()
        time.sleep(0.01)
    sent = time.monotonic()
    proc.send_signal(signal.SIGTERM)
    code = proc.wait(GRACE_S + 20)
    waited = time.monotonic() - sent
    err = proc.stderr.read()
    assert code == EXIT_HUNG, err
    assert waited >= GRACE_S
    lines = [line for line in err.splitlines() if line.startswith("s7graph: error")]
    assert len(lines) == 1 and "did not return" in lines[0] and "hang.py" in lines[0]
    with sqlite3.connect(state) as con:
        rows = con.execute("SELECT event_id, message FROM diagnostics ORDER BY seq").fetchall()
        clean = con.execute("SELECT value FROM meta WHERE key='clean'").fetchone()
    con.close()
    assert rows[-1][0] == EventId.STOP_HUNG and "did not return" in rows[-1][1]
    assert clean == ("0",)  # the run did not end cleanly, and the file says so


ENDLESS_PLANT = """
class Plant:
    n = 0
    def cycle(self, io, t_ms, dt_ms):
        self.n += 1
        while self.n > 10:
            pass
"""


@pytest.mark.timeout(60)
def test_a_chart_run_whose_plant_hangs_goes_to_stop_says_why_and_exits_1(tmp_path: Path) -> None:
    plant = tmp_path / "endless.py"
    plant.write_text(textwrap.dedent(ENDLESS_PLANT))
    proc = _start(
        str(DRILL / "drill.s7g"),
        "--symbols",
        str(DRILL / "symbols.txt"),
        "--plant",
        str(plant),
        "--state",
        str(tmp_path / "s.sqlite"),
        "--max-cycle-ms",
        "50",
    )
    code = proc.wait(40)
    assert proc.stderr is not None
    err = proc.stderr.read()
    assert code == 1, err
    (line,) = [x for x in err.splitlines() if "error" in x]
    assert "the CPU went to STOP: plant endless.py: aborted: still running" in line
    assert "endless.py:6 in cycle" in line and "Traceback" not in err


@pytest.mark.timeout(60)
def test_a_plant_raising_system_exit_ends_the_run_with_one_line(tmp_path: Path) -> None:
    plant = tmp_path / "quits.py"
    plant.write_text(
        "class Plant:\n    def cycle(self, io, t_ms, dt_ms):\n        raise SystemExit(0)\n"
    )
    proc = _start(
        str(DRILL / "drill.s7g"),
        "--symbols",
        str(DRILL / "symbols.txt"),
        "--plant",
        str(plant),
        "--state",
        str(tmp_path / "s.sqlite"),
    )
    code = proc.wait(40)
    assert proc.stderr is not None
    err = proc.stderr.read()
    assert code == 1, err
    (line,) = [x for x in err.splitlines() if "error" in x]
    assert "SystemExit" in line and "quits.py:3" in line


BEYOND = """
FUNCTION_BLOCK "Far" FB 1 DB 1
SEQUENCE 1
  INITIAL_STEP S1: N Q0.0; END_STEP
  STEP S2: END_STEP
  TRANSITION T1 FROM S1 TO S2 := I200.0;
  TRANSITION T2 FROM S2 TO S1 := TRUE;
END_SEQUENCE
END_FUNCTION_BLOCK
"""


@pytest.mark.timeout(60)
def test_a_chart_whose_startup_stops_the_cpu_says_the_located_reason_at_once_and_exits_1(
    tmp_path: Path,
) -> None:
    """The first call (OB100, INIT_SQ) reads I200.0, beyond a default CPU's 128 input bytes:
    the run says why in one error line — the STOP's place (OB100), the diagnostic entry
    (block, operand, message) and where the chart uses the operand — and exits 1, without
    waiting for ``--duration-s``."""
    chart = tmp_path / "far.s7g"
    chart.write_text(textwrap.dedent(BEYOND))
    proc = _start(str(chart), "--state", str(tmp_path / "s.sqlite"), "--rt-priority", "0")
    code = proc.wait(40)
    assert proc.stderr is not None
    err = proc.stderr.read()
    assert code == 1, err
    (line,) = [x for x in err.splitlines() if x.startswith("s7graph: error")]
    assert line == (
        "s7graph: error: far.s7g (Far): the CPU went to STOP in its startup (OB100): FB1: "
        "I200.0 is outside the I area (128 bytes) (programming error, OB121 not loaded); "
        f"I200.0: first used at {chart}:6:34 (transition T1)"
    )
    assert "stopped (state saved" not in err


SFC46_AT_SCAN_5 = """
from s7graph.engine import ob

calls = [0]

@ob(1)
def main(ctx):
    calls[0] += 1
    if calls[0] == 5:
        ctx.call("SFC46")
"""


@pytest.mark.timeout(60)
def test_a_program_stopping_the_cpu_by_sfc46_ends_the_run_saying_so_with_exit_0(
    tmp_path: Path,
) -> None:
    """A STOP the program requested (SFC46 STP) is no error: one line says it, without
    ``error:``, the run ends at once with its state saved, exit 0."""
    program = tmp_path / "stp.py"
    program.write_text(textwrap.dedent(SFC46_AT_SCAN_5))
    proc = _start(str(program), "--state", str(tmp_path / "s.sqlite"), "--rt-priority", "0")
    code = proc.wait(40)
    assert proc.stderr is not None
    err = proc.stderr.read()
    assert code == 0, err
    assert "s7graph: error" not in err
    assert (
        "s7graph: stp.py: the CPU went to STOP: SFC46 STP (the program's request, not an "
        "error)\n" in err
    )
    assert "s7graph: stp.py stopped (state saved in" in err


BAD_OB100 = """
from s7graph.engine import ob

@ob(100)
def start(ctx):
    ctx.mem.get("I200.0")

@ob(1)
def main(ctx):
    pass
"""


@pytest.mark.timeout(60)
def test_a_program_whose_startup_stops_the_cpu_by_an_error_says_why_and_exits_1(
    tmp_path: Path,
) -> None:
    program = tmp_path / "bad.py"
    program.write_text(textwrap.dedent(BAD_OB100))
    proc = _start(str(program), "--state", str(tmp_path / "s.sqlite"), "--rt-priority", "0")
    code = proc.wait(40)
    assert proc.stderr is not None
    err = proc.stderr.read()
    assert code == 1, err
    (line,) = [x for x in err.splitlines() if x.startswith("s7graph: error")]
    assert line.startswith("s7graph: error: bad.py: the CPU went to STOP in its startup (OB100): ")
    assert "I200.0" in line and "OB121 not loaded" in line


KEY_AT_STOP = """
from s7graph.engine import ob
from s7graph.engine.modes import KeySwitch

CPU = {"key": KeySwitch.STOP}

@ob(1)
def main(ctx):
    pass
"""

OB35_DESELECTED = """
from s7graph.engine import ob

@ob(1)
def main(ctx):
    pass

@ob(35)
def every_100_ms(ctx):
    pass

def setup(cpu):
    cpu.interrupts.configure(35, 0)  # loaded, but deselected: no startup (16#4309)
"""


@pytest.mark.timeout(60)
@pytest.mark.parametrize(
    ("program", "why"),
    [
        (KEY_AT_STOP, "key switch is in STOP"),
        (OB35_DESELECTED, "OB35: OB35 is loaded but deselected: startup aborted"),
    ],
    ids=["the key switch at STOP", "a deselected OB"],
)
def test_a_startup_the_cpu_refuses_says_why_at_once_and_exits_1(
    tmp_path: Path, program: str, why: str
) -> None:
    """Before: ``in STOP``, then ``stopped (state saved …)``, exit 0 — as if the run had
    done its work. The CPU's refusal (its entry 16#4309) is one error line, the block it
    names first, and the run ends at once with exit 1, as after a STOP in the startup."""
    path = tmp_path / "refused.py"
    path.write_text(textwrap.dedent(program))
    proc = _start(str(path), "--state", str(tmp_path / "s.sqlite"), "--rt-priority", "0")
    code = proc.wait(40)
    assert proc.stderr is not None
    err = proc.stderr.read()
    assert code == 1, err
    (line,) = [x for x in err.splitlines() if x.startswith("s7graph: error")]
    assert line == f"s7graph: error: refused.py: the CPU refused its startup: {why}"
    assert "stopped (state saved" not in err


def test_a_hot_restart_the_cpu_turns_warm_is_no_refused_startup() -> None:
    """Its 16#4309 entry says so, but the CPU starts (warm): nothing for the run to say."""
    from s7graph.engine import Cpu, VirtualClock, ob
    from s7graph.engine.runner import refused_startup

    @ob(1)
    def main(ctx: object) -> None:
        pass

    cpu = Cpu(VirtualClock())
    cpu.load(main)
    cpu.hot_blockers.add("program download")
    record = cpu.start("hot")
    assert any(e.event_id == EventId.STARTUP_REFUSED for e in record.diagnostics)
    assert refused_startup(cpu) is None and cpu.last_restart == "warm"
