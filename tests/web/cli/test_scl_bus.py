"""``s7graph run PROGRAM.scl`` on the bus (real processes): as a Python program of blocks,
on a TLS bus with a users file it answers ``s7graph status``, ``watch --address`` (a
global DB by name, kept by the warm restart), ``stop`` and ``start`` from a shell and
serves its sources on ``blocks``; with ``--web`` its page shows the CPU in RUN
(docs/scl.md, "On the bus"; docs/cli.md, "s7graph run")"""

from __future__ import annotations

import os
import re
import signal
import socket
import subprocess
import sys
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from tests.paths import ROOT
from tests.web.helpers import chromium_page, wait_until

if TYPE_CHECKING:
    from tests.conftest import BusCerts

pytestmark = pytest.mark.timeout(240)
PASSWORD = "correct horse battery"

BLOCKS = """
FUNCTION_BLOCK FB17
VAR_INPUT go : BOOL; END_VAR
VAR n : DINT; END_VAR
  IF go THEN n := n + 1; END_IF;
END_FUNCTION_BLOCK
"""
PROGRAM = """
DATA_BLOCK DB20
STRUCT warm : INT; END_STRUCT
BEGIN
END_DATA_BLOCK

ORGANIZATION_BLOCK OB100
  DB20.warm := DB20.warm + 1;
END_ORGANIZATION_BLOCK

ORGANIZATION_BLOCK OB1
  FB17.DB10(go := TRUE);
END_ORGANIZATION_BLOCK
"""


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _sources(tmp_path: Path) -> list[str]:
    blocks = tmp_path / "blocks.scl"
    blocks.write_text(BLOCKS, encoding="utf-8")
    program = tmp_path / "prog.scl"
    program.write_text(PROGRAM, encoding="utf-8")
    state = tmp_path / "prog.sqlite"
    return [str(program), "--blocks", str(blocks), "--state", str(state), "--cycle-ms", "5"]


def _users(tmp_path: Path) -> Path:
    users = tmp_path / "users.json"
    for name, role in (("olga", "operator"), ("eng", "engineer")):
        add = ["users", "add", name, "--role", role, "--file", str(users), "--password-stdin"]
        done = _shell([], *add, stdin=PASSWORD + "\n")
        assert done.returncode == 0, done.stderr
    return users


def _shell(
    bus: list[str], *args: str, stdin: str | None = None
) -> subprocess.CompletedProcess[str]:
    """``s7graph ARGS BUS`` as a shell runs it (the password in S7GRAPH_PASSWORD)."""
    return subprocess.run(
        [sys.executable, "-m", "s7graph", *args, *bus],
        cwd=ROOT,
        env=dict(os.environ, S7GRAPH_PASSWORD=PASSWORD),
        input=stdin,
        capture_output=True,
        text=True,
        timeout=60,
    )


def _run(*args: str) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "s7graph", "run", *args, "--duration-s", "180"],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def _first_line(proc: subprocess.Popen[str]) -> str:
    assert proc.stdout is not None
    line = proc.stdout.readline()
    assert line, proc.stderr.read() if proc.stderr is not None else ""
    return line


def test_an_scl_program_on_a_tls_bus_answers_the_shell_and_serves_its_sources(
    tmp_path: Path, bus_certs: BusCerts
) -> None:
    endpoint = f"tls/localhost:{_free_port()}"  # a users file: every node has a certificate
    users = _users(tmp_path)
    proc = _run(
        *_sources(tmp_path),
        "--listen",
        endpoint,
        "--users",
        str(users),
        *bus_certs.args("cpu.cpu1"),
    )
    bus = ["--connect", endpoint, *bus_certs.args("client.olga")]
    try:
        assert f"s7graph: CPU cpu1 on the bus {endpoint}" in _first_line(proc)
        status = _status(bus)  # a loaded machine may refuse the first TLS handshake
        assert status.startswith("CPU cpu1: RUN") and "FBs none" in status, status
        asked = "DB10.n,MW0:INT,DB20.warm"  # DB20 by name: its layout came with the block
        watched = _shell(bus, "watch", "--address", asked, "--duration-s", "1")
        line = watched.stdout.splitlines()[0]
        found = re.search(r"DB10\.n=L#(\d+)\s+MW0:INT=0\s+DB20\.warm=1$", line)
        assert found is not None and int(found[1]) > 0, watched.stdout  # FB17 counts
        assert _shell(bus, "stop", "--user", "olga").returncode == 1  # an operator's? no
        stopped = _shell(bus, "stop", "--user", "eng")
        assert stopped.stdout.startswith("s7graph: stop applied on cpu1 "), stopped.stderr
        assert _status(bus).startswith("CPU cpu1: STOP")
        started = _shell(bus, "start", "--user", "eng")
        assert started.returncode == 0, started.stderr
        assert wait_until(lambda: _status(bus).startswith("CPU cpu1: RUN"), 60)
        again = _shell(bus, "watch", "--address", "DB20.warm", "--duration-s", "1")
        assert again.stdout.splitlines()[0].endswith(" DB20.warm=2"), again  # kept, OB100
        sources = _blocks(endpoint, bus_certs)
        assert [(b.label, b.file, b.line) for b in sources.blocks] == [
            ("FB17", "blocks.scl", 2),
            ("DB20", "prog.scl", 2),
            ("OB100", "prog.scl", 7),
            ("OB1", "prog.scl", 11),
        ]
        assert sources.blocks[0].text == BLOCKS.strip()
    finally:
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=60)
    assert proc.returncode == 0, err  # stopped by the switch and started again: no error
    assert "prog.scl stopped (state saved in" in err


def _status(bus: list[str]) -> str:
    """``s7graph status``'s answer, asked again while the bus does not let it join."""
    answer = [""]

    def asked() -> bool:
        done = _shell(bus, "status")
        answer[0] = done.stdout
        return done.returncode == 0 or "cannot join the bus" not in done.stderr

    wait_until(asked, 60, poll=0.5)
    return answer[0]


def _blocks(endpoint: str, certs: BusCerts) -> object:
    """The CPU's ``blocks``, read by a client over TLS."""
    from s7graph.web.bus.client import BusClient
    from s7graph.web.bus.session import open_session

    with open_session(connect=[endpoint], tls=certs.tls("client.olga")) as session:
        client = BusClient(session, "cpu1")
        found = client.blocks()
        client.close()
    assert found is not None
    return found


def test_an_scl_program_with_web_serves_its_page_with_the_cpu_in_run(tmp_path: Path) -> None:
    port = _free_port()
    proc = _run(*_sources(tmp_path), "--web", "--port", str(port))
    try:
        line = _first_line(proc)
        assert line.startswith(f"s7graph: view http://127.0.0.1:{port}/ (bus "), line
        with chromium_page(f"http://127.0.0.1:{port}/") as page:
            page.get_by_text("s7graph CPU cpu1 (a program)").wait_for(timeout=60_000)
            assert wait_until(lambda: "RUN" in page.inner_text("body"), 60)
    finally:
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=60)
    assert proc.returncode == 0, err
