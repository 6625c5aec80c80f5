"""The CPU's message list and its acknowledgement log survive a killed ``s7graph run``
process (who acknowledged, when, persisted)."""

from __future__ import annotations

import base64
import json
import os
import signal
import subprocess
import time
from pathlib import Path
from typing import Any

import pytest

from tests.real_process import ROOT, kill_run, query_store, run_command, wait_for

PROGRAM = """
from s7graph.engine import DB, ob
from s7graph.sfb.alarms import message_list

SEEN = DB(1, 8)

@ob(100)
def startup(ctx):
    msg = message_list(ctx.cpu).get(7)
    ctx.mem.set("DB1.DBW0", ctx.mem.get("DB1.DBW0") + 1)   # restart count
    ctx.mem.set("DB1.DBX2.0", msg is not None and msg.acked and msg.ack_user == "ann")

@ob(1)
def main(ctx):
    messages = message_list(ctx.cpu)
    now = ctx.cpu.clock.now_ns()
    n = ctx.mem.get("MW2") + 1   # retentive: counts on across restarts
    ctx.mem.set("MW2", n)
    if n == 3:
        messages.alarm(True, 7, now, text="Tank 7 overflow")   # ALARM_SQ, incoming
    if n == 6:
        messages.acknowledge(7, "ann", now)
    for event in messages.pop_events():
        ctx.alarm(event)
"""


def _read(path: Path) -> dict[str, Any] | None:
    rows = query_store(
        path,
        lambda con: (
            con.execute("SELECT t_ns, key, state, user FROM alarms ORDER BY id").fetchall(),
            con.execute("SELECT state FROM parts WHERE name='messages'").fetchone(),
            con.execute("SELECT value FROM meta WHERE key='memory'").fetchone(),
        ),
    )
    if rows is None:
        return None
    alarms, part, db1 = rows
    if part is None or db1 is None:
        return None
    data = base64.b64decode(json.loads(db1[0])["dbs"]["1"]["data"])
    return {
        "alarms": alarms,
        "messages": json.loads(part[0]),
        "restarts": int.from_bytes(data[0:2], "big"),
        "restored_ack": bool(data[2] & 1),
    }


def _acked(state: dict[str, Any]) -> bool:
    active = state["messages"]["active"]
    return bool(active) and active[0]["ack_user"] == "ann"


@pytest.mark.timeout(90)
@pytest.mark.skipif(os.name != "posix", reason="SIGKILL")
def test_killed_cpu_keeps_its_message_list_and_who_acknowledged_when(tmp_path: Path) -> None:
    cmd, state = run_command(tmp_path, PROGRAM)
    started = time.time_ns()

    first = subprocess.Popen(cmd, cwd=ROOT, stderr=subprocess.PIPE)
    try:
        killed = wait_for(_read, state, lambda s: _acked(s) and len(s["alarms"]) == 2, first)
    finally:
        kill_run(first)
    (incoming, acked) = killed["alarms"]
    assert incoming[1:] == ("7", "incoming", "")
    assert acked[1:] == ("7", "acknowledged", "ann")
    assert started <= incoming[0] <= acked[0] <= time.time_ns()  # wall-clock "when"

    second = subprocess.Popen(cmd, cwd=ROOT, stderr=subprocess.PIPE)
    try:
        after = wait_for(_read, state, lambda s: s["restarts"] == 2, second)
    finally:
        second.send_signal(signal.SIGTERM)
        second.wait(10)
    assert after["restored_ack"]  # OB100 of the new process saw message 7 acked by ann
    (message,) = after["messages"]["active"]
    assert (message["msg_id"], message["state"], message["text"]) == (
        7,
        "incoming",
        "Tank 7 overflow",
    )
    assert message["ack_ns"] is not None
    assert after["alarms"][:2] == killed["alarms"]  # the log is append-only, kept
