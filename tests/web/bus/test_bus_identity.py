"""Who may join the bus and who may serve a CPU's keys, with real zenoh sessions on
loopback: mutual TLS with the plant's certificates (``bus_certs``), zenoh's user/password
authentication, the access control of ``web.bus.acl`` refusing a rogue peer's queryables
and publications, and the audit's origin taken from the transport (``web.bus.origin``)."""

from __future__ import annotations

import re
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import pytest
import zenoh

from s7graph.sequencer.text.model import Chart, Sequence, Step, Transition
from s7graph.web.access.audit import AuditStore, read_audit
from s7graph.web.access.login import Authenticator
from s7graph.web.access.users import UsersFile
from s7graph.web.bus.acl import grants_markdown
from s7graph.web.bus.client import BusClient
from s7graph.web.bus.cpu_side import CpuSide
from s7graph.web.bus.gate import Gate
from s7graph.web.bus.protocol import ChartLayout, Command, CommandReply, StepStateUpdate
from s7graph.web.bus.session import BusEnds, BusLogin, TlsFiles, open_session
from tests.web.helpers import free_port, wait_until

if TYPE_CHECKING:
    from tests.conftest import BusCerts

pytestmark = pytest.mark.timeout(90)
ROOT = Path(__file__).resolve().parents[3]
PASSWORD = "correct horse"


def _layout() -> ChartLayout:
    steps = (Step(1, "Idle", initial=True), Step(2, "Run"))
    transitions = (Transition(1, "", (1,), (2,)), Transition(2, "", (2,), (1,)))
    return ChartLayout.from_chart(Chart("FILL", sequences=(Sequence(1, "M", steps, transitions),)))


@dataclass
class Cpu:
    """A CPU with a users file on a real bus, its commands applied by a scan thread."""

    side: CpuSide
    state: Path
    endpoint: str
    applied: list[Command] = field(default_factory=list)


@contextmanager
def running_cpu(tmp_path: Path, ends: BusEnds, cpu: str = "cpu1") -> Iterator[Cpu]:
    users = UsersFile(tmp_path / "users.json")
    users.add("olga", "operator", PASSWORD)
    state = tmp_path / "state.sqlite"
    store = AuditStore(state)
    side = CpuSide({"FILL": _layout()}, cpu=cpu, ends=ends, gate=Gate(Authenticator(users), store))
    rig = Cpu(side, state, side.endpoint)
    stop = threading.Event()

    def scan() -> None:
        def apply(command: Command) -> tuple[bool, str]:
            rig.applied.append(command)
            return True, ""

        cycle = 0
        while not stop.is_set():
            cycle += 1
            update = StepStateUpdate(cycle=cycle, t_ms=cycle, mode="AUTO", active=[1])
            side.publisher.publish("FILL", update)
            side.publisher.apply_commands(apply, cycle=cycle)
            stop.wait(0.01)

    scanner = threading.Thread(target=scan, daemon=True)
    scanner.start()
    try:
        yield rig
    finally:
        stop.set()
        scanner.join(5)
        side.close()
        store.close()


def _log_in_and_command(client: BusClient) -> CommandReply:
    login = client.login("olga", PASSWORD, origin="shell olga@somewhere pid 1")
    assert login.ok, login.reason
    command = Command(
        op="init", fb="FILL", user="olga", token=login.token, origin="shell olga@somewhere pid 1"
    )
    return client.send(command)


def test_a_rogue_with_a_valid_certificate_never_sees_a_login_nor_answers_a_command(
    tmp_path: Path, bus_certs: BusCerts
) -> None:
    endpoint = f"tls/localhost:{free_port()}"
    ends = BusEnds(listen=[endpoint], tls=bus_certs.tls("cpu.cpu1"))
    heard: list[str] = []

    def rogue_answer(query: zenoh.Query) -> None:
        heard.append(str(query.key_expr))  # the password would be in query.payload
        query.reply(query.key_expr, b'{"ok": true, "token": "rogue"}')

    with (
        running_cpu(tmp_path, ends) as cpu,
        open_session(connect=[endpoint], tls=bus_certs.tls("client.rogue")) as rogue,
    ):
        for key in ("s7graph/cpu1/login", "s7graph/cpu1/cmd", "s7graph/**"):
            rogue.declare_queryable(key, rogue_answer)
        rogue.liveliness().declare_token("s7graph/cpu1/alive")
        time.sleep(0.5)  # the declarations have reached the CPU (and been refused there)
        with open_session(connect=[endpoint], tls=bus_certs.tls("client.olga")) as olga:
            client = BusClient(olga, "cpu1")
            statuses: list[bytes] = []
            olga.declare_subscriber(
                "s7graph/cpu1/status", lambda s: statuses.append(s.payload.to_bytes())
            )
            assert wait_until(lambda: client.chart("FILL") is not None)
            rogue.put("s7graph/cpu1/status", b'{"cpu": "cpu1", "state": "STOP"}')
            reply = _log_in_and_command(client)
            assert reply.applied, reply.reason
            assert [c.op for c in cpu.applied] == ["init"]
            time.sleep(0.5)
            assert b'{"cpu": "cpu1", "state": "STOP"}' not in statuses
            client.close()
        assert heard == []  # zenoh refused the rogue's queryables: it never saw a query


def test_without_the_access_control_the_rogue_would_hear_the_password(
    bus_certs: BusCerts,
) -> None:
    """The control of the test above: the same sessions, no ``guard`` on the listener."""
    endpoint = f"tls/localhost:{free_port()}"
    heard: list[bytes] = []

    def rogue_answer(query: zenoh.Query) -> None:
        heard.append(query.payload.to_bytes() if query.payload else b"")
        query.reply(query.key_expr, b"rogue")

    with (
        open_session(listen=[endpoint], tls=bus_certs.tls("cpu.cpu1")),
        open_session(connect=[endpoint], tls=bus_certs.tls("client.rogue")) as rogue,
        open_session(connect=[endpoint], tls=bus_certs.tls("client.olga")) as olga,
    ):
        rogue.declare_queryable("s7graph/cpu1/login", rogue_answer)
        assert wait_until(lambda: bool(list(olga.get("s7graph/cpu1/login", payload=b"pw"))))
    assert heard and heard[0] == b"pw"


def test_a_peer_without_a_certificate_cannot_join_a_cpu_with_one(
    tmp_path: Path, bus_certs: BusCerts
) -> None:
    endpoint = f"tls/localhost:{free_port()}"
    with running_cpu(tmp_path, BusEnds(listen=[endpoint], tls=bus_certs.tls("cpu.cpu1"))):
        with pytest.raises(zenoh.ZError):
            open_session(connect=[endpoint], tls=bus_certs.tls()).close()
        stranger = tmp_path / "stranger"  # a certificate from another CA is no better
        from s7graph.web.access.certs import init_ca, issue

        init_ca(stranger)
        made = issue(stranger, "olga", "client")
        other = TlsFiles(str(bus_certs.ca), str(made.cert), str(made.key))
        with pytest.raises(zenoh.ZError):
            open_session(connect=[endpoint], tls=other).close()


def test_the_audit_origin_is_the_certificates_name_and_the_transport_locator(
    tmp_path: Path, bus_certs: BusCerts
) -> None:
    endpoint = f"tls/localhost:{free_port()}"
    with (
        running_cpu(tmp_path, BusEnds(listen=[endpoint], tls=bus_certs.tls("cpu.cpu1"))) as cpu,
        open_session(connect=[endpoint], tls=bus_certs.tls("client.olga")) as olga,
    ):
        client = BusClient(olga, "cpu1")
        assert wait_until(lambda: client.chart("FILL") is not None)
        assert _log_in_and_command(client).applied
        (link,) = [x for x in cpu.side.session.info.links() if str(x.zid) == str(olga.zid())]
        client.close()
    rows = {r.op: r for r in read_audit(cpu.state)}
    origin = f"client.olga@{link.dst}"
    assert re.fullmatch(r"client\.olga@tls/127\.0\.0\.1:\d+", origin)
    assert rows["login"].origin == origin and rows["init"].origin == origin
    assert rows["login"].detail == "claimed origin: shell olga@somewhere pid 1"
    assert rows["init"].detail.endswith("; claimed origin: shell olga@somewhere pid 1")


def test_usrpwd_a_wrong_password_cannot_join_and_the_right_one_is_audited_by_its_link(
    tmp_path: Path,
) -> None:
    dictionary = tmp_path / "bus-users.txt"
    dictionary.write_text("cpu.cpu1:cpu secret\nolga:olga secret\n", encoding="utf-8")
    dictionary.chmod(0o600)
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    login = BusLogin("cpu.cpu1", "cpu secret", str(dictionary))
    with running_cpu(tmp_path, BusEnds(listen=[endpoint], login=login)) as cpu:
        for who in (None, BusLogin("olga", "not it"), BusLogin("mallory", "olga secret")):
            with pytest.raises(zenoh.ZError):
                open_session(connect=[endpoint], login=who).close()
        with open_session(connect=[endpoint], login=BusLogin("olga", "olga secret")) as olga:
            client = BusClient(olga, "cpu1")
            assert wait_until(lambda: client.chart("FILL") is not None)
            assert _log_in_and_command(client).applied
            (link,) = cpu.side.session.info.links()
            client.close()
    # zenoh 1.10.2 keeps a usrpwd user name to itself (Link.auth_identifier is None): the
    # origin is the link's remote locator
    origins = {r.origin for r in read_audit(cpu.state) if r.op in ("login", "init")}
    assert origins == {str(link.dst)} and re.fullmatch(r"tcp/127\.0\.0\.1:\d+", str(link.dst))


def test_through_a_router_each_cpu_serves_only_its_own_keys(
    tmp_path: Path, bus_certs: BusCerts
) -> None:
    endpoint = f"tls/localhost:{free_port()}"
    heard: list[str] = []
    with open_session(
        [endpoint], mode="router", tls=bus_certs.tls("router.hub"), guard=("line1", "line2")
    ):
        connect = BusEnds(connect=[endpoint], tls=bus_certs.tls("cpu.line1"))
        with (
            running_cpu(tmp_path, connect, cpu="line1") as line1,
            open_session(connect=[endpoint], tls=bus_certs.tls("cpu.line2")) as line2,
        ):
            line2.declare_queryable(  # line2's identity, line1's key: refused by the router
                "s7graph/line1/login", lambda q: heard.append(str(q.key_expr))
            )
            line2.declare_queryable(
                "s7graph/line2/status", lambda q: q.reply(q.key_expr, b'{"cpu": "line2"}')
            )
            time.sleep(0.5)
            with open_session(connect=[endpoint], tls=bus_certs.tls("client.olga")) as olga:
                client = BusClient(olga, "line1")
                assert wait_until(lambda: client.chart("FILL") is not None)
                assert _log_in_and_command(client).applied
                replies = list(olga.get("s7graph/line2/status", timeout=5))
                assert [r.ok.payload.to_bytes() for r in replies if r.ok] == [b'{"cpu": "line2"}']
                client.close()
        assert heard == []
    rows = [r for r in read_audit(line1.state) if r.op == "login"]
    assert re.fullmatch(r"router\.hub@tls/127\.0\.0\.1:\d+ \(relayed\)", rows[0].origin)


def test_the_docs_show_the_access_table_the_code_uses() -> None:
    table = grants_markdown()
    assert table in (ROOT / "docs" / "security.md").read_text(encoding="utf-8")
