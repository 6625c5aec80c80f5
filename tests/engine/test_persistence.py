"""Retentive state in SQLite; a killed CPU process comes back by warm restart
(docs/state-file.md)."""

from __future__ import annotations

import base64
import json
import math
import os
import signal
import sqlite3
import subprocess
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

from s7graph.engine import DB, CallContext, Cpu, InstanceDB, VirtualClock, fb, ob
from s7graph.engine.persistence import StateStore, unpack_instance
from tests.real_process import ROOT, kill_run, query_store, run_command, wait_for


@fb(2, STAT={"total": ("DINT", 0), "note": ("STRING[8]", "")})
def acc(ctx: CallContext, db: InstanceDB) -> None:
    db.total = int(db.total) + 1  # type: ignore[call-overload]


@ob(1)
def main(ctx: CallContext) -> None:
    ctx.mem.set("MW2", int(ctx.mem.get("MW2")) + 1)  # type: ignore[call-overload]
    ctx.mem.set("MW100", 5)
    ctx.call(acc, 2)


def _cpu(clock: VirtualClock) -> Cpu:
    cpu = Cpu(clock)
    cpu.load(main, acc, DB(1, 4))
    cpu.create_instance_db(2, acc)
    return cpu


def test_state_round_trips_and_restarts_warm(clock: VirtualClock, tmp_path: Path) -> None:
    """After load + warm restart retentive M, DBs and instance DBs are intact,
    non-retentive M is cleared; the diagnostic buffer comes back too."""
    store = StateStore(tmp_path / "s.sqlite")
    cpu = _cpu(clock)
    cpu.start()
    for _ in range(5):
        clock.advance(10)
        cpu.scan()
    cpu.mem.set("DB1.DBW2", 1234)
    cpu.instance_db(2).note = "hello"
    store.save(cpu)
    store.close()

    again = _cpu(VirtualClock())
    store = StateStore(tmp_path / "s.sqlite")
    assert store.load(again)
    again.start("warm")
    assert again.mem.get("MW2") == 5 and again.mem.get("MW100") == 0
    assert again.mem.get("DB1.DBW2") == 1234
    assert again.instance_db(2).total == 5 and again.instance_db(2).note == "hello"
    assert [e.message for e in again.diagnostics][:2] == ["warm restart", "STARTUP → RUN (warm)"]


def _rows(path: Path) -> list[tuple[int, str]]:
    with sqlite3.connect(path) as con:
        rows = [(int(r[0]), str(r[1])) for r in con.execute("SELECT seq, message FROM diagnostics")]
    con.close()
    return rows


def test_diagnostic_entries_keep_their_numbers_across_restarts(
    clock: VirtualClock, tmp_path: Path
) -> None:
    """Entry N is row N - 1 of the state file; a CPU that reads the buffer back numbers on
    from the last entry written there, even when it holds fewer than were written."""
    path = tmp_path / "s.sqlite"
    store = StateStore(path)
    cpu = Cpu(clock, diag_capacity=4)
    cpu.load(main, acc, DB(1, 4))
    cpu.create_instance_db(2, acc)
    for k in range(6):
        cpu.diagnostics.record(clock.now_ns(), 0x5FFF, message=f"first run {k}")
    store.save(cpu)
    store.close()
    assert cpu.diagnostics.total == 6

    again = Cpu(VirtualClock(), diag_capacity=4)
    again.load(main, acc, DB(1, 4))
    again.create_instance_db(2, acc)
    store = StateStore(path)
    assert store.load(again)
    assert again.diagnostics.total == 6 and len(again.diagnostics) == 4
    again.diagnostics.record(0, 0x5FFF, message="second run")
    assert again.diagnostics.total == 7
    for k in range(5):  # more than the ring holds between two saves: 7 and 8 are lost
        again.diagnostics.record(0, 0x5FFF, message=f"burst {k}")
    store.save(again)
    store.close()
    rows = _rows(path)
    assert rows[:4] == [(k, f"first run {k}") for k in range(2, 6)]  # 0 and 1 were lost
    assert rows[4:] == [(8, "burst 1"), (9, "burst 2"), (10, "burst 3"), (11, "burst 4")]
    third = Cpu(VirtualClock(), diag_capacity=4)
    third.load(main, acc, DB(1, 4))
    third.create_instance_db(2, acc)
    store = StateStore(path)
    assert store.load(third)
    store.close()
    assert third.diagnostics.total == 12


@fb(3, STAT={"r": ("REAL", 0.0), "inf": ("REAL", 0.0), "big": ("OBJECT", None)})
def holder(ctx: CallContext, db: InstanceDB) -> None:
    pass


def test_instance_values_come_back_exactly_nan_infinity_and_big_integers_included(
    tmp_path: Path,
) -> None:
    """A REAL may hold NaN or infinity (a division by zero) and a plain OBJECT any integer:
    the instance row keeps them as they were (MessagePack; JSON for an integer beyond 64
    bits)."""

    def program() -> Cpu:
        cpu = Cpu(VirtualClock())
        cpu.load(holder)
        cpu.create_instance_db(3, holder)
        cpu.create_instance_db(4, holder)
        return cpu

    cpu = program()
    cpu.instance_db(3).values.update({"r": float("nan"), "inf": float("-inf")})
    cpu.instance_db(4).values.update({"big": [2**70, -(2**63), "x"]})
    store = StateStore(tmp_path / "s.sqlite")
    store.save(cpu)
    store.close()

    again = program()
    store = StateStore(tmp_path / "s.sqlite")
    store.load(again)
    store.close()
    got = again.instance_db(3).values
    assert math.isnan(got["r"]) and got["inf"] == float("-inf")  # type: ignore[arg-type]
    assert again.instance_db(4).values["big"] == [2**70, -(2**63), "x"]


def test_maybe_save_writes_only_when_retentive_data_changed(
    clock: VirtualClock, tmp_path: Path
) -> None:
    """Saving each scan that changed retentive data — and only then."""
    store = StateStore(tmp_path / "s.sqlite")
    cpu = Cpu(clock)
    cpu.start()
    assert store.maybe_save(cpu)
    cpu.scan()
    assert not store.maybe_save(cpu)
    cpu.mem.set("MW100", 9)  # not retentive
    assert not store.maybe_save(cpu)
    cpu.mem.set("MW0", 9)
    assert store.maybe_save(cpu)


def test_interval_limits_how_often_it_saves(clock: VirtualClock, tmp_path: Path) -> None:
    """A configurable interval bounds the saving rate."""
    store = StateStore(tmp_path / "s.sqlite", interval_ms=100)
    cpu = Cpu(clock)
    cpu.start()
    assert store.maybe_save(cpu)
    cpu.mem.set("MW0", 1)
    clock.advance(50)
    assert not store.maybe_save(cpu)
    clock.advance(50)
    assert store.maybe_save(cpu)


def test_alarm_and_audit_tables(tmp_path: Path) -> None:
    """Alarms and the audit log (who, what, when) are stored append-only."""
    store = StateStore(tmp_path / "s.sqlite")
    store.log_alarm(5, "FB1.S3.V", "incoming", "Step 3 supervision")
    store.log_audit(7, "ann", "ack", "FB1 S3")
    assert store.alarms() == [
        {
            "t_ns": 5,
            "key": "FB1.S3.V",
            "state": "incoming",
            "text": "Step 3 supervision",
            "user": "",
            "cpu_ns": None,
            "reason": "",
        }
    ]
    assert store.audit()[0]["user"] == "ann"


def test_an_existing_files_alarm_log_is_bounded_counting_the_rows_it_held(
    tmp_path: Path,
) -> None:
    """The rows a file holds are counted when it is opened (read-only) and taken as they
    are when it is opened for writing: the 21st row over a limit of 20 rolls the oldest."""
    first = StateStore(tmp_path / "s.sqlite")
    for i in range(15):
        first.log_alarm(10**18 + i, f"M{i}", "incoming", "text")
    first.close()
    store = StateStore(tmp_path / "s.sqlite")
    store.alarm_limit = 20
    store.open_writing()
    for i in range(5):
        store.log_alarm(2 * 10**18 + i, f"N{i}", "incoming", "text")
    assert len(store.alarms()) == 20  # not over the limit: nothing rolled
    store.log_alarm(3 * 10**18, "N5", "incoming", "text")
    rolled = store._db.execute("SELECT SUM(count) FROM alarm_summary").fetchone()[0]
    assert len(store.alarms()) < 20 and rolled + len(store.alarms()) == 21
    assert store.alarms()[-1]["key"] == "N5"
    store.close()


@dataclass(frozen=True)
class _Event:  # the shape of sfb.alarms.MessageEvent (the engine may not import sfb)
    kind: str
    msg_id: int | str
    event_id: int
    t_ns: int
    user: str = ""
    text: str = ""


def test_log_alarms_appends_each_message_event_with_its_user(tmp_path: Path) -> None:
    """Every message event of a scan record goes to the alarm log: who acknowledged, when
    (wall time) and the CPU clock's time; anything else in the record is skipped."""
    store = StateStore(tmp_path / "s.sqlite")
    events = (
        _Event("incoming", "FB1/DB1/S2/SV", 1, 10, text="S002 overdue"),
        "not a message event",
        _Event("acknowledged", "FB1/DB1/S2/SV", 1, 20, "ann", "S002 overdue"),
    )
    assert store.log_alarms(events, wall_ns=1_700_000_000_000_000_000) == 2
    rows = store.alarms()
    assert [(r["state"], r["user"], r["cpu_ns"]) for r in rows] == [
        ("incoming", "", 10),
        ("acknowledged", "ann", 20),
    ]
    assert {r["t_ns"] for r in rows} == {1_700_000_000_000_000_000}


def test_added_parts_are_saved_with_the_state_and_restored_on_load(
    clock: VirtualClock, tmp_path: Path
) -> None:
    """``add_part``: extra named snapshots (the CPU's message list) ride in every save;
    a changed part alone makes ``maybe_save`` write."""
    part = {"messages": ["m1"]}
    store = StateStore(tmp_path / "s.sqlite")
    store.add_part("extra", lambda: dict(part), lambda data: None)
    cpu = Cpu(clock)
    cpu.start()
    assert store.maybe_save(cpu)
    assert not store.maybe_save(cpu)
    part["messages"] = ["m1", "m2"]
    assert store.maybe_save(cpu)
    store.close()

    restored: list[object] = []
    store = StateStore(tmp_path / "s.sqlite")
    store.add_part("extra", dict, restored.append)
    store.add_part("unknown", dict, restored.append)  # nothing saved under it: not called
    assert store.load(Cpu(VirtualClock()))
    assert restored == [{"messages": ["m1", "m2"]}]


def test_an_old_state_file_gains_the_user_column_of_the_alarm_log(tmp_path: Path) -> None:
    path = tmp_path / "old.sqlite"
    with sqlite3.connect(path) as con:
        con.execute(
            "CREATE TABLE alarms (id INTEGER PRIMARY KEY AUTOINCREMENT, t_ns INTEGER, "
            "key TEXT, state TEXT, text TEXT)"
        )
        con.execute("INSERT INTO alarms (t_ns, key, state, text) VALUES (1, 'k', 'incoming', '')")
    con.close()
    store = StateStore(path)
    store.log_alarm(2, "k", "acknowledged", user="bob")
    assert [(r["state"], r["user"]) for r in store.alarms()] == [
        ("incoming", ""),
        ("acknowledged", "bob"),
    ]


PROGRAM = """
from s7graph.engine import DB, fb, ob

RESTARTS = DB(1, 8)

@ob(100)
def startup(ctx):
    ctx.mem.set("DB1.DBW0", ctx.mem.get("DB1.DBW0") + 1)   # restart count
    ctx.mem.set("DB1.DBW2", ctx.mem.get("MW2"))            # retentive MW seen at restart
    ctx.mem.set("DB1.DBW4", ctx.mem.get("MW100"))          # non-retentive MW seen at restart

@fb(2, STAT={"total": ("DINT", 0)})
def acc(ctx, db):
    db.total += 1

@ob(1)
def main(ctx):
    ctx.mem.set("MW2", ctx.mem.get("MW2") + 1)
    ctx.mem.set("MW100", ctx.mem.get("MW100") + 1)
    ctx.call(acc, 2)

def setup(cpu):
    cpu.create_instance_db(2, acc)
"""


def _read(path: Path) -> dict[str, Any] | None:
    rows = query_store(
        path,
        lambda con: (
            con.execute("SELECT value FROM meta WHERE key='memory'").fetchone(),
            con.execute("SELECT data FROM instances WHERE number=2").fetchone(),
            con.execute("SELECT value FROM meta WHERE key='last_restart'").fetchone(),
        ),
    )
    if rows is None:
        return None
    row, inst, restart = rows
    if row is None or inst is None:
        return None
    mem = json.loads(row[0])
    markers = base64.b64decode(mem["markers"]["data"])
    db1 = base64.b64decode(mem["dbs"]["1"]["data"])
    return {
        "MW2": int.from_bytes(markers[2:4], "big"),
        "restarts": int.from_bytes(db1[0:2], "big"),
        "MW2_at_restart": int.from_bytes(db1[2:4], "big"),
        "MW100_at_restart": int.from_bytes(db1[4:6], "big"),
        "total": unpack_instance(inst[0])["total"],
        "last_restart": restart[0] if restart else "",
    }


@pytest.mark.timeout(90)
@pytest.mark.skipif(os.name != "posix", reason="SIGKILL")
def test_killed_cpu_process_comes_back_by_warm_restart(tmp_path: Path) -> None:
    """A SIGKILLed CPU process restarts warm with every retentive value intact
    (retentive MW, DB and instance DB) and non-retentive MW cleared."""
    cmd, state = run_command(tmp_path, PROGRAM)

    first = subprocess.Popen(cmd, cwd=ROOT, stderr=subprocess.PIPE)
    try:
        wait_for(_read, state, lambda s: s["MW2"] >= 20, first)
    finally:
        kill_run(first)
    killed = _read(state)
    assert killed is not None and killed["restarts"] == 1

    second = subprocess.Popen(cmd, cwd=ROOT, stderr=subprocess.PIPE)
    try:
        after = wait_for(_read, state, lambda s: s["restarts"] == 2, second)
    finally:
        second.send_signal(signal.SIGTERM)
        second.wait(10)
    assert after["last_restart"] == "warm"
    assert after["MW2_at_restart"] == killed["MW2"]  # retentive marker intact
    assert after["MW100_at_restart"] == 0  # non-retentive marker cleared
    assert after["total"] >= killed["total"]  # instance DB intact
    final = _read(state)
    assert final is not None and final["MW2"] >= killed["MW2"]
