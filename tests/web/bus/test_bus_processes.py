"""The bus across processes: ``s7graph router``, two CPUs (``s7graph run --cpu``, one with a
users file, one the demo), ``s7graph web`` serving one of them, ``s7graph watch`` and the
shell's commands, each a process of its own on loopback with its own certificate (mutual
TLS, the router's access control for line1 and line2); and the command line's refusals
(a busy or out-of-range --port, a non-loopback --listen without users)."""

from __future__ import annotations

import os
import queue
import re
import signal
import socket
import subprocess
import sys
import threading
import time
import urllib.request
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from s7graph.web.access.users import UsersFile
from tests.paths import ROOT
from tests.web.helpers import free_port

if TYPE_CHECKING:
    from tests.conftest import BusCerts

pytestmark = pytest.mark.timeout(240)
DRILL = ROOT / "examples" / "drill"
PASSWORD = "correct horse"


class Proc:
    """A running ``s7graph`` process whose stdout lines are collected in a thread."""

    def __init__(self, *args: str, env: dict[str, str] | None = None) -> None:
        self.args = args
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "s7graph", *args],
            cwd=ROOT,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env={**os.environ, **(env or {})},
        )
        self.lines: queue.Queue[str] = queue.Queue()
        self.seen: list[str] = []
        out = self.proc.stdout
        assert out is not None
        threading.Thread(target=lambda: [self.lines.put(x) for x in out], daemon=True).start()

    def wait_for(self, pattern: str, timeout: float = 60) -> re.Match[str]:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            for line in self.seen:
                found = re.search(pattern, line)
                if found:
                    return found
            try:
                self.seen.append(self.lines.get(timeout=0.5))
            except queue.Empty:
                if self.proc.poll() is not None:
                    err = self.proc.stderr.read() if self.proc.stderr else ""
                    raise AssertionError(f"{self.args[0]} ended: {err}") from None
        raise AssertionError(f"no line matching {pattern!r} from {self.args[0]}: {self.seen}")

    def stop(self) -> str:
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
            try:
                self.proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        return self.proc.stderr.read() if self.proc.stderr else ""


def run(*args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "s7graph", *args],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=90,
        env={**os.environ, **(env or {})},
    )


@pytest.fixture
def bus(tmp_path: Path, bus_certs: BusCerts) -> Iterator[tuple[str, Path, Path, BusCerts]]:
    """A router and two CPUs on it, every node with its certificate: line1 with a users file
    (and a quarter of the cycle for commands), line2 the demo."""
    users = UsersFile(tmp_path / "users.json")
    users.add("olga", "operator", PASSWORD)
    users.add("vic", "viewer", PASSWORD)
    endpoint = f"tls/localhost:{free_port()}"
    relays = ["--cpu", "line1", "--cpu", "line2"]
    procs = [Proc("router", "--listen", endpoint, *relays, *bus_certs.args("router.hub"))]
    try:
        procs[0].wait_for("router on")
        chart = [str(DRILL / "drill.s7g"), "--symbols", str(DRILL / "symbols.txt")]
        line1 = ["--users", str(users.path), "--comm-load", "25"]
        for cpu, extra in (("line1", line1), ("line2", [])):
            procs.append(
                Proc(
                    "run",
                    *chart,
                    "--cpu",
                    cpu,
                    *bus_certs.args(f"cpu.{cpu}"),
                    "--connect",
                    endpoint,
                    "--duration-s",
                    "200",
                    "--max-cycle-ms",
                    "5000",  # the bus is tested, not a loaded CI's time errors
                    "--state",
                    str(tmp_path / f"{cpu}.sqlite"),
                    *extra,
                )
            )
        for p in procs[1:]:
            p.wait_for(r"CPU line\d on the bus")
        yield endpoint, users.path, tmp_path, bus_certs
    finally:
        errors = [p.stop() for p in reversed(procs)]
        assert not any("Traceback" in e for e in errors), errors


def test_router_two_cpus_one_web_view_and_shell_commands_as_processes(
    bus: tuple[str, Path, Path, BusCerts],
) -> None:
    endpoint, _, tmp, certs = bus
    port = free_port()
    view = ["--connect", endpoint, *certs.args("view.desk")]
    web = Proc("web", *view, "--cpu", "line2", "--port", str(port), "--duration-s", "200")
    olga = ["--connect", endpoint, *certs.args("client.olga")]
    watch = Proc("watch", *olga, "--cpu", "line1", "--duration-s", "200")
    try:
        web.wait_for(r"CPU line1 \(RUN, logins: users\): Seq_drill")
        web.wait_for(r"CPU line2 \(RUN, logins: demo\): Seq_drill")
        url = web.wait_for(r"view (\S+) of line2/Seq_drill")[1]
        with urllib.request.urlopen(url, timeout=30) as page:
            assert page.status == 200 and b"<html" in page.read(2000).lower()
        watch.wait_for(r"cycle \d+  Seq_drill  AUTO  active S\d")

        env = {"S7GRAPH_PASSWORD": PASSWORD}
        shell = ["--cpu", "line1", *olga]
        done = run("mode", "MAN", *shell, "--user", "olga", env=env)
        assert done.returncode == 0, done.stderr
        assert "mode applied on line1/Seq_drill" in done.stdout
        watch.wait_for(r"Seq_drill  MAN  active")
        refused = run("ack", *shell, "--user", "vic", env=env)
        assert refused.returncode == 1
        assert "ack refused: role viewer may not ack (needs operator)" in refused.stderr
        wrong = run("init", *shell, "--user", "olga", env={"S7GRAPH_PASSWORD": "not it"})
        assert wrong.returncode == 1 and "wrong user name or password" in wrong.stderr
        demo = run("mode", "AUTO", "--cpu", "line2", *olga, "--user", "dan")
        assert demo.returncode == 0, demo.stderr

        audit = run("audit", "--state", str(tmp / "line1.sqlite"), "--since", "1h")
        assert audit.returncode == 0, audit.stderr
        # from the transport: the router's link (the shell is behind it); the claim a note
        relayed = r"from router\.hub@tls/127\.0\.0\.1:\d+ \(relayed\)"
        assert re.search(
            rf"olga \(operator\) {relayed}: mode Seq_drill .*applied - .*claimed origin: shell ",
            audit.stdout,
        )
        assert re.search(r"vic \(viewer\) .*: ack Seq_drill: refused: role viewer", audit.stdout)
        assert PASSWORD not in audit.stdout
        demo_audit = run("audit", "--state", str(tmp / "line2.sqlite"))
        assert "dan (unverified) (engineer)" in demo_audit.stdout

        status = run("status", "--cpu", "line1", *olga)
        assert status.returncode == 0, status.stderr
        head, cycle, longest, *_ = status.stdout.splitlines()
        assert re.match(r"CPU line1: RUN, cycle \d+, FBs Seq_drill, 0 force jobs$", head), head
        assert re.match(
            r"cycle time: last [\d.]+ ms, min [\d.]+, max [\d.]+; scan [\d.]+ ms "
            r"on average; \d+ overruns; \d+ over 12.0 ms$",
            cycle,
        ), cycle
        assert re.match(
            r"longest: cycle \d+ at \d\d:\d\d:\d\d(, overran)?, [\d.]+ ms: "
            r"(encode [\d.]+, )?scan ",
            longest,
        ), longest
        assert status.stdout.splitlines()[-2].startswith(
            "communication: up to 25 % of the cycle at each scan boundary; "
        )
        assert status.stdout.splitlines()[-1].startswith("scan thread: ")
        absent = run("status", "--cpu", "line9", *olga)
        assert absent.returncode == 2 and "CPU 'line9' does not answer" in absent.stderr
    finally:
        for p in (watch, web):
            err = p.stop()
            assert "Traceback" not in err, err


def test_the_command_line_refuses_a_busy_port_and_an_open_bus_without_users(
    tmp_path: Path,
) -> None:
    chart = [str(DRILL / "drill.s7g"), "--symbols", str(DRILL / "symbols.txt")]
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        busy = run(
            "run",
            *chart,
            "--web",
            "--port",
            str(port),
            "--duration-s",
            "5",
            "--state",
            str(tmp_path / "s.sqlite"),
        )
    assert busy.returncode == 2
    assert "is in use" in busy.stderr
    assert len(busy.stderr.strip().splitlines()) == 1, busy.stderr
    out_of_range = run("run", *chart, "--web", "--port", "70000")
    assert out_of_range.returncode == 2
    assert "to 65535, not 70000" in out_of_range.stderr, out_of_range.stderr
    open_bus = run("run", *chart, "--listen", "tcp/0.0.0.0:7447")
    assert open_bus.returncode == 2 and "not loopback" in open_bus.stderr
    open_page = run("run", *chart, "--web", "--host", "0.0.0.0")
    assert open_page.returncode == 2 and "--host 0.0.0.0 is not loopback" in open_page.stderr
