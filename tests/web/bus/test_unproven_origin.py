"""A login or a command whose link the CPU cannot name (web/bus/origin.py
``query_origin``): a query without zenoh ``source_info`` on a CPU with several links is
refused, and audited, with a reason that says what the client must do — over the only link
it is that link's, as before; a session the query names that is not linked to the CPU is
refused the same way. Real zenoh sessions on TCP on loopback (docs/security.md, "Who may
join the bus")."""

from __future__ import annotations

import threading
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import pytest
import zenoh

from s7graph.sequencer.text.model import Chart, Sequence, Step, Transition
from s7graph.web.access.audit import UNAUTHENTICATED, AuditStore, read_audit
from s7graph.web.access.login import Authenticator
from s7graph.web.access.scram import MIN_ITERATIONS
from s7graph.web.access.users import UsersFile
from s7graph.web.bus.client import BusClient
from s7graph.web.bus.gate import Gate
from s7graph.web.bus.origin import UNKNOWN, query_origin
from s7graph.web.bus.protocol import ChartLayout, Command, StepStateUpdate
from s7graph.web.bus.publisher import BusPublisher
from s7graph.web.bus.session import open_session
from tests.web.helpers import free_port, wait_until

pytestmark = pytest.mark.timeout(60)
PASSWORD = "correct horse"
NAMES_NONE = (
    "origin unproven: this CPU has 2 links and the request names no session of its own: "
    "send it with zenoh source_info naming your session (zenoh.SourceInfo(session.id, n)), "
    "as s7graph's own clients do"
)


class Unstamped(BusClient):
    """A client that sends its queries without ``source_info`` (not s7graph's own)."""

    def _get_one(
        self, key: str, payload: bytes | None = None, timeout: float | None = None
    ) -> bytes | None:
        for reply in self._session.get(key, payload=payload, timeout=timeout or 5):
            if reply.ok is not None:
                return reply.ok.payload.to_bytes()
        return None


@dataclass
class Cpu:
    session: zenoh.Session
    endpoint: str
    state: Path
    applied: list[Command] = field(default_factory=list)


def _layout() -> ChartLayout:
    steps = (Step(1, "Idle", initial=True), Step(2, "Run"))
    transitions = (Transition(1, "", (1,), (2,)), Transition(2, "", (2,), (1,)))
    return ChartLayout.from_chart(Chart("FILL", sequences=(Sequence(1, "M", steps, transitions),)))


@contextmanager
def running_cpu(tmp_path: Path) -> Iterator[Cpu]:
    """A CPU with a users file (olga, an operator) listening on TCP on loopback, its
    commands applied by a scan thread."""
    users = UsersFile(tmp_path / "users.json")
    users.add("olga", "operator", PASSWORD, iterations=MIN_ITERATIONS)
    store = AuditStore(tmp_path / "state.sqlite")
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    stop = threading.Event()
    with open_session(listen=[endpoint]) as session:
        publisher = BusPublisher(
            session, "cpu1", {"FILL": _layout()}, gate=Gate(Authenticator(users), store)
        )
        cpu = Cpu(session, endpoint, tmp_path / "state.sqlite")

        def scan() -> None:
            def apply(command: Command) -> tuple[bool, str]:
                cpu.applied.append(command)
                return True, ""

            cycle = 0
            while not stop.is_set():
                cycle += 1
                update = StepStateUpdate(cycle=cycle, t_ms=cycle, mode="AUTO", active=[1])
                publisher.publish("FILL", update)
                publisher.apply_commands(apply, cycle=cycle)
                stop.wait(0.01)

        scanner = threading.Thread(target=scan, daemon=True)
        scanner.start()
        try:
            yield cpu
        finally:
            stop.set()
            scanner.join(5)
            publisher.close()
            store.close()


def _init(user: str, token: str) -> Command:
    return Command(op="init", fb="FILL", user=user, token=token, origin="shell x")


def test_a_login_or_command_without_source_info_among_several_links_is_refused_saying_what_to_do(
    tmp_path: Path,
) -> None:
    with running_cpu(tmp_path) as cpu, open_session(connect=[cpu.endpoint]) as first:
        alone = Unstamped(first, "cpu1")
        assert wait_until(lambda: alone.status() is not None)
        over_the_only_link = alone.login("olga", PASSWORD)
        assert over_the_only_link.ok, over_the_only_link.reason  # that link's: as before
        with open_session(connect=[cpu.endpoint]) as second:
            assert wait_until(lambda: len(list(cpu.session.info.links())) == 2)
            refused = Unstamped(second, "cpu1").login("olga", PASSWORD)
            assert (refused.ok, refused.reason) == (False, NAMES_NONE)
            stamped = BusClient(second, "cpu1")  # s7graph's own client names its session
            login = stamped.login("olga", PASSWORD, origin="shell x")
            assert login.ok, login.reason
            assert stamped.send(_init("olga", login.token)).applied
            signer = stamped._signer(login.token)
            assert signer is not None
            unstamped_command = alone.send(signer.sign(_init("olga", login.token)))
            assert (unstamped_command.applied, unstamped_command.reason) == (False, NAMES_NONE)
    assert len(cpu.applied) == 1
    rows = [r for r in read_audit(cpu.state) if r.reason == NAMES_NONE]
    assert [(r.user, r.claimed, r.op, r.origin) for r in rows] == [
        (UNAUTHENTICATED, "olga", "login", UNKNOWN),  # the login: no author proven
        ("olga", "", "init", UNKNOWN),  # the command: its session proves olga
    ]


def test_a_query_naming_a_session_not_linked_to_the_cpu_is_unproven_and_says_so(
    tmp_path: Path,
) -> None:
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    with (
        open_session(listen=[endpoint]) as cpu,
        open_session(connect=[endpoint]),
        open_session(connect=[endpoint]),
        open_session() as elsewhere,  # linked to nobody
    ):
        assert wait_until(lambda: len(list(cpu.info.links())) == 2)
        named = zenoh.SourceInfo(elsewhere.id, 1)
        assert query_origin(cpu, named) == (
            UNKNOWN,
            "origin unproven: the session the request names is not linked to this CPU, and "
            "the CPU cannot tell which of its 2 links relayed it (0 to routers): connect to "
            "the CPU directly, or through a router",
        )
        assert query_origin(cpu, None) == (UNKNOWN, NAMES_NONE)
