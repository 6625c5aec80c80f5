"""The command line's bus options at start: a CPU or router that would be reachable by
anyone is refused with one line naming the way out (exit 2), and ``s7graph certs`` makes a
CA and node certificates that a real session then uses."""

from __future__ import annotations

import os
import socket
import stat
from pathlib import Path
from typing import TYPE_CHECKING

import pytest
import zenoh

from s7graph.sequencer.text.model import Chart, Sequence, Step, Transition
from s7graph.web.access.certs import read_common_name
from s7graph.web.access.users import UsersFile
from s7graph.web.bus.client import BusClient
from s7graph.web.bus.cpu_side import CpuSide
from s7graph.web.bus.protocol import ChartLayout
from s7graph.web.bus.session import BusEnds, TlsFiles, open_session
from s7graph.web.cli import main
from s7graph.web.cli.net import NetOptions
from tests.web.helpers import wait_until

if TYPE_CHECKING:
    from tests.conftest import BusCerts

pytestmark = pytest.mark.timeout(60)
ROOT = Path(__file__).resolve().parents[3]
CHART = str(ROOT / "examples" / "drill" / "drill.s7g")


def _refused(capsys: pytest.CaptureFixture[str], *args: str) -> str:
    """The one error line of ``s7graph ARGS``, which must exit 2 at start."""
    assert main(list(args)) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("s7graph: error: "), err
    return err[0]


def _tls_endpoint() -> str:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return f"tls/localhost:{s.getsockname()[1]}"


def _cpu(endpoint: str, tls: TlsFiles) -> CpuSide:
    """A CPU of one small chart listening on ``endpoint`` with ``tls``."""
    steps = (Step(1, "Idle", initial=True),)
    chart = Chart("FILL", sequences=(Sequence(1, "M", steps, (Transition(1, "", (1,), (1,)),)),))
    ends = BusEnds(listen=[endpoint], tls=tls)
    return CpuSide({"FILL": ChartLayout.from_chart(chart)}, cpu="cpu1", ends=ends)


def _users(tmp_path: Path) -> Path:
    users = UsersFile(tmp_path / "users.json")
    users.add("olga", "operator", "correct horse")
    return users.path


def test_a_demo_cpu_connecting_to_another_machine_is_refused_like_listening(
    capsys: pytest.CaptureFixture[str],
) -> None:
    line = _refused(capsys, "run", CHART, "--connect", "tcp/10.1.2.3:7447")
    assert "--connect tcp/10.1.2.3:7447 is not loopback" in line and "users file" in line
    line = _refused(capsys, "run", CHART, "--listen", "tcp/0.0.0.0:7447")
    assert "--listen tcp/0.0.0.0:7447 is not loopback" in line


def test_a_users_file_that_is_not_there_is_said_at_start_with_or_without_a_bus(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    missing = str(tmp_path / "nosuch" / "users.json")
    for extra in ((), ("--listen", "tcp/127.0.0.1:7447")):
        line = _refused(capsys, "run", CHART, "--users", missing, *extra)
        assert line == f"s7graph: error: {missing}: no such users file (s7graph users add ...)"


def test_a_cpu_with_users_and_a_bus_without_credentials_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], bus_certs: BusCerts
) -> None:
    users = str(_users(tmp_path))
    line = _refused(capsys, "run", CHART, "--users", users, "--listen", "tcp/127.0.0.1:7447")
    assert "would let anyone join" in line and "s7graph certs init" in line
    line = _refused(capsys, "run", CHART, "--users", users, "--connect", "tcp/10.1.2.3:7447")
    assert "without credentials" in line and "s7graph certs init" in line
    line = _refused(  # a tcp/ endpoint beside the certificate is still open to anyone
        capsys,
        "run",
        CHART,
        "--users",
        users,
        "--listen",
        "tcp/127.0.0.1:7447",
        *bus_certs.args("cpu.cpu1"),
    )
    assert "would let anyone join" in line


def test_a_cpu_proves_its_own_name_and_not_another_nodes(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], bus_certs: BusCerts
) -> None:
    line = _refused(
        capsys,
        "run",
        CHART,
        "--cpu",
        "line1",
        "--listen",
        "tls/localhost:7447",
        *bus_certs.args("cpu.line2"),
    )
    assert "is 'cpu.line2', not 'cpu.line1'" in line and "certs issue" in line
    secret = tmp_path / "pw"
    secret.write_text("s3cret\n", encoding="utf-8")
    secret.chmod(0o600)
    line = _refused(
        capsys,
        "run",
        CHART,
        "--cpu",
        "line1",
        "--bus-user",
        "olga",
        "--bus-password-file",
        str(secret),
    )
    assert "--bus-user olga: the bus user of CPU line1 is cpu.line1" in line


def test_the_bus_password_file_must_be_private_and_the_user_named(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    secret = tmp_path / "pw"
    secret.write_text("s3cret\n", encoding="utf-8")
    secret.chmod(0o644)
    line = _refused(
        capsys,
        "status",
        "--connect",
        "tcp/127.0.0.1:7447",
        "--bus-user",
        "olga",
        "--bus-password-file",
        str(secret),
    )
    assert f"others may read it (chmod 600 {secret})" in line
    line = _refused(
        capsys, "status", "--connect", "tcp/127.0.0.1:7447", "--bus-password-file", str(secret)
    )
    assert "--bus-password-file needs --bus-user" in line


def test_a_router_with_credentials_names_its_cpus_and_one_without_stays_home(
    capsys: pytest.CaptureFixture[str], bus_certs: BusCerts
) -> None:
    line = _refused(
        capsys, "router", "--listen", "tls/localhost:7447", *bus_certs.args("router.hub")
    )
    assert "--cpu NAME" in line
    line = _refused(capsys, "router", "--listen", "tcp/0.0.0.0:7447")
    assert "not loopback" in line and "s7graph certs init" in line
    line = _refused(
        capsys,
        "router",
        "--listen",
        "tcp/0.0.0.0:7447",
        "--cpu",
        "line1",
        *bus_certs.args("router.hub"),
    )
    assert "would let anyone join" in line


def test_certs_init_and_issue_make_files_a_real_session_uses(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = tmp_path / "plant"
    assert main(["certs", "init", str(folder)]) == 0
    assert main(["certs", "issue", str(folder), "cpu1", "--kind", "cpu", "--host", "plc1"]) == 0
    assert main(["certs", "issue", str(folder), "olga", "--kind", "client"]) == 0
    capsys.readouterr()
    for key in ("ca.key", "cpu.cpu1.key", "client.olga.key"):
        assert stat.S_IMODE(os.stat(folder / key).st_mode) == 0o600, key
    assert read_common_name(folder / "cpu.cpu1.pem") == "cpu.cpu1"

    # what is there stays unless --force; an unusable CA or name is one line
    before = (folder / "cpu.cpu1.pem").read_bytes()
    line = _refused(capsys, "certs", "issue", str(folder), "cpu1", "--kind", "cpu")
    assert "already there (give --force" in line
    assert (folder / "cpu.cpu1.pem").read_bytes() == before
    assert main(["certs", "issue", str(folder), "cpu1", "--kind", "cpu", "--force"]) == 0
    assert (folder / "cpu.cpu1.pem").read_bytes() != before
    assert "already there" in _refused(capsys, "certs", "init", str(folder))
    assert "no such file" in _refused(
        capsys, "certs", "issue", str(tmp_path / "x"), "a", "--kind", "cpu"
    )
    assert "use one of cpu" in _refused(
        capsys, "certs", "issue", str(folder), "a", "--kind", "boss"
    )
    assert "use letters" in _refused(capsys, "certs", "issue", str(folder), "a b", "--kind", "cpu")
    (folder / "ca.key").write_text("not a key", encoding="utf-8")
    line = _refused(capsys, "certs", "issue", str(folder), "b", "--kind", "cpu")
    assert "cannot read the CA's key" in line
    capsys.readouterr()

    endpoint = _tls_endpoint()
    ca = str(folder / "ca.pem")
    cpu_tls = TlsFiles(ca, str(folder / "cpu.cpu1.pem"), str(folder / "cpu.cpu1.key"))
    olga_tls = TlsFiles(ca, str(folder / "client.olga.pem"), str(folder / "client.olga.key"))
    side = _cpu(endpoint, cpu_tls)
    try:
        with open_session(connect=[endpoint], tls=olga_tls) as olga:
            client = BusClient(olga, "cpu1")
            assert wait_until(lambda: client.status() is not None)
            (link,) = side.session.info.links()
            assert link.auth_identifier == "client.olga"
            client.close()
    finally:
        side.close()


def test_a_shell_without_a_certificate_is_told_why_it_cannot_join(
    capsys: pytest.CaptureFixture[str], bus_certs: BusCerts
) -> None:
    endpoint = _tls_endpoint()
    side = _cpu(endpoint, bus_certs.tls("cpu.cpu1"))
    try:
        line = _refused(capsys, "status", "--connect", endpoint, "--tls-ca", str(bus_certs.ca))
        assert line.endswith(
            f"cannot join the bus: nothing answers at {endpoint}: nothing listens there, or "
            "it lets in only nodes with credentials (--tls-cert/--tls-key or --bus-user)"
        )
        assert main(["status", "--connect", endpoint, *bus_certs.args("client.olga")]) == 0
        assert capsys.readouterr().out.startswith("CPU cpu1: ")
    finally:
        side.close()


@pytest.mark.parametrize(
    ("credentials", "error", "said"),
    [
        (
            False,
            "Unable to connect to any of [Single(tcp/127.0.0.1:1)]!  at /root/.cargo/git/"
            "checkouts/zenoh-9c599d5ef3e0480e/cc83980/zenoh/src/net/runtime/orchestrator.rs:447.",
            "cannot join the bus: nothing answers at tcp/127.0.0.1:1: nothing listens there, "
            "or it lets in only nodes with credentials (--tls-cert/--tls-key or --bus-user)",
        ),
        (
            True,
            "Unable to connect to any of [Single(tcp/127.0.0.1:1)]! at /x/orchestrator.rs:447.",
            "cannot join the bus: nothing answers at tcp/127.0.0.1:1: nothing listens there, "
            "or it refused this node's credentials",
        ),
        (
            True,
            "Invalid TLS configuration at /x/zenoh-link-tls/src/utils.rs:91.",
            "cannot join the bus: Invalid TLS configuration",
        ),
    ],
)
def test_why_a_node_cannot_join_is_said_without_zenohs_source_places(
    credentials: bool, error: str, said: str
) -> None:
    """zenoh ends its errors with the Rust file and line they come from: left out; a bus
    nobody answers at says what to check, as this node showed credentials or not."""
    net = NetOptions(connect=["tcp/127.0.0.1:1"], bus_user="olga" if credentials else None)
    assert net.join_error(zenoh.ZError(error)) == said


SYMBOLS = ("--symbols", str(ROOT / "examples" / "drill" / "symbols.txt"))


@pytest.mark.parametrize(
    "program", [(CHART, *SYMBOLS), (str(ROOT / "examples" / "blink.py"),)], ids=["chart", "py"]
)
def test_a_run_whose_bus_answers_nowhere_says_where_as_a_shell_does(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], program: tuple[str, ...]
) -> None:
    """``run --connect`` to an endpoint nobody listens at (no --web): the join's words,
    never "cannot serve the view" nor zenoh's Rust source places (docs/cli.md, "The bus
    from a shell")."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]  # closed again: nothing listens there
    line = _refused(
        capsys,
        *("run", *program, "--state", str(tmp_path / "s.sqlite"), "--duration-s", "1"),
        *("--connect", f"tcp/127.0.0.1:{port}"),
    )
    assert line == (
        f"s7graph: error: cannot join the bus: nothing answers at tcp/127.0.0.1:{port}: nothing "
        "listens there, or it lets in only nodes with credentials (--tls-cert/--tls-key or "
        "--bus-user)"
    )


def test_a_run_whose_listen_address_is_taken_says_so_without_rust_places(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``run --listen`` on a port another program holds: the bus's refusal with the OS's
    words, every Rust source place zenoh quotes left out (the cause's too)."""
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        line = _refused(
            capsys,
            *("run", CHART, *SYMBOLS, "--state", str(tmp_path / "s.sqlite")),
            *("--duration-s", "1", "--listen", f"tcp/127.0.0.1:{port}"),
        )
    assert line.startswith("s7graph: error: cannot put the CPU on the bus: ")
    assert "Address already in use" in line and ".rs:" not in line


@pytest.mark.parametrize("command", [["init"], ["issue", "cpu1", "--kind", "cpu"]])
def test_certs_given_a_file_for_its_folder_says_it_is_a_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], command: list[str]
) -> None:
    """Before: ``pki.txt/ca.key: cannot write: File exists`` for ``init``."""
    path = tmp_path / "pki.txt"
    path.write_text("notes\n", encoding="utf-8")
    line = _refused(capsys, "certs", command[0], str(path), *command[1:])
    assert line == (
        f"s7graph: error: {path}: a file, not a folder; give the folder of the plant's certificates"
    )
    assert path.read_text(encoding="utf-8") == "notes\n"


def test_a_run_taking_the_name_of_a_cpu_running_here_warns_before_it_starts(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """Two runs named cpu1 on one machine (two examples in two shells): a shell reaches the
    second only while it runs — the second says so; a
    socket a killed CPU left behind is no CPU running (``web.cli.net.running_here``)."""
    from s7graph.web.bus import local
    from s7graph.web.cli.net import name_taken_note

    runtime = tmp_path / "run"
    runtime.mkdir(mode=0o700)
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(runtime))
    sock = tmp_path / "bus.sock"
    endpoint = f"unixsock-stream/{sock}"
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as first:
        first.bind(str(sock))
        first.listen()
        local.publish("cpu1", endpoint)
        assert name_taken_note(NetOptions(cpu="line2")) == ""
        assert name_taken_note(NetOptions(cpu="cpu1", listen=["tcp/127.0.0.1:7447"])) == ""
        args = ["run", str(ROOT / "examples" / "blink.py"), "--state", str(tmp_path / "s.sqlite")]
        assert main([*args, "--web", "--port", "0", "--duration-s", "0.5"]) == 0
        err = capsys.readouterr().err
    assert " in RUN (" in err.splitlines()[0]  # the warning after it, as the run starts
    assert err.splitlines()[1] == (
        f"s7graph: warning: a CPU named cpu1 runs on this machine already ({endpoint}): a shell "
        "reaches only this one while it runs (that one again once it ends); give each its own "
        "name with --cpu NAME"
    )
    local.publish("cpu1", endpoint)  # the socket file stays, nothing listens: a killed CPU's
    assert name_taken_note(NetOptions(cpu="cpu1")) == ""
