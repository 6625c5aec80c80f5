"""Logins, roles and the audit over a real zenoh bus (two sessions, a unix socket or TLS on
loopback): the CPU side checks every command at the scan boundary and audits it."""

from __future__ import annotations

import re
import threading
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import pytest
import zenoh

from s7graph.sequencer.text.model import Chart, Sequence, Step, Transition
from s7graph.web.access.audit import AuditStore, read_audit
from s7graph.web.access.login import Authenticator
from s7graph.web.access.users import UsersFile
from s7graph.web.bus.client import BusClient, find_cpus
from s7graph.web.bus.gate import Gate
from s7graph.web.bus.protocol import ChartLayout, Command, CommandReply, StepStateUpdate
from s7graph.web.bus.publisher import BusPublisher
from s7graph.web.bus.session import open_session
from tests.web.helpers import free_port, wait_until

if TYPE_CHECKING:
    from tests.conftest import BusCerts

pytestmark = pytest.mark.timeout(60)
PASSWORD = "correct horse"


def layout() -> ChartLayout:
    steps = (Step(1, "Idle", initial=True), Step(2, "Run"))
    transitions = (Transition(1, "", (1,), (2,)), Transition(2, "", (2,), (1,)))
    return ChartLayout.from_chart(Chart("FILL", sequences=(Sequence(1, "M", steps, transitions),)))


@dataclass
class Rig:
    publisher: BusPublisher
    client: BusClient
    state: Path
    applied: list[Command]
    cpu: zenoh.Session


def _scan_loop(publisher: BusPublisher, applied: list[Command], stop: threading.Event) -> None:
    def apply(command: Command) -> tuple[bool, str, str]:
        applied.append(command)
        return True, "", "FB FILL"

    cycle = 0
    while not stop.is_set():
        cycle += 1
        publisher.publish("FILL", StepStateUpdate(cycle=cycle, t_ms=cycle, mode="AUTO", active=[1]))
        publisher.apply_commands(apply, cycle=cycle)
        stop.wait(0.01)


@pytest.fixture
def rig(tmp_path: Path) -> Iterator[Rig]:
    users = UsersFile(tmp_path / "users.json")
    users.add("olga", "operator", PASSWORD)
    users.add("vic", "viewer", PASSWORD)
    state = tmp_path / "state.sqlite"
    store = AuditStore(state)
    gate = Gate(Authenticator(users), store)
    endpoint = f"unixsock-stream/{tmp_path}/bus.sock"
    applied: list[Command] = []
    stop = threading.Event()
    with open_session(listen=[endpoint]) as cpu, open_session(connect=[endpoint]) as view:
        publisher = BusPublisher(cpu, "cpu1", {"FILL": layout()}, gate=gate)
        client = BusClient(view, "cpu1")
        scanner = threading.Thread(target=_scan_loop, args=(publisher, applied, stop))
        scanner.start()
        try:
            assert wait_until(lambda: client.status() is not None)
            yield Rig(publisher, client, state, applied, cpu)
        finally:
            stop.set()
            scanner.join(5)
            client.close()
            publisher.close()
            store.close()


def command(rig: Rig, user: str, op: str = "init", **args: object) -> CommandReply:
    login = rig.client.login(user, PASSWORD, origin="shell test")
    assert login.ok, login.reason
    return rig.client.send(
        Command(op=op, fb="FILL", user=user, token=login.token, origin="shell test", args=args)  # type: ignore[arg-type]
    )


def test_a_viewer_is_refused_and_an_operator_applied_each_audited_under_its_name(
    rig: Rig,
) -> None:
    status = rig.client.status()
    assert status is not None and status.login == "users"
    refused = command(rig, "vic", "mode", mode="MAN")
    assert not refused.applied and refused.reason == "role viewer may not mode (needs operator)"
    assert refused.kind == "access"
    applied = command(rig, "olga", "mode", mode="MAN")
    assert applied.applied, applied.reason
    assert [(c.op, c.user, c.token) for c in rig.applied] == [("mode", "olga", "")]  # no token
    rows = [r for r in read_audit(rig.state) if r.op == "mode"]
    (link,) = rig.cpu.info.links()  # the origin is the transport's: the view's link
    assert [(r.user, r.role, r.origin, r.outcome) for r in rows] == [
        ("vic", "viewer", str(link.dst), "refused"),
        ("olga", "operator", str(link.dst), "applied"),
    ]
    assert rows[0].detail == "claimed origin: shell test"  # the claim: a note only
    assert re.fullmatch(r"cycle \d+: FB FILL; claimed origin: shell test", rows[1].detail)
    assert rows[0].reason.startswith("role viewer") and '"MAN"' in rows[1].args
    listed = rig.client.audit()
    assert listed is not None and [e.user for e in listed.entries if e.op == "mode"] == [
        "vic",
        "olga",
    ]
    engineer_only = command(rig, "olga", "en_il", on=False)
    assert engineer_only.reason == "role operator may not en_il (needs engineer)"


def test_a_wrong_password_is_refused_and_five_lock_the_user_out(rig: Rig) -> None:
    for _ in range(4):
        reply = rig.client.login("olga", "not it at all")
        assert (reply.ok, reply.reason, reply.token) == (False, "wrong user name or password", "")
    fifth = rig.client.login("olga", "not it at all")
    assert not fifth.ok and "locked out" in fifth.reason
    locked = rig.client.login("olga", PASSWORD)
    assert not locked.ok and "locked out" in locked.reason
    rig.publisher.gate.flush()  # failed logins are counted per minute and reason
    logins = [r for r in read_audit(rig.state) if r.op == "login"]
    assert sum(r.count for r in logins) == 6 and {r.outcome for r in logins} == {"refused"}
    text = rig.state.read_bytes()
    assert b"not it at all" not in text and PASSWORD.encode() not in text


@pytest.mark.parametrize(
    "payload",
    [
        b'{"op":"init","fb":"FILL","user":"bob\\r\\nroot","token":"x"}',
        b'{"op":"init","fb":"FILL","user":"\\u001b[31mred","token":"x"}',
        b'{"op":"init","fb":"FILL","user":"olga","token":"../../etc/passwd"}',
        b'{"op":"init","fb":"FILL","user":"olga","token":"' + b"A" * 65 + b'"}',
        b'{"op":"init","fb":"FILL","user":"olga","origin":"page\\u0000"}',
        b'{"op":"init","fb":"FILL","user":"program"}',
        b'{"op":"init","fb":"FILL","user":"olga","token":"forgedforgedforged"}',
        b"not json",
    ],
)
def test_hostile_names_and_tokens_are_refused_and_never_reach_the_scan(
    rig: Rig, payload: bytes
) -> None:
    reply = rig.client.send_raw(payload, timeout=5)
    assert reply is not None and not reply.applied and reply.reason
    assert rig.applied == []
    assert wait_until(lambda: any(r.outcome == "refused" for r in read_audit(rig.state)))


def test_wildcard_queries_are_answered_or_ignored_cleanly(rig: Rig) -> None:
    session = rig.client._session
    everything = session.get(
        "s7graph/**",
        payload=b'{"op":"init","fb":"FILL"}',
        timeout=2,
        target=zenoh.QueryTarget.ALL,
        consolidation=zenoh.ConsolidationMode.NONE,
    )
    replies = list(everything)
    keys = sorted(str(r.ok.key_expr) for r in replies if r.ok is not None)
    assert "s7graph/cpu1/status" in keys and "s7graph/cpu1/fb/FILL/chart" in keys
    assert "s7graph/cpu1/cmd" not in keys and "s7graph/cpu1/login" not in keys
    assert all("*" not in k for k in keys)
    assert rig.applied == []
    assert [s.cpu for s in find_cpus(session)] == ["cpu1"]
    assert rig.client.chart("FILL") == layout()  # still serving


# ---------------------------------------------------------------- TLS on loopback


def test_tls_on_loopback_carries_login_and_commands_and_refuses_a_stranger(
    tmp_path: Path, bus_certs: BusCerts
) -> None:
    endpoint = f"tls/localhost:{free_port()}"
    users = UsersFile(tmp_path / "users.json")
    users.add("olga", "operator", PASSWORD)
    gate = Gate(Authenticator(users))
    with open_session(listen=[endpoint], tls=bus_certs.tls("cpu.cpu1")) as cpu:
        publisher = BusPublisher(cpu, "cpu1", {"FILL": layout()}, gate=gate)
        try:
            with open_session(connect=[endpoint], tls=bus_certs.tls("client.olga")) as view:
                client = BusClient(view, "cpu1")
                assert wait_until(lambda: client.chart("FILL") is not None)
                login = client.login("olga", PASSWORD)
                assert login.ok and login.role == "operator"
                replies: list[CommandReply] = []
                cmd = Command(op="init", fb="FILL", user="olga", token=login.token)
                sender = threading.Thread(target=lambda: replies.append(client.send(cmd)))
                sender.start()
                assert wait_until(lambda: publisher.apply_commands(lambda c: (True, "")) > 0)
                sender.join(5)
                assert replies and replies[0].applied
                client.close()
            # a node without the CA cannot even connect, nor one without a certificate
            with pytest.raises(zenoh.ZError):
                open_session(connect=[endpoint], mode="client").close()
            with pytest.raises(zenoh.ZError):
                open_session(connect=[endpoint], tls=bus_certs.tls()).close()
        finally:
            publisher.close()
