"""Logins and signed commands over a real zenoh bus (unix socket on loopback), watched by a
passive listener: a second peer with its own queryables on ``login`` and ``cmd`` and a
subscriber on everything, which sees every request, plus every reply the client got. It
never sees the password, nor anything it can log in with or command with: a replayed
login, a replayed or changed command, a token without its session key are refused and
audited. A fake CPU is found out by the client; wrong passwords lock their source out,
not the operator."""

from __future__ import annotations

import base64
import json
import threading
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import msgspec
import pytest
import zenoh

from s7graph.sequencer.text.model import Chart, Sequence, Step, Transition
from s7graph.web.access.audit import AuditStore, read_audit
from s7graph.web.access.login import NOT_SIGNED, Authenticator
from s7graph.web.access.scram import MIN_ITERATIONS, Verifier
from s7graph.web.access.users import UsersFile
from s7graph.web.bus.client import BusClient
from s7graph.web.bus.gate import Gate
from s7graph.web.bus.origin import stamp
from s7graph.web.bus.protocol import (
    ChartLayout,
    Command,
    CommandReply,
    LoginReply,
    LoginRequest,
    StepStateUpdate,
    decode,
    encode,
)
from s7graph.web.bus.publisher import BusPublisher
from s7graph.web.bus.session import open_session
from tests.web.helpers import wait_until

pytestmark = pytest.mark.timeout(60)
PASSWORD = "correct horse"
LOGIN, CMD = "s7graph/cpu1/login", "s7graph/cpu1/cmd"


def layout() -> ChartLayout:
    steps = (Step(1, "Idle", initial=True), Step(2, "Run"))
    transitions = (Transition(1, "", (1,), (2,)), Transition(2, "", (2,), (1,)))
    return ChartLayout.from_chart(Chart("FILL", sequences=(Sequence(1, "M", steps, transitions),)))


class RecordingClient(BusClient):
    """A bus client that keeps what it sent and what came back: what a listener on the
    link sees of its exchanges."""

    wire: list[bytes]

    def _get_one(
        self, key: str, payload: bytes | None = None, timeout: float | None = None
    ) -> bytes | None:
        answer = super()._get_one(key, payload, timeout)
        self.wire.extend(x for x in (payload, answer) if x is not None)
        return answer


@dataclass
class Rig:
    client: RecordingClient
    attacker: BusClient
    spy: zenoh.Session
    state: Path
    applied: list[Command]
    gate: Gate
    heard: list[bytes] = field(default_factory=list)  # what the listener's peer received

    def seen(self) -> list[bytes]:
        """Everything on the wire: the listener's catch and the client's replies."""
        return [*self.heard, *self.client.wire]


def _scan_loop(publisher: BusPublisher, applied: list[Command], stop: threading.Event) -> None:
    def apply(command: Command) -> tuple[bool, str]:
        applied.append(command)
        return True, ""

    cycle = 0
    while not stop.is_set():
        cycle += 1
        publisher.publish("FILL", StepStateUpdate(cycle=cycle, t_ms=cycle, mode="AUTO", active=[1]))
        publisher.apply_commands(apply, cycle=cycle)
        stop.wait(0.01)


@pytest.fixture
def rig(tmp_path: Path) -> Iterator[Rig]:
    users = UsersFile(tmp_path / "users.json")
    users.add("olga", "operator", PASSWORD, iterations=MIN_ITERATIONS)
    state = tmp_path / "state.sqlite"
    store = AuditStore(state)
    gate = Gate(Authenticator(users), store)
    endpoint = f"unixsock-stream/{tmp_path}/bus.sock"
    applied: list[Command] = []
    stop = threading.Event()
    with (
        open_session(listen=[endpoint]) as cpu,
        open_session(connect=[endpoint]) as view,
        open_session(connect=[endpoint]) as spy,
    ):
        publisher = BusPublisher(cpu, "cpu1", {"FILL": layout()}, gate=gate)
        client = RecordingClient(view, "cpu1")
        client.wire = []
        attacker = BusClient(spy, "cpu1")
        rig = Rig(client, attacker, spy, state, applied, gate)

        def hear(query: zenoh.Query) -> None:
            if query.payload is not None:
                rig.heard.append(query.payload.to_bytes())

        listeners = [
            spy.declare_queryable(LOGIN, hear),
            spy.declare_queryable(CMD, hear),
            spy.declare_subscriber("s7graph/**", lambda s: rig.heard.append(s.payload.to_bytes())),
        ]
        scanner = threading.Thread(target=_scan_loop, args=(publisher, applied, stop))
        scanner.start()
        try:
            assert wait_until(lambda: client.status() is not None)
            yield rig
        finally:
            stop.set()
            scanner.join(5)
            for listener in listeners:
                listener.undeclare()  # type: ignore[no-untyped-call]
            client.close()
            publisher.close()
            store.close()


def _log_in(rig: Rig) -> LoginReply:
    login = rig.client.login("olga", PASSWORD, origin="page 1 (10.0.0.7)")
    assert login.ok and login.verified, login.reason
    return login


def _command(login: LoginReply, op: str = "mode", **args: object) -> Command:
    fields: dict[str, Any] = {"op": op, "args": args}
    return Command(fb="FILL", user="olga", token=login.token, origin="page 1", **fields)


def _ask_login(session: zenoh.Session, payload: bytes) -> LoginReply:
    """``payload`` on ``login`` from ``session``, naming it as every client must (``stamp``)."""
    for reply in session.get(LOGIN, payload=payload, timeout=5, source_info=stamp(session)):
        if reply.ok is not None:
            return decode(reply.ok.payload.to_bytes(), LoginReply)
    raise AssertionError("the CPU did not answer")


def _heard(rig: Rig, kind: type[Any], **match: object) -> list[Any]:
    """What the listener caught that decodes as ``kind`` with the given fields."""
    found = []
    for raw in rig.heard:
        try:
            message = decode(raw, kind)
        except Exception:
            continue
        if all(getattr(message, k, None) == v for k, v in match.items()):
            found.append(message)
    return found


def _refused(rig: Rig, reason: str) -> list[str]:
    return [
        r.reason for r in read_audit(rig.state) if r.outcome == "refused" and reason in r.reason
    ]


def test_a_listener_on_the_login_and_cmd_keys_never_sees_the_password_or_a_way_in(
    rig: Rig,
) -> None:
    login = _log_in(rig)
    assert rig.client.send(_command(login, mode="MAN")).applied
    assert wait_until(lambda: len(_heard(rig, LoginRequest)) >= 2 and _heard(rig, Command))
    wire = b"\n".join(rig.seen())
    assert b'"op":"proof"' in wire and b'"mac":"' in wire  # the listener heard it all
    # no password, and nothing the CPU keeps that would stand in for it
    users = json.loads((rig.state.parent / "users.json").read_text())["users"]
    verifier = Verifier.parse(users["olga"]["password"])
    key = rig.client._signers[login.token]._key
    for secret in (
        PASSWORD.encode(),
        base64.b64encode(verifier.stored_key),
        base64.b64encode(verifier.server_key),
        key,
        key.hex().encode(),
        base64.b64encode(key),
    ):
        assert secret not in wire
    # what was heard does not log in: the login replayed gets a new challenge, the proof
    # answers the old one
    first, proof = (
        _heard(rig, LoginRequest, op="login")[0],
        _heard(rig, LoginRequest, op="proof")[0],
    )
    challenge = _ask_login(rig.spy, encode(first))
    assert not challenge.ok and challenge.login_id and challenge.login_id != proof.login_id
    for login_id in (proof.login_id, challenge.login_id):
        replayed = _ask_login(rig.spy, encode(msgspec.structs.replace(proof, login_id=login_id)))
        assert not replayed.ok and not replayed.token, replayed
    # nor does it command: the heard token, unsigned or replayed, is refused
    token_only = rig.attacker.send(_command(login, mode="AUTO"))
    assert not token_only.applied and token_only.reason == NOT_SIGNED
    assert [(c.op, c.args.get("mode")) for c in rig.applied] == [("mode", "MAN")]


def test_a_captured_command_replayed_is_refused_and_audited(rig: Rig) -> None:
    login = _log_in(rig)
    assert rig.client.send(_command(login, "init")).applied
    assert wait_until(lambda: _heard(rig, Command))
    captured = next(raw for raw in rig.heard if b'"op":"init"' in raw)
    replayed = rig.attacker.send_raw(captured, timeout=5)
    assert replayed is not None and not replayed.applied
    assert replayed.reason == "replayed or out of order: seq 1"
    assert len(rig.applied) == 1
    assert wait_until(lambda: _refused(rig, "replayed or out of order: seq 1"))
    assert rig.client.send(_command(login, "init")).applied  # seq 2: the session goes on


def test_a_command_with_a_tampered_argument_is_refused_and_audited(rig: Rig) -> None:
    login = _log_in(rig)
    assert rig.client.send(_command(login, mode="MAN")).applied
    assert wait_until(lambda: _heard(rig, Command))
    captured = next(raw for raw in rig.heard if b'"op":"mode"' in raw)
    # changed before the CPU saw it: a new seq, another mode, the same mac
    tampered = captured.replace(b'"MAN"', b'"AUTO"').replace(b'"seq":1', b'"seq":2')
    reply = rig.attacker.send_raw(tampered, timeout=5)
    assert reply is not None and not reply.applied and reply.reason == NOT_SIGNED
    assert [c.args.get("mode") for c in rig.applied] == ["MAN"]
    assert wait_until(lambda: _refused(rig, "not signed by the session"))


def test_a_token_used_without_the_session_key_is_refused(rig: Rig) -> None:
    login = _log_in(rig)
    unsigned = rig.attacker.send(_command(login, "init"))
    assert not unsigned.applied and unsigned.reason == NOT_SIGNED
    numbered = msgspec.structs.replace(_command(login, "init"), seq=9, mac="0" * 64)
    forged = rig.attacker.send(numbered)
    assert not forged.applied and forged.reason == NOT_SIGNED
    logout = rig.attacker.logout(login.token, user="olga")  # unsigned: the session stays
    assert not logout.ok and logout.reason == NOT_SIGNED
    assert rig.applied == []
    assert rig.client.send(_command(login, "init")).applied
    assert rig.client.logout(login.token, user="olga").ok  # signed: it ends
    assert rig.client.send(_command(login, "init")).reason == "invalid token: log in again"


def test_the_client_detects_a_wrong_server_signature_of_a_fake_cpu(rig: Rig) -> None:
    """A peer answering for ``fake1`` without the users file: it takes the proof (which
    does not give it the password) and says yes, but cannot sign the answer."""
    told: list[str] = []

    def fake(query: zenoh.Query) -> None:
        assert query.payload is not None
        request = decode(query.payload.to_bytes(), LoginRequest)
        told.append(request.op)
        if request.op == "login":
            nonce = request.scram.split("r=", 1)[1]
            first = f"r={nonce}fake,s={base64.b64encode(b'x' * 16).decode()},i=4096"
            reply = LoginReply(ok=False, login_id="fake", scram=first)
        else:
            signature = base64.b64encode(b"\x00" * 32).decode()
            reply = LoginReply(
                ok=True, user="olga", role="engineer", token="t", scram=f"v={signature}"
            )
        query.reply(query.key_expr, encode(reply))

    queryable = rig.spy.declare_queryable("s7graph/fake1/login", fake)
    try:
        client = BusClient(rig.client._session, "fake1")
        assert wait_until(lambda: client.login("olga", PASSWORD) is not None and bool(told))
        told.clear()  # the fake's queryable has reached the client's side of the bus
        answer = client.login("olga", PASSWORD)
        assert told == ["login", "proof"]
        assert not answer.ok and not answer.token
        assert "did not prove it knows the password" in answer.reason
        assert client._signers == {}  # its token is not used
    finally:
        queryable.undeclare()  # type: ignore[no-untyped-call]


def test_lockout_per_source_leaves_the_operators_own_client_able_to_log_in(rig: Rig) -> None:
    for _ in range(5):
        rogue = rig.attacker.login("olga", "guessing", origin="peer rogue")
    assert not rogue.ok and "locked out for 60 s" in rogue.reason
    again = rig.attacker.login("olga", PASSWORD, origin="peer rogue")
    assert not again.ok and "locked out" in again.reason
    _log_in(rig)  # the real operator, from her page
    rig.gate.flush()  # failed logins are counted per minute, source and reason
    logins = [r for r in read_audit(rig.state) if r.op == "login"]
    refused = [r for r in logins if r.outcome == "refused"]
    assert sum(r.count for r in refused) == 6 and logins[-1].outcome == "applied"
    assert all(r.origin.startswith("unixsock-stream/") for r in refused)  # the transport's
    assert {r.detail for r in refused} == {"claimed origin: peer rogue"}


def test_commands_sent_at_once_from_one_session_are_all_applied(rig: Rig) -> None:
    login = _log_in(rig)
    replies: list[CommandReply] = []

    def click() -> None:
        replies.append(rig.client.send(_command(login, "init")))

    threads = [threading.Thread(target=click) for _ in range(12)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(30)
    assert len(replies) == 12 and all(r.applied for r in replies), [r.reason for r in replies]
    assert len(rig.applied) == 12
