"""The bus on a real zenoh: a CPU session and a view session over a unix socket."""

from __future__ import annotations

import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from s7graph.sequencer.text.model import Chart, Sequence, Step, Transition
from s7graph.web.bus.client import BusClient
from s7graph.web.bus.protocol import ChartLayout, Command, CommandReply, Refusal, StepStateUpdate
from s7graph.web.bus.publisher import BusPublisher
from s7graph.web.bus.session import open_session
from tests.web import helpers

pytestmark = pytest.mark.timeout(30)


def layout() -> ChartLayout:
    steps = (Step(1, "Idle", initial=True), Step(2, "Run"))
    transitions = (Transition(1, "", (1,), (2,)), Transition(2, "", (2,), (1,)))
    return ChartLayout.from_chart(Chart("FILL", sequences=(Sequence(1, "M", steps, transitions),)))


def scan(cycle: int, active: list[int], **kw: object) -> StepStateUpdate:
    return StepStateUpdate(cycle=cycle, t_ms=cycle * 10, mode="AUTO", active=active, **kw)


@pytest.fixture
def bus(tmp_path: Path) -> Iterator[tuple[BusPublisher, BusClient]]:
    endpoint = f"unixsock-stream/{tmp_path}/bus.sock"
    with open_session(listen=[endpoint]) as cpu, open_session(connect=[endpoint]) as view:
        publisher = BusPublisher(cpu, "cpu1", {"FILL": layout()})
        client = BusClient(view, "cpu1")
        try:
            assert wait_until(lambda: client.chart("FILL") is not None)
            yield publisher, client
        finally:
            _TOKENS.clear()
            client.close()
            publisher.close()


_TOKENS: dict[int, str] = {}


def cmd(client: BusClient, op: str, fb: str = "FILL", user: str = "bob", **args: object) -> Command:
    """A command from ``user``, logged in at the CPU (the demo: no password)."""
    if id(client) not in _TOKENS:
        reply = client.login(user)
        assert reply.ok, reply.reason
        _TOKENS[id(client)] = reply.token
    return Command(op=op, fb=fb, user=user, token=_TOKENS[id(client)], args=args)  # type: ignore[arg-type]


def wait_until(predicate, timeout: float = 5.0) -> bool:
    return helpers.wait_until(predicate, timeout, poll=0.02)


def send_in_background(
    client: BusClient, command: Command
) -> tuple[threading.Thread, list[CommandReply]]:
    replies: list[CommandReply] = []
    sender = threading.Thread(target=lambda: replies.append(client.send(command)))
    sender.start()
    return sender, replies


def test_chart_queryable_serves_the_layout(bus: tuple[BusPublisher, BusClient]) -> None:
    _, client = bus
    assert client.chart("FILL") == layout()
    assert client.chart("OTHER") is None


def test_late_joiner_gets_the_state_then_only_newer_deltas(
    bus: tuple[BusPublisher, BusClient],
) -> None:
    publisher, client = bus
    assert publisher.publish("FILL", scan(1, [1], events=[("S1", 1)]))
    assert not publisher.publish("FILL", scan(2, [1]))  # nothing changed: no delta
    state = client.state("FILL")
    assert state is not None and (state.seq, state.cycle) == (1, 2)

    seen: list[StepStateUpdate] = []
    follower = client.follow("FILL", seen.append)
    assert [u.cycle for u in seen] == [2]  # the snapshot
    publisher.publish("FILL", scan(3, [2], events=[("S0", 1), ("S1", 2)]))
    publisher.publish("FILL", scan(4, [2]))
    publisher.publish("FILL", scan(5, [1], events=[("S0", 2), ("S1", 1)]))
    assert wait_until(lambda: len(seen) == 3)
    assert [(u.seq, u.cycle, u.active) for u in seen] == [(1, 2, [1]), (2, 3, [2]), (3, 5, [1])]
    assert follower.latest == seen[-1] and follower.gaps == 0


def test_command_round_trip_is_applied_at_the_scan_boundary(
    bus: tuple[BusPublisher, BusClient],
) -> None:
    publisher, client = bus
    replies: list[CommandReply] = []
    sender = threading.Thread(
        target=lambda: replies.append(client.send(cmd(client, "step_on", step=2)))
    )
    sender.start()
    pending = []
    assert wait_until(lambda: pending.extend(publisher.drain_commands()) or pending)
    assert not replies  # nothing answered before the scan loop decides
    assert pending[0].command.step == 2 and pending[0].command.user == "bob"
    pending[0].resolve(True, cycle=7)
    sender.join(5)
    assert replies == [CommandReply(applied=True, op="step_on", fb="FILL", cycle=7)]


def test_command_refused_by_the_cpu_carries_its_reason_and_kind(
    bus: tuple[BusPublisher, BusClient],
) -> None:
    """The kind its site gave the refusal travels in the reply (a reason that gives none:
    "")."""
    publisher, client = bus
    replies: list[CommandReply] = []
    sender = threading.Thread(target=lambda: replies.append(client.send(cmd(client, "ack"))))
    sender.start()

    def apply(command: Command) -> tuple[bool, str]:
        return False, Refusal("state", "no error to acknowledge")

    assert wait_until(lambda: publisher.apply_commands(apply, cycle=3) > 0)
    sender.join(5)
    assert replies[0].applied is False and replies[0].reason == "no error to acknowledge"
    assert replies[0].kind == "state"


def test_deeply_nested_json_is_refused_in_words(bus: tuple[BusPublisher, BusClient]) -> None:
    """Any peer may send it: the refusal says what is wrong, never Python's
    ``RecursionError``."""
    _, client = bus
    nested = b'{"op": ' + b"[" * 5000 + b"]" * 5000 + b', "fb": "FILL"}'
    reply = client.send_raw(nested)
    assert reply is not None and not reply.applied
    assert reply.reason == (
        "invalid Command: nested too deeply (arrays or objects inside each other)"
    )


def test_a_command_that_breaks_its_route_is_refused_in_words(
    bus: tuple[BusPublisher, BusClient],
) -> None:
    """A defect of ours behind the last-resort guard of a routed command: an internal
    error, which command and FB, and what it said, in one line."""
    publisher, client = bus

    def broken(pending: object) -> None:
        raise KeyError("x")

    publisher.route(["ack"], broken)
    reply = client.send(cmd(client, "ack"))
    assert not reply.applied
    assert reply.reason == (
        "command refused: an internal error in the CPU while taking ack for FILL: 'x' "
        "(please report it)"
    )


def test_a_login_that_breaks_in_the_cpu_is_refused_in_words(
    bus: tuple[BusPublisher, BusClient], monkeypatch: pytest.MonkeyPatch
) -> None:
    """The asker is not logged in: it hears that the CPU failed, not how."""
    publisher, client = bus

    def broken(*args: object, **kwargs: object) -> None:
        raise KeyError("x")

    monkeypatch.setattr(publisher.gate, "login", broken)
    reply = client.login("bob")
    assert not reply.ok
    assert reply.reason == (
        "login failed: an internal error in the CPU while answering a login request "
        "(please report it)"
    )


def test_hostile_or_misdirected_command_is_refused_at_once(
    bus: tuple[BusPublisher, BusClient],
) -> None:
    publisher, client = bus
    bad = client.send_raw(b'{"op":"mode","fb":"FILL","args":{"mode":"TURBO"}}')
    assert bad is not None and not bad.applied and "$.args.mode" in bad.reason
    junk = client.send_raw(b"\x00not json")
    assert junk is not None and not junk.applied and "malformed JSON" in junk.reason
    other = client.send(cmd(client, "ack", fb="NOPE"))
    assert not other.applied and "unknown FB 'NOPE'" in other.reason
    assert (bad.kind, junk.kind, other.kind) == ("argument", "argument", "not_found")
    assert publisher.drain_commands() == []  # none of them reached the scan loop


def test_a_command_nobody_drains_ends_in_a_refusal_not_a_hang(
    bus: tuple[BusPublisher, BusClient],
) -> None:
    _, client = bus
    reply = client.send(cmd(client, "init"), timeout=0.3)
    assert not reply.applied and reply.reason == "no answer from CPU 'cpu1' within 0.3 s"
    assert reply.kind == "communication"  # said by the client


def test_no_answer_from_no_cpu_at_all_says_so_at_once(tmp_path: Path) -> None:
    """Nothing on the bus serves the CPU's keys: the request ends before its wait, and
    the reason says the CPU is not reachable rather than that it kept silent 30 s."""
    with open_session(listen=[f"unixsock-stream/{tmp_path}/bus.sock"]) as alone:
        nobody = BusClient(alone, "cpu9")
        try:
            asked = time.monotonic()
            reply = nobody.send(Command(op="init", fb="FILL", user="bob"), timeout=30)
            assert time.monotonic() - asked < 10  # not the 30 s asked for
            assert not reply.applied
            assert reply.reason.startswith("no answer from CPU 'cpu9': the bus ended the request")
            watched = nobody.watch(["M0.0"], timeout=30)
            assert watched.error.startswith("no answer from CPU 'cpu9': the bus ended")
        finally:
            nobody.close()


def test_an_exception_while_applying_refuses_that_command_only(
    bus: tuple[BusPublisher, BusClient],
) -> None:
    publisher, client = bus
    replies: list[CommandReply] = []
    sender = threading.Thread(target=lambda: replies.append(client.send(cmd(client, "off"))))
    sender.start()

    def apply(command: Command) -> tuple[bool, str]:
        raise RuntimeError("boom")

    assert wait_until(lambda: publisher.apply_commands(apply) > 0)
    sender.join(5)
    assert not replies[0].applied and replies[0].reason == (
        "command refused: an internal error in the CPU while applying off to FILL: boom "
        "(please report it)"
    )
    assert replies[0].kind == ""  # none said: a reader goes by the words


def test_status_reports_the_cpu_and_its_fbs(bus: tuple[BusPublisher, BusClient]) -> None:
    publisher, client = bus
    publisher.publish("FILL", scan(9, [1]))
    status = client.status()
    assert status is not None and status.cpu == "cpu1" and status.fbs == ["FILL"]
    assert status.cycle == 9
