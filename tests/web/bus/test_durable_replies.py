"""Durable before answered: a command's reply leaves only once its effect and its audit row
are committed to the state file (web/bus/publisher.py ``apply_commands(durable=...)``,
engine/runner.py ``when_durable``), from the writer thread — never by the scan thread
waiting. The drill chart on the system clock in a real Runner with its writer, a real zenoh
bus on a unix socket; a foreign lock on the state file plays the slow disk."""

from __future__ import annotations

import sqlite3
import threading
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

from s7graph.engine.clock import SystemClock
from s7graph.engine.persistence import StateStore, unpack_instance
from s7graph.engine.record import ScanRecord
from s7graph.engine.runner import Runner
from s7graph.sfb.alarms import message_list
from s7graph.web.access.audit import read_audit
from s7graph.web.bus.client import CLIENT_TIMEOUT_S, BusClient
from s7graph.web.bus.gate import cpu_gate
from s7graph.web.bus.live import LiveGraph
from s7graph.web.bus.protocol import AuditEntry, Command, CommandReply
from s7graph.web.bus.publisher import COMMAND_MAX_AGE_S, REPLY_WITHIN_S, BusPublisher
from s7graph.web.bus.session import open_session
from s7graph.web.harness.session import ChartSession
from tests.paths import ROOT
from tests.web.helpers import wait_until

pytestmark = pytest.mark.timeout(90)
DRILL = ROOT / "examples" / "drill"
FB = "Seq_drill"


@dataclass
class Rig:
    runner: Runner
    client: BusClient
    state: Path
    token: str
    audited: list[AuditEntry]

    def command(self, op: str, **args: object) -> Command:
        return Command(op=op, fb=FB, user="tess", token=self.token, args=args)  # type: ignore[arg-type]


def _rig(tmp_path: Path, reply_within_s: float) -> Iterator[Rig]:
    session = ChartSession.load(DRILL / "drill.s7g", DRILL / "symbols.txt", SystemClock())
    state = tmp_path / "drill.sqlite"
    store = StateStore(state)
    live = LiveGraph(session.graph, read=session.get, messages=message_list(session.cpu))
    endpoint = f"unixsock-stream/{tmp_path}/bus.sock"
    cpu_bus = open_session(listen=[endpoint])
    publisher = BusPublisher(
        cpu_bus,
        "cpu1",
        {FB: live.layout},
        gate=cpu_gate(None, store),
        reply_within_s=reply_within_s,
    )
    runner: Runner

    def on_record(record: ScanRecord) -> None:  # what LiveEdge.on_record does on the bus
        publisher.publish(FB, live.update(record))
        publisher.apply_commands(live.apply, cycle=record.cycle, durable=runner)

    runner = Runner(session.cpu, cycle_ms=10, store=store, on_record=on_record)
    view_bus = open_session(connect=[endpoint])
    client = BusClient(view_bus, "cpu1")
    try:
        runner.startup("warm")
        runner.start_thread()
        login = client.login("tess")
        assert login.ok, login.reason
        audited: list[AuditEntry] = []
        client.on_audit(audited.append)
        yield Rig(runner, client, state, login.token, audited)
    finally:
        runner.request_stop()
        runner.shutdown()
        client.close()
        publisher.close()
        view_bus.close()  # type: ignore[no-untyped-call]
        cpu_bus.close()  # type: ignore[no-untyped-call]
        store.close()


@pytest.fixture
def rig(tmp_path: Path) -> Iterator[Rig]:
    yield from _rig(tmp_path, reply_within_s=4.5)


@pytest.fixture
def impatient_rig(tmp_path: Path) -> Iterator[Rig]:
    yield from _rig(tmp_path, reply_within_s=0.5)


def _mode_on_disk(state: Path) -> str:
    with sqlite3.connect(f"file:{state}?mode=ro", uri=True) as con:
        (blob,) = con.execute("SELECT data FROM instances WHERE number=1").fetchone()
    con.close()
    return str(unpack_instance(blob)["G7_STATE"]["mode"])


def _audit_ops(state: Path) -> list[tuple[str, str, str]]:
    return [(r.user, r.op, r.outcome) for r in read_audit(state) if r.op != "login"]


def _send_in_thread(rig: Rig, command: Command) -> tuple[threading.Thread, list[CommandReply]]:
    replies: list[CommandReply] = []
    thread = threading.Thread(target=lambda: replies.append(rig.client.send(command)))
    thread.start()
    return thread, replies


def _foreign_lock(state: Path) -> sqlite3.Connection:
    """Another connection holding the state file's write lock (a backup tool, a slow disk)."""
    con = sqlite3.connect(state, timeout=10, isolation_level=None)  # between two commits
    con.execute("BEGIN IMMEDIATE")
    return con


def test_when_the_reply_arrives_the_effect_and_the_audit_row_are_on_disk(rig: Rig) -> None:
    reply = rig.client.send(rig.command("mode", mode="MAN"))
    assert reply.applied, reply.reason
    # read at once, from outside: both are committed already
    assert _mode_on_disk(rig.state) == "MAN"
    assert ("tess (unverified)", "mode", "applied") in _audit_ops(rig.state)
    refused = rig.client.send(rig.command("step_on", step=42))
    assert (refused.applied, refused.reason) == (False, f"no step S42 in {FB}")
    assert ("tess (unverified)", "step_on", "refused") in _audit_ops(rig.state)


def test_the_reply_waits_for_the_commit_and_the_scan_does_not(rig: Rig) -> None:
    lock = _foreign_lock(rig.state)
    try:
        thread, replies = _send_in_thread(rig, rig.command("mode", mode="MAN"))
        # applied at the scan boundary (the gate published its audit row) ...
        assert wait_until(lambda: any(e.op == "mode" for e in rig.audited), 10)
        # ... the writer waits for the lock while 50 more scans run ...
        scans = rig.runner.scans
        assert wait_until(lambda: rig.runner.scans >= scans + 50, 10)
        # ... and no answer has left
        assert replies == [] and thread.is_alive()
        assert ("tess (unverified)", "mode", "applied") not in _audit_ops(rig.state)
    finally:
        lock.rollback()
        lock.close()
    thread.join(10)
    assert len(replies) == 1 and replies[0].applied, replies
    assert _mode_on_disk(rig.state) == "MAN"
    assert ("tess (unverified)", "mode", "applied") in _audit_ops(rig.state)
    assert rig.runner.overruns == 0 or rig.runner.scans > 50


def test_a_command_the_disk_has_not_confirmed_in_time_is_answered_as_not_confirmed(
    impatient_rig: Rig,
) -> None:
    rig = impatient_rig
    lock = _foreign_lock(rig.state)
    try:
        reply = rig.client.send(rig.command("mode", mode="MAN"))
    finally:
        lock.rollback()
        lock.close()
    assert not reply.applied
    assert reply.reason.startswith("not confirmed: applied in cycle "), reply.reason
    assert reply.reason.endswith("but the state file has not committed it within 0.5 s")
    assert reply.kind == "timeout"
    # it was applied, and lands once the lock is gone
    assert wait_until(lambda: _mode_on_disk(rig.state) == "MAN", 10)
    assert wait_until(lambda: ("tess (unverified)", "mode", "applied") in _audit_ops(rig.state), 10)


def test_every_command_is_answered_within_its_senders_timeout() -> None:
    """A command waits at most ``COMMAND_MAX_AGE_S`` for its scan boundary (else refused),
    and is answered — confirmed or not — ``REPLY_WITHIN_S`` after it came at the latest,
    before the sender's ``BusClient`` gives up."""
    assert COMMAND_MAX_AGE_S < REPLY_WITHIN_S < CLIENT_TIMEOUT_S
    assert CLIENT_TIMEOUT_S - REPLY_WITHIN_S >= 0.5  # the reply's way back over the bus
    assert BusClient.__init__.__kwdefaults__ == {"timeout": CLIENT_TIMEOUT_S}
