"""The OPC UA server as a process of its own, beside a real ``s7graph run`` CPU process:
``run --opcua`` starts it as a child and starts it again when it dies; with a users file
on a TLS bus the child joins with the CPU's certificate and ``s7graph opcua`` with its
own, OPC UA users log in (the CPU checks the password over the bus) and their signed
commands stop and start the CPU, whose STOP's reason and entry the face shows;
``s7graph opcua`` refuses bad options in one line; and a flood of OPC UA requests costs
the face's process, never the CPU's — its processor time and its scans go on as without
the flood (docs/opcua.md, "Running it")."""

from __future__ import annotations

import asyncio
import os
import re
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING

import pytest
from asyncua import ua
from asyncua.ua.uaerrors import UaStatusCodeError

from s7graph.web.access.audit import read_audit
from s7graph.web.access.users import UsersFile
from s7graph.web.bus.client import BusClient
from s7graph.web.bus.session import open_session
from tests.paths import ROOT
from tests.web.helpers import wait_until
from tests.web.opcua.helpers import (
    FACE_CN,
    PASSWORD,
    connected,
    eventually,
    free_port,
    node,
    run,
)

if TYPE_CHECKING:
    from tests.conftest import BusCerts

pytestmark = pytest.mark.timeout(240)

DRILL = ROOT / "examples" / "drill"
S7GRAPH = [sys.executable, "-m", "s7graph"]


def _children(pid: int) -> list[int]:
    """Every process below ``pid`` (from /proc)."""
    parent: dict[int, int] = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
            except OSError:
                continue
            parent[int(entry.name)] = int(stat.rsplit(")", 1)[1].split()[1])
    found, todo = [], [pid]
    while todo:
        p = todo.pop()
        kids = [c for c, pp in parent.items() if pp == p]
        found += kids
        todo += kids
    return found


def _cpu_seconds(pids: list[int]) -> float:
    """User and system time of ``pids`` so far."""
    total = 0
    for pid in pids:
        try:
            fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        total += int(fields[11]) + int(fields[12])
    return total / os.sysconf("SC_CLK_TCK")


def _opcua_child(tree: list[int]) -> int | None:
    for pid in tree:
        try:
            cmd = Path(f"/proc/{pid}/cmdline").read_bytes().split(b"\0")
        except OSError:
            continue
        if b"opcua" in cmd and b"--child" in cmd:
            return pid
    return None


@contextmanager
def _run(tmp_path: Path, *extra: str) -> Iterator[subprocess.Popen[str]]:
    proc = subprocess.Popen(
        [
            *S7GRAPH,
            "run",
            str(DRILL / "drill.s7g"),
            "--plant",
            str(DRILL / "demo_plant.py"),
            "--symbols",
            str(DRILL / "symbols.txt"),
            "--state",
            str(tmp_path / "state.sqlite"),
            *extra,
        ],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        yield proc
    finally:
        if proc.poll() is None:
            _interrupt(proc, must_end=False)


def _interrupt(proc: subprocess.Popen[str], *, must_end: bool = True) -> None:
    """Ctrl-C to ``proc``; one not ended within 30 s is killed (and, ``must_end``, fails)."""
    proc.send_signal(signal.SIGINT)
    try:
        proc.wait(30)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait(30)
        if must_end:
            raise AssertionError(f"{proc.args} did not end within 30 s of Ctrl-C") from None


def _line(proc: subprocess.Popen[str], pattern: str, timeout: float = 90.0) -> str:
    """The first line of ``proc``'s stdout matching ``pattern``."""
    assert proc.stdout is not None
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        line = proc.stdout.readline()
        if not line:
            break
        if re.search(pattern, line):
            return line
    raise AssertionError(
        f"no line like {pattern!r}; stderr: {proc.stderr.read() if proc.stderr else ''}"
    )


def test_run_opcua_serves_from_a_child_started_again_when_it_dies(tmp_path: Path) -> None:
    url = f"opc.tcp://127.0.0.1:{free_port()}"
    with _run(tmp_path, "--opcua", url) as proc:
        assert url in _line(proc, r"^s7graph: opcua ")

        async def state() -> object:
            async with connected(url) as c:
                return await node(c, "cpu1/State").read_value()

        assert run(state()) == "RUN"
        child = _opcua_child(_children(proc.pid))
        assert child is not None
        os.kill(child, signal.SIGKILL)
        assert wait_until(lambda: _opcua_child(_children(proc.pid)) not in (None, child), 60)

        async def back() -> bool:
            try:
                return await state() == "RUN"
            except (TimeoutError, OSError, UaStatusCodeError):
                return False

        async def wait_back() -> bool:
            return await eventually(back, 90)

        assert run(wait_back())
        assert proc.poll() is None  # the CPU went on
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=60)
    assert "the OPC UA server process ended (killed by SIGKILL); restarting it in 1 s" in err


def test_on_a_tls_bus_the_faces_log_users_in_and_their_commands_stop_and_start_the_cpu(
    tmp_path: Path, bus_certs: BusCerts
) -> None:
    users = UsersFile(tmp_path / "users.json")
    users.add("eng", "engineer", PASSWORD)
    endpoint = f"tls/localhost:{free_port()}"
    child_url, own_url = (f"opc.tcp://127.0.0.1:{free_port()}" for _ in range(2))
    cpu_args = ["--users", str(users.path), "--listen", endpoint, *bus_certs.args("cpu.cpu1")]
    with _run(tmp_path, *cpu_args, "--opcua", child_url) as cpu:
        assert child_url in _line(cpu, r"^s7graph: opcua ")  # joined with the CPU's
        face_args = ["--listen", own_url, "--users", str(users.path), *bus_certs.args(FACE_CN)]
        face = subprocess.Popen(
            [*S7GRAPH, "opcua", "--connect", endpoint, *face_args],
            cwd=ROOT,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        try:
            _line(face, r"^s7graph: opcua ")
            run(_stop_and_start(child_url, own_url))
        finally:
            _interrupt(face)
    rows = [r for r in read_audit(tmp_path / "state.sqlite") if r.op in ("stop", "start")]
    assert [(r.user, r.op, r.outcome) for r in rows] == [
        ("eng", "stop", "applied"),
        ("eng", "stop", "refused"),
        ("eng", "start", "applied"),
    ]
    assert rows[0].origin.startswith("cpu.cpu1@tls/127.0.0.1:")  # the child's link
    assert rows[2].origin.startswith(f"{FACE_CN}@tls/127.0.0.1:")  # the face's own


async def _stop_and_start(child_url: str, own_url: str) -> None:
    """STOP through the child's face, its reason and entry on both faces; RUN again
    through the other."""

    async def reads(c: object, path: str, value: object, index: int | None = None) -> bool:
        got = await node(c, path).read_value()
        return bool(got) and got[index] == value if index is not None else bool(got == value)

    async with connected(child_url, "eng") as child, connected(own_url, "eng") as own:
        assert await eventually(lambda: reads(own, "cpu1/State", "RUN"), 30)
        await node(child, "cpu1").call_method(ua.NodeId("cpu1/Stop", 2))
        for c in (child, own):
            assert await eventually(lambda c=c: reads(c, "cpu1/State", "STOP"), 30)
            assert await eventually(lambda c=c: reads(c, "cpu1/StopEventId", "16#4304"), 30)
            assert "STOP by the switch (eng)" in await node(c, "cpu1/StopReason").read_value()
            newest = "cpu1/DiagnosticBuffer/EventId"
            assert await eventually(lambda c=c, at=newest: reads(c, at, "16#4304", 0), 30)
        with pytest.raises(UaStatusCodeError):  # in STOP already: the CPU refuses it
            await node(own, "cpu1").call_method(ua.NodeId("cpu1/Stop", 2))
        await node(own, "cpu1").call_method(ua.NodeId("cpu1/Start", 2))
        for c in (child, own):
            assert await eventually(lambda c=c: reads(c, "cpu1/State", "RUN"), 30)
            assert await eventually(lambda c=c: reads(c, "cpu1/StopEventId", ""), 30)
            assert await node(c, "cpu1/StopReason").read_value() == ""


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (
            ["opcua", "--connect", "tcp/127.0.0.1:1", "--listen", "opc.tcp://0.0.0.0:4840"],
            "--users",
        ),
        (
            ["opcua", "--connect", "tcp/127.0.0.1:1", "--listen", "http://x:1"],
            "opc.tcp://HOST:PORT",
        ),
        (["opcua", "--connect", "tcp/127.0.0.1:1", "--anonymous", "maybe"], "read or refuse"),
        (["run", "x.s7g", "--opcua", "opc.tcp://10.1.2.3:4840"], "--users"),
        (["run", "x.s7g", "--opcua-cert", "c.pem"], "go with --opcua"),
        (["opcua", "--connect", "tcp/127.0.0.1:1", "--writes", "hold"], "force or modify"),
        (["run", "x.s7g", "--opcua-writes", "modify"], "go with --opcua"),
        (
            ["run", "x.s7g", "--opcua", "opc.tcp://127.0.0.1:4840", "--opcua-writes", "hold"],
            "--opcua-writes must be force or modify",
        ),
        (["run", "x.py", "--opcua", "opc.tcp://127.0.0.1:4840"], "chart"),
    ],
)
def test_bad_options_are_one_line_and_exit_2(args: list[str], says: str) -> None:
    proc = subprocess.run([*S7GRAPH, *args], cwd=ROOT, capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("s7graph: error:") and says in lines[0], lines


def test_a_flood_of_opcua_requests_is_not_felt_by_the_cpu(tmp_path: Path) -> None:
    """The CPU process's processor time and its scans over three seconds of a flood of
    OPC UA requests are those of three quiet seconds: every request is the face's."""
    endpoint = f"unixsock-stream/{tmp_path}/bus.sock"
    url = f"opc.tcp://127.0.0.1:{free_port()}"
    with _run(tmp_path, "--listen", endpoint) as cpu:
        _line(cpu, "on the bus")
        face = subprocess.Popen(
            [*S7GRAPH, "opcua", "--connect", endpoint, "--listen", url],
            cwd=ROOT,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        try:
            _line(face, r"^s7graph: opcua ")
            run(_flood(url, cpu.pid, face.pid, endpoint))
        finally:
            _interrupt(face)


async def _flood(url: str, cpu_pid: int, face_pid: int, endpoint: str) -> None:
    with open_session(connect=[endpoint]) as session:
        client = BusClient(session, "cpu1")
        tree = [cpu_pid, *_children(cpu_pid)]

        def sample() -> tuple[float, float, int]:
            status = client.status()
            assert status is not None and status.stats is not None
            return time.monotonic(), _cpu_seconds(tree), status.cycle

        await asyncio.sleep(2.0)  # the face has built its address space
        t0, cpu0, cycle0 = sample()
        await asyncio.sleep(3.0)
        t1, cpu1, cycle1 = sample()
        face0 = _cpu_seconds([face_pid])
        served = await _hammer(url, seconds=3.0)
        t2, cpu2, cycle2 = sample()
        face_spent = _cpu_seconds([face_pid]) - face0
        client.close()
    quiet, flood = (cpu1 - cpu0) / (t1 - t0), (cpu2 - cpu1) / (t2 - t1)
    scans_quiet, scans_flood = (cycle1 - cycle0) / (t1 - t0), (cycle2 - cycle1) / (t2 - t1)
    shown = (
        f"CPU process {quiet:.3f} s/s quiet, {flood:.3f} s/s under {served} operations; "
        f"the face spent {face_spent:.2f} s; scans/s {scans_quiet:.0f} quiet, {scans_flood:.0f}"
    )
    print(shown)
    assert served > 10_000 and face_spent > 0.2, shown  # the flood happened, in the face
    assert flood <= quiet * 1.5 + 0.05, shown
    assert scans_flood >= scans_quiet * 0.8, shown


async def _hammer(url: str, *, seconds: float) -> int:
    """Three anonymous clients doing what a hostile client does for ``seconds``: reads of
    400 values, browses, subscriptions of 200 items made and dropped, calls refused; the
    operations asked for."""
    served = [0]

    async def one(kind: int, ready: asyncio.Event, go: asyncio.Event) -> None:
        async with connected(url) as c:
            fb = node(c, "cpu1/Seq_drill")
            ready.set()
            await go.wait()
            deadline = time.monotonic() + seconds
            while time.monotonic() < deadline:
                try:
                    if kind == 0:
                        await c.uaclient.read(_reads())
                        served[0] += 400
                    elif kind == 1:
                        await fb.get_children()
                        sub = await c.create_subscription(10, None)
                        await sub.subscribe_data_change([node(c, "cpu1/Cycle")] * 200)
                        await sub.delete()
                        served[0] += 203
                    else:
                        await fb.call_method(ua.NodeId("cpu1/Seq_drill/Init", 2))
                except (TimeoutError, UaStatusCodeError):
                    served[0] += 1

    readies = [asyncio.Event() for _ in range(3)]
    go = asyncio.Event()
    tasks = [asyncio.create_task(one(k, readies[k], go)) for k in range(3)]
    for ready in readies:
        await ready.wait()
    go.set()
    await asyncio.gather(*tasks)
    return served[0]


def _reads() -> ua.ReadParameters:
    params = ua.ReadParameters()
    paths = ["cpu1/State", "cpu1/Cycle", "cpu1/Seq_drill/S2/T", "cpu1/Symbols/Start_button"]
    params.NodesToRead = [
        ua.ReadValueId(NodeId=ua.NodeId(p, 2), AttributeId=ua.AttributeIds.Value)
        for p in paths * 100
    ]
    return params
