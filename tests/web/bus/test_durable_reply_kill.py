"""A kill right after the reply loses nothing: ``s7graph run`` of the drill demo as a real
process on the bus; a command is sent, and the moment its reply *applied* arrives the CPU
is killed with SIGKILL. The state file then holds the command's effect and its audit row,
and the CPU restarted hot (``--restart hot``) shows the effect."""

from __future__ import annotations

import sqlite3
import subprocess
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

from s7graph.engine.persistence import unpack_instance
from s7graph.web.access.audit import read_audit
from s7graph.web.bus.client import BusClient
from s7graph.web.bus.protocol import Command
from tests.paths import ROOT
from tests.real_process import kill_run
from tests.web.helpers import cpu_process, wait_until

pytestmark = pytest.mark.timeout(180)
DRILL = ROOT / "examples" / "drill"
FB = "Seq_drill"
USER = "tess (unverified)"


@contextmanager
def cpu(tmp_path: Path, state: Path) -> Iterator[tuple[subprocess.Popen[str], BusClient, str]]:
    """The drill demo restarted hot from ``state``, on a unix socket; a client logged in."""
    args = [
        str(DRILL / "drill.s7g"),
        "--symbols",
        str(DRILL / "symbols.txt"),
        "--plant",
        str(DRILL / "demo_plant.py"),
        "--state",
        str(state),
        "--restart",
        "hot",
        "--duration-s",
        "120",
    ]
    with cpu_process(tmp_path, args, fb=FB, user="tess") as running:
        yield running


def _send_and_kill(proc: subprocess.Popen[str], client: BusClient, command: Command) -> None:
    reply = client.send(command)
    kill_run(proc)  # at once, on the reply
    assert reply.applied, reply.reason


def _disk(state: Path) -> tuple[str, list[tuple[str, str, str]]]:
    """The FB's mode and the alarm log's (key, state, user) rows, as the file holds them."""
    with sqlite3.connect(f"file:{state}?mode=ro", uri=True) as con:
        (blob,) = con.execute("SELECT data FROM instances WHERE number=1").fetchone()
        alarms = con.execute("SELECT key, state, user FROM alarms ORDER BY id").fetchall()
    con.close()
    return str(unpack_instance(blob)["G7_STATE"]["mode"]), alarms


def test_the_effect_and_the_audit_row_of_an_answered_command_survive_sigkill(
    tmp_path: Path,
) -> None:
    state = tmp_path / "drill.sqlite"
    with cpu(tmp_path, state) as (proc, client, token):
        as_tess = {"fb": FB, "user": "tess", "token": token}
        _send_and_kill(proc, client, Command(op="mode", args={"mode": "MAN"}, **as_tess))
    mode, _ = _disk(state)
    assert mode == "MAN"
    assert (USER, "mode", "applied") in [(r.user, r.op, r.outcome) for r in read_audit(state)]

    with cpu(tmp_path, state) as (proc, client, token):
        snapshot = client.state(FB)
        assert snapshot is not None and snapshot.mode == "MAN"  # resumed, hot
        as_tess = {"fb": FB, "user": "tess", "token": token}
        if 2 not in snapshot.active:
            reply = client.send(Command(op="step_on", args={"step": 2}, **as_tess))
            assert reply.applied, reply.reason
        # MAN holds S2: its supervision (500 ms) trips, a message comes

        def pending() -> str | None:
            alarms = client.alarms()
            waiting = [e for e in alarms.entries if not e.acked] if alarms else []
            return waiting[0].msg_id if waiting else None

        assert wait_until(lambda: pending() is not None, 30)
        msg_id = pending()
        assert msg_id is not None
        _send_and_kill(proc, client, Command(op="ack_msg", args={"msg_id": msg_id}, **as_tess))
    _, alarms = _disk(state)
    assert (msg_id, "acknowledged", USER) in alarms
    assert (USER, "ack_msg", "applied") in [(r.user, r.op, r.outcome) for r in read_audit(state)]

    with cpu(tmp_path, state) as (_, client, _):
        history = client.history()
        assert history is not None
        assert any(
            e.msg_id == msg_id and e.state == "acknowledged" and e.user == USER
            for e in history.entries
        )
