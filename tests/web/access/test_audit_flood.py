"""Refusals of unauthenticated senders are counted, not written one by one
(web/access/tally.py): a flood adds a row a minute per source and reason, and every refusal
is still in a count; an authenticated sender's refusals stay one row each. The gate is
driven directly with an injected wall clock, then over a real zenoh bus."""

from __future__ import annotations

import threading
from collections.abc import Iterator
from pathlib import Path

import pytest

from s7graph.engine import Cpu, VirtualClock
from s7graph.engine.persistence import StateStore
from s7graph.engine.writer import StoreWriter
from s7graph.web.access.audit import UNAUTHENTICATED, AuditRecord, AuditStore, read_audit
from s7graph.web.access.login import Authenticator
from s7graph.web.access.scram import MIN_ITERATIONS
from s7graph.web.access.tally import MAX_KINDS
from s7graph.web.access.users import UsersFile
from s7graph.web.bus.gate import Gate
from s7graph.web.bus.protocol import AuditEntry, Command, LoginRequest
from tests.web.access.gate_login import gate_login

PASSWORD = "correct horse"
MINUTE = 60 * 10**9
T0 = 29_833_333 * MINUTE + 50 * 10**9  # 50 s into a minute: a 20 s flood spans two


class Wall:
    """The gate's wall clock, moved by the test."""

    def __init__(self, t_ns: int = T0) -> None:
        self.t_ns = t_ns

    def __call__(self) -> int:
        return self.t_ns


@pytest.fixture
def users(tmp_path: Path) -> UsersFile:
    users = UsersFile(tmp_path / "users.json")
    users.add("olga", "operator", PASSWORD, iterations=MIN_ITERATIONS)
    users.add("vic", "viewer", PASSWORD, iterations=MIN_ITERATIONS)
    return users


def forged(origin: str = "10.0.0.66", user: str = "mallory") -> Command:
    return Command(op="init", fb="FILL", user=user, token="forgedforgedforged", origin=origin)


def applied(command: Command) -> tuple[bool, str]:
    return True, ""


def rows(path: Path, op: str | None = None) -> list[AuditRecord]:
    return [r for r in read_audit(path) if op is None or r.op == op]


def test_a_20_s_flood_of_unauthenticated_refusals_adds_at_most_1000_rows_and_counts_every_one(
    tmp_path: Path, users: UsersFile
) -> None:
    wall = Wall()
    gate = Gate(Authenticator(users), AuditStore(tmp_path / "s.sqlite"), wall_ns=wall, flush_s=None)
    published: list[AuditEntry] = []
    gate.on_audit = published.append
    sent = 0
    for ms in range(20_000):  # 20 s, two refusals a millisecond: 2,000 a second
        wall.t_ns = T0 + ms * 1_000_000
        for _ in range(2):
            assert gate.apply(forged(), applied) == (False, "invalid token: log in again")
            sent += 1
        if ms % 1000 == 999:
            gate.flush()  # what the timer does every second
    gate.flush()
    audit = rows(tmp_path / "s.sqlite")
    assert sent == 40_000 and len(audit) <= 1000
    assert len(audit) == 2  # one a minute: the flood spans two
    assert sum(r.count for r in audit) == sent
    assert {(r.user, r.claimed, r.role, r.origin, r.reason) for r in audit} == {
        (UNAUTHENTICATED, "mallory", "", "10.0.0.66", "invalid token: log in again")
    }
    assert len(published) <= 2 + 20 + 2  # the rows, a count a second, the last counts
    assert {e.id for e in published} == {r.id for r in audit}
    assert published[-1].count == audit[-1].count


def test_every_refusal_is_counted_while_the_flood_runs_not_only_at_its_end(
    tmp_path: Path, users: UsersFile
) -> None:
    wall = Wall(T0 - 40 * 10**9)  # 10 s into a minute
    gate = Gate(Authenticator(users), AuditStore(tmp_path / "s.sqlite"), wall_ns=wall, flush_s=None)
    for _ in range(500):
        gate.apply(forged(), applied)
    first = rows(tmp_path / "s.sqlite")
    assert [r.count for r in first] == [1]  # written at once: an operator sees it start
    assert [e.count for e in gate.audit_list().entries] == [500]  # the panel: the live count
    gate.flush()
    assert [r.count for r in rows(tmp_path / "s.sqlite")] == [500]


def test_refusals_from_two_sources_are_two_rows(tmp_path: Path, users: UsersFile) -> None:
    wall = Wall(T0 - 40 * 10**9)
    gate = Gate(Authenticator(users), AuditStore(tmp_path / "s.sqlite"), wall_ns=wall, flush_s=None)
    for _ in range(300):
        gate.apply(forged("10.0.0.66"), applied)
        gate.apply(forged("10.0.0.67"), applied)
    gate.flush()
    assert sorted((r.origin, r.count) for r in rows(tmp_path / "s.sqlite")) == [
        ("10.0.0.66", 300),
        ("10.0.0.67", 300),
    ]


def test_an_authenticated_users_refusals_are_not_aggregated(
    tmp_path: Path, users: UsersFile
) -> None:
    wall = Wall(T0 - 40 * 10**9)
    gate = Gate(Authenticator(users), AuditStore(tmp_path / "s.sqlite"), wall_ns=wall, flush_s=None)
    vic = gate_login(gate, "vic", PASSWORD)[1]
    assert vic is not None
    for _ in range(30):
        command = vic.sign(
            Command(op="mode", fb="FILL", user="vic", token=vic.token, args={"mode": "MAN"})
        )
        assert gate.apply(command, applied) == (False, "role viewer may not mode (needs operator)")
        gate.refuse(command, "command queue full; the CPU is not draining commands")
    gate.flush()
    audit = rows(tmp_path / "s.sqlite", "mode")
    assert len(audit) == 60 and {(r.user, r.role, r.count) for r in audit} == {("vic", "viewer", 1)}


def test_every_kind_of_unauthenticated_refusal_is_counted_and_only_those(
    tmp_path: Path, users: UsersFile
) -> None:
    wall = Wall(T0 - 40 * 10**9)
    gate = Gate(
        Authenticator(users, max_failures=1000),
        AuditStore(tmp_path / "s.sqlite"),
        wall_ns=wall,
        flush_s=None,
    )
    signer = gate_login(gate, "olga", PASSWORD)[1]
    assert signer is not None
    olga = signer.token
    kinds = {
        "no token": lambda: gate.apply(Command(op="init", fb="FILL", user="olga"), applied),
        "forged token": lambda: gate.apply(forged(user="olga"), applied),
        "another's token": lambda: gate.apply(
            Command(op="init", fb="FILL", user="vic", token=olga), applied
        ),
        "unreadable": lambda: gate.refuse(None, "not a command: expected JSON", origin="bus"),
        "unknown FB, forged": lambda: gate.refuse(forged(), "unknown FB 'X'"),
        "logout of no session": lambda: gate.login(LoginRequest(op="logout", token="nosuch")),
    }
    for _ in range(20):
        for send in kinds.values():
            send()
    for _ in range(3):  # a few (each a whole exchange)
        gate_login(gate, "olga", "not it at all")
        gate_login(gate, "nobody", "not it at all")
    for _ in range(4):  # and what is not anonymous: one row each
        gate.apply(signer.sign(Command(op="init", fb="FILL", user="olga", token=olga)), applied)
        gate_login(gate, "olga", PASSWORD)
    gate.flush()
    audit = rows(tmp_path / "s.sqlite")
    counted = [r for r in audit if r.count > 1]
    assert sorted(r.count for r in counted) == [3, 3] + [20] * len(kinds)
    assert {(r.user, r.claimed, r.reason) for r in counted if r.op == "login"} == {
        (UNAUTHENTICATED, "olga", "wrong user name or password"),  # a user: her own row
        (UNAUTHENTICATED, "nobody", "wrong user name or password"),
    }
    singles = [(r.user, r.op, r.outcome) for r in audit if r.count == 1]
    assert (
        singles
        == [("olga", "login", "applied")]
        + [
            ("olga", "init", "applied"),
            ("olga", "login", "applied"),
        ]
        * 4
    )
    assert sum(r.count for r in audit) == 1 + 20 * len(kinds) + 6 + 8


def test_a_window_row_says_star_where_its_refusals_differed(
    tmp_path: Path, users: UsersFile
) -> None:
    wall = Wall(T0 - 40 * 10**9)
    gate = Gate(Authenticator(users), AuditStore(tmp_path / "s.sqlite"), wall_ns=wall, flush_s=None)
    gate.apply(forged(user="mallory"), applied)
    gate.apply(forged(user="eve"), applied)
    gate.flush()
    [row] = rows(tmp_path / "s.sqlite")
    assert (row.user, row.claimed, row.op, row.origin, row.count) == (
        UNAUTHENTICATED,
        "*",
        "init",
        "10.0.0.66",
        2,
    )


def test_made_up_sources_cannot_open_more_than_max_kinds_windows_a_minute(
    tmp_path: Path, users: UsersFile
) -> None:
    wall = Wall(T0 - 40 * 10**9)
    gate = Gate(
        Authenticator(users),
        AuditStore(tmp_path / "s.sqlite"),
        wall_ns=wall,
        flush_s=None,
        max_kinds=8,
    )
    for i in range(5000):
        gate.apply(forged(origin=f"made up {i}"), applied)
    gate.flush()
    audit = rows(tmp_path / "s.sqlite")
    assert len(audit) == 8 + 1 and sum(r.count for r in audit) == 5000
    assert audit[-1].origin == "*" and f"more than {MAX_KINDS}" in audit[-1].reason


@pytest.fixture
def cpu() -> Cpu:
    cpu = Cpu(VirtualClock())
    cpu.start()
    return cpu


def test_with_the_state_writer_a_window_costs_one_row_and_one_job_a_commit(
    tmp_path: Path, users: UsersFile, cpu: Cpu
) -> None:
    state = StateStore(tmp_path / "s.sqlite")
    writer = StoreWriter(state)
    try:
        audit = AuditStore(state.path, state=state)
        gate = Gate(Authenticator(users), audit, wall_ns=Wall(T0 - 40 * 10**9), flush_s=None)
        for mark in (1, 2, 3):
            for _ in range(5000):
                gate.apply(forged(), applied)
            batch = state.stage(cpu, upto=mark)
            assert batch is not None
            assert len(batch.appended) == (1 if mark == 1 else 0) and len(batch.jobs) == 1
            writer.submit(batch, mark)
            assert writer.flush(10)
            assert [r.count for r in rows(state.path)] == [5000 * mark]  # no flush: the job
        audit.close()
    finally:
        writer.close()
        state.close()


# ---------------------------------------------------------------- over the bus


@pytest.fixture
def bus(tmp_path: Path, users: UsersFile) -> Iterator[tuple[Gate, Path, object]]:
    from s7graph.sequencer.text.model import Chart, Sequence, Step, Transition
    from s7graph.web.bus.client import BusClient
    from s7graph.web.bus.protocol import ChartLayout, StepStateUpdate
    from s7graph.web.bus.publisher import BusPublisher
    from s7graph.web.bus.session import open_session
    from tests.web.helpers import wait_until

    steps = (Step(1, "Idle", initial=True), Step(2, "Run"))
    transitions = (Transition(1, "", (1,), (2,)), Transition(2, "", (2,), (1,)))
    layout = ChartLayout.from_chart(
        Chart("FILL", sequences=(Sequence(1, "M", steps, transitions),))
    )
    store = AuditStore(tmp_path / "s.sqlite")
    gate = Gate(Authenticator(users), store)
    endpoint = f"unixsock-stream/{tmp_path}/bus.sock"
    stop = threading.Event()
    with open_session(listen=[endpoint]) as cpu, open_session(connect=[endpoint]) as view:
        publisher = BusPublisher(cpu, "cpu1", {"FILL": layout}, gate=gate)
        client = BusClient(view, "cpu1")

        def scan() -> None:
            cycle = 0
            while not stop.is_set():
                cycle += 1
                update = StepStateUpdate(cycle=cycle, t_ms=cycle, mode="AUTO", active=[1])
                publisher.publish("FILL", update)
                publisher.apply_commands(applied, cycle=cycle)
                stop.wait(0.002)

        scanner = threading.Thread(target=scan)
        scanner.start()
        try:
            assert wait_until(lambda: client.status() is not None)
            yield gate, store.path, client
        finally:
            stop.set()
            scanner.join(5)
            client.close()
            publisher.close()
            store.close()


def test_a_flood_over_the_bus_is_a_row_per_kind_and_the_audit_topic_is_not_flooded(
    bus: tuple[Gate, Path, object],
) -> None:
    from s7graph.web.bus.client import BusClient
    from s7graph.web.bus.protocol import encode

    gate, path, client = bus
    assert isinstance(client, BusClient)
    published: list[AuditEntry] = []
    client.on_audit(published.append)
    bad = encode(Command(op="init", fb="FILL", user="mallory", token="forged", origin="x"))
    for _ in range(300):
        reply = client.send_raw(b"not json", timeout=5)
        assert reply is not None and not reply.applied
    for _ in range(100):
        reply = client.send_raw(bad, timeout=5)
        assert reply is not None and reply.reason == "invalid token: log in again"
    gate.flush()
    audit = rows(path)
    assert 2 <= len(audit) <= 4  # two kinds, in one minute or across two
    assert sum(r.count for r in audit) == 400
    assert len(published) < 40  # was 400: a message a refusal


def test_a_command_that_breaks_in_the_cpu_is_refused_and_audited_in_words(
    tmp_path: Path, users: UsersFile
) -> None:
    """A defect of ours behind the gate's last guard: the reply and the audit row say it
    is an internal error, which op on which FB, and what it said — no class name."""
    gate = Gate(Authenticator(users), AuditStore(tmp_path / "s.sqlite"), flush_s=None)
    olga = gate_login(gate, "olga", PASSWORD)[1]
    assert olga is not None
    command = olga.sign(Command(op="init", fb="FILL", user="olga", token=olga.token))

    def broken(command: Command) -> tuple[bool, str]:
        raise KeyError("x")

    why = (
        "command refused: an internal error in the CPU while applying init to FILL: 'x' "
        "(please report it)"
    )
    assert gate.apply(command, broken) == (False, why)
    gate.flush()
    assert [r.reason for r in rows(tmp_path / "s.sqlite", "init")] == [why]
