"""A node that joins a CPU checks whom it reached (``web.bus.session.peer_problem``): over
TLS the node at the other end must be that CPU (``cpu.<name>``) or a router; another
certificate of the plant listening where the CPU should be — a fake CPU — is refused
before a word it says is shown, by the shell's commands, the view and the OPC UA face."""

from __future__ import annotations

from pathlib import Path

import pytest
import zenoh

from s7graph.web.bus.protocol import CpuStatus, encode
from s7graph.web.bus.session import open_session, peer_problem
from s7graph.web.cli import main
from tests.conftest import BusCerts
from tests.web.helpers import free_port

pytestmark = pytest.mark.timeout(60)


@pytest.mark.parametrize(
    ("listener", "wrong"),
    [
        ("cpu.cpu1", None),
        ("router.hub", None),
        ("client.rogue", "is client.rogue, not cpu.cpu1 or a router"),
        ("cpu.line1", "is cpu.line1, not cpu.cpu1 or a router"),
        ("view.desk", "is view.desk, not cpu.cpu1 or a router"),
    ],
)
def test_the_node_reached_over_tls_must_be_the_cpu_or_a_router(
    bus_certs: BusCerts, listener: str, wrong: str | None
) -> None:
    endpoint = f"tls/localhost:{free_port()}"
    with (
        open_session(listen=[endpoint], tls=bus_certs.tls(listener)),
        open_session(connect=[endpoint], tls=bus_certs.tls("client.olga")) as client,
    ):
        problem = peer_problem(client, "cpu1")
    if wrong is None:
        assert problem is None
    else:
        assert problem is not None and wrong in problem and "tls/127.0.0.1:" in problem


def test_a_link_that_proved_no_one_is_not_judged(tmp_path: Path) -> None:
    endpoint = f"unixsock-stream/{tmp_path}/bus.sock"
    with open_session(listen=[endpoint]), open_session(connect=[endpoint]) as client:
        assert peer_problem(client, "cpu1") is None


def test_a_shell_refuses_a_fake_cpu_before_showing_what_it_says(
    bus_certs: BusCerts, capsys: pytest.CaptureFixture[str]
) -> None:
    endpoint = f"tls/localhost:{free_port()}"
    with open_session(listen=[endpoint], tls=bus_certs.tls("client.rogue")):
        code = main(
            ["status", "--cpu", "cpu1", "--connect", endpoint, *bus_certs.args("client.olga")]
        )
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    assert err.startswith("s7graph: error: the node at tls/127.0.0.1:")
    assert "is client.rogue, not cpu.cpu1 or a router: it is not CPU cpu1" in err


@pytest.mark.parametrize(
    "face",
    [
        ["web", "--port", "0", "--duration-s", "1"],
        ["opcua", "--listen", "opc.tcp://127.0.0.1:0", "--duration-s", "1"],
    ],
    ids=["the view", "the OPC UA face"],
)
def test_the_view_and_the_opcua_face_refuse_a_fake_cpu_that_answers(
    bus_certs: BusCerts, capsys: pytest.CaptureFixture[str], face: list[str]
) -> None:
    """The fake answers ``status`` as cpu1 would: the face finds it, then refuses it for
    the certificate it proved, before printing what it said."""
    endpoint = f"tls/localhost:{free_port()}"
    status = encode(CpuStatus(cpu="cpu1", fbs=["Seq_drill"], cycle=424242))

    def answer(query: zenoh.Query) -> None:
        query.reply(query.key_expr, status)

    with open_session(listen=[endpoint], tls=bus_certs.tls("client.rogue")) as fake:
        served = fake.declare_queryable("s7graph/cpu1/status", answer)
        try:
            args = [*face, "--cpu", "cpu1", "--connect", endpoint]
            code = main([*args, *bus_certs.args("client.olga")])
        finally:
            served.undeclare()  # type: ignore[no-untyped-call]
    out, err = capsys.readouterr()
    assert code == 2 and "424242" not in out + err and "CPU cpu1 (" not in out
    assert "is client.rogue, not cpu.cpu1 or a router: it is not CPU cpu1" in err
