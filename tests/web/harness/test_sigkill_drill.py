"""50 SIGKILLs at random moments of the drill demo (``s7graph run examples/drill/drill.s7g
--plant …demo_plant.py``), one real process after the other, each killed at a random
moment after its startup and restarted from the state file it left; the hot and the warm
series run side by side (the CPUs keep no processor from each other: engine/cores.py).

The plant is the demo's, its machine made to outlive the PLC (position, motor, clamp and
piece count kept in a file beside it: a real drill does not reset when its PLC restarts),
quicker, and with a slow clamp now and then, so the sequence runs through its steps and
faults S2.

* ``--restart hot``: each restart resumes exactly in the steps on disk when it was killed
  (the step it was killed in, or the next if that switch was already durable), every fault
  on disk is still latched, no message pending on disk disappears, and no acknowledgement
  appears that nobody made.
* the default (warm): each restart writes the position on disk to the diagnostic buffer
  before it initializes the sequence; every message pending on disk stays listed and
  unacknowledged (it goes outgoing with the restart as its reason); the diagnostic buffer
  and the alarm log only ever grow — nothing in them is rewritten.
"""

from __future__ import annotations

import itertools
import json
import random
import re
import signal
import sqlite3
import subprocess
import sys
import textwrap
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import pytest

from s7graph.engine.diagnostics import EventId
from s7graph.engine.persistence import unpack_instance
from s7graph.sequencer.state import GraphState
from tests.paths import ROOT
from tests.real_process import kill_run

DRILL = ROOT / "examples" / "drill"
KILLS = 50

PLANT = """
import importlib.util, json, os
from pathlib import Path

_spec = importlib.util.spec_from_file_location("demo_plant", {demo!r})
_demo = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_demo)
_KEPT = ("position_mm", "motor_on_ms", "motor_off_ms", "clamp_ms", "coolant_ms",
         "pieces", "idle_ms", "press_ms")


class Plant(_demo.Plant):
    IDLE_MS = {idle}
    SLOW_EVERY = {slow}
    SPEED_MM_S = 200.0
    FILE = Path(__file__).with_suffix(".json")

    def __init__(self):
        super().__init__()
        if self.FILE.exists():
            for key, value in json.loads(self.FILE.read_text()).items():
                setattr(self, key, value)

    def cycle(self, io, t_ms, dt_ms):
        super().cycle(io, t_ms, dt_ms)
        tmp = self.FILE.with_suffix(".tmp")
        tmp.write_text(json.dumps({{k: getattr(self, k) for k in _KEPT}}))
        os.replace(tmp, self.FILE)
"""

_STEP = re.compile(r"S(\d+) '[^']*' T=\d+ ms U=\d+ ms( supervision fault)?")


@dataclass
class OnDisk:
    """What a killed run left in its state file."""

    active: set[int]
    faults: set[int]
    pending: dict[int, dict[str, object]]  # event id → message (listed, unacknowledged)
    diagnostics: list[tuple[int, int, str]]  # (seq, event id, message)
    alarms: list[tuple[int, str, str, str, str]]  # (id, key, state, user, reason)


def _read(path: Path) -> OnDisk:
    con = sqlite3.connect(path)
    try:
        (blob,) = con.execute("SELECT data FROM instances WHERE number=1").fetchone()
        (part,) = con.execute("SELECT state FROM parts WHERE name='messages'").fetchone()
        diagnostics = con.execute(
            "SELECT seq, event_id, message FROM diagnostics ORDER BY seq"
        ).fetchall()
        alarms = con.execute(
            "SELECT id, key, state, user, reason FROM alarms ORDER BY id"
        ).fetchall()
    finally:
        con.close()
    st = GraphState.from_state(unpack_instance(blob)["G7_STATE"])  # as a restart reads it
    messages = json.loads(part)["active"]
    return OnDisk(
        active={i + 1 for i in st.active},  # the drill's step i is S(i+1)
        faults={i + 1 for i, latched in enumerate(st.sv_err) if latched},
        pending={m["event_id"]: m for m in messages if not m["acked"]},
        diagnostics=[tuple(r) for r in diagnostics],
        alarms=[tuple(r) for r in alarms],
    )


def _position(diagnostics: list[tuple[int, int, str]], after: int) -> tuple[str, set, set]:
    """The newest position entry after seq ``after``: (text, steps, faulted steps)."""
    entries = [m for seq, e, m in diagnostics if seq > after and e == EventId.SEQUENCER_POSITION]
    assert entries, "the restart wrote no position entry"
    found = _STEP.findall(entries[-1])
    return entries[-1], {int(n) for n, _ in found}, {int(n) for n, f in found if f}


def _kill_runs(
    tmp_path: Path, restart: str, *, idle: int, slow: int, seed: int, upto_s: float
) -> list[tuple[OnDisk, OnDisk]]:
    """KILLS runs, each SIGKILLed at a random moment, restarted with ``restart``; the last
    ends by SIGTERM. Returns (state on disk after kill k, after kill k + 1) pairs."""
    plant = tmp_path / "plant.py"
    plant.write_text(
        textwrap.dedent(PLANT.format(demo=str(DRILL / "demo_plant.py"), idle=idle, slow=slow))
    )
    state = tmp_path / "drill.sqlite"
    # kills are tested, not a loaded CI's time errors: a generous maximum cycle time
    cmd = [
        sys.executable,
        "-m",
        "s7graph",
        "run",
        str(DRILL / "drill.s7g"),
        "--symbols",
        str(DRILL / "symbols.txt"),
        "--plant",
        str(plant),
        "--state",
        str(state),
        "--restart",
        restart,
        "--max-cycle-ms",
        "5000",
    ]
    rng = random.Random(seed)
    seen: list[OnDisk] = []
    for k in range(KILLS + 1):
        proc = subprocess.Popen(cmd, cwd=ROOT, stderr=subprocess.PIPE, text=True)
        assert proc.stderr is not None
        first = proc.stderr.readline()
        assert " in RUN (" in first, first + proc.stderr.read()
        if k:
            how = "fresh start" if k == 0 else f"{restart} restart from {state} after an unclean"
            assert how in first
            text, steps, faults = _position(_read(state).diagnostics, seen[-1].diagnostics[-1][0])
            assert steps == seen[-1].active, text  # resumed / initialized from what was on disk
            assert faults == seen[-1].faults, text
        if k == KILLS:
            proc.send_signal(signal.SIGTERM)
            assert proc.wait(30) == 0, proc.stderr.read()
        else:
            time.sleep(rng.uniform(0.0, upto_s))
            kill_run(proc)  # and its CPU: its last commit may still land after the run
        proc.stderr.close()
        seen.append(_read(state))
    return list(itertools.pairwise(seen))


def _never_acknowledged(pairs: list[tuple[OnDisk, OnDisk]]) -> None:
    last = pairs[-1][1]
    assert not [a for a in last.alarms if a[2] == "acknowledged"], "nobody acknowledged"
    for before, after in pairs:
        assert after.diagnostics[: len(before.diagnostics)] == before.diagnostics  # append-only
        assert after.alarms[: len(before.alarms)] == before.alarms


@pytest.fixture(scope="module")
def series(tmp_path_factory: pytest.TempPathFactory) -> dict[str, list[tuple[OnDisk, OnDisk]]]:
    """Both series of kills, hot and warm, run side by side: each mostly waits for its
    process to start, or for the moment it is killed."""
    runs = {
        "hot": {"idle": 100, "slow": 3, "seed": 9, "upto_s": 0.9},
        "warm": {"idle": 0, "slow": 1, "seed": 4, "upto_s": 1.0},
    }
    with ThreadPoolExecutor(len(runs)) as pool:
        started = {
            restart: pool.submit(_kill_runs, tmp_path_factory.mktemp(restart), restart, **how)
            for restart, how in runs.items()
        }
        return {restart: future.result() for restart, future in started.items()}


@pytest.mark.timeout(900)
def test_fifty_kills_under_hot_restart_resume_where_the_drill_was(
    series: dict[str, list[tuple[OnDisk, OnDisk]]],
) -> None:
    pairs = series["hot"]
    steps = {s for before, _ in pairs for s in before.active}
    assert len(steps) >= 3, steps  # the kills hit the sequence in several of its steps
    assert any(before.faults for before, _ in pairs), "the clamp never faulted"
    for before, after in pairs:
        assert before.faults <= after.faults  # no fault disappears
        for event_id, msg in before.pending.items():  # no pending message disappears
            assert event_id in after.pending, msg
    _never_acknowledged(pairs)


@pytest.mark.timeout(900)
def test_fifty_kills_under_the_default_warm_restart_keep_alarms_and_diagnostics_true(
    series: dict[str, list[tuple[OnDisk, OnDisk]]],
) -> None:
    pairs = series["warm"]
    assert any(before.pending for before, _ in pairs), "no message was ever pending"
    for before, after in pairs:
        for event_id, msg in before.pending.items():
            kept = after.pending.get(event_id)
            newer = [m for m in after.pending.values() if m["msg_id"] == msg["msg_id"]]
            assert kept is not None or newer, msg  # still listed, or a newer occurrence is
            if kept is not None and msg["state"] == "incoming":
                assert kept["state"] == "outgoing" and kept["reason"] == "warm restart (OB100)"
    outgoing = [a for a in pairs[-1][1].alarms if a[2] == "outgoing"]
    assert outgoing and all(a[4] == "warm restart (OB100)" for a in outgoing)
    _never_acknowledged(pairs)
