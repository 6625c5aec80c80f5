"""``s7graph web`` and ``s7graph opcua`` given no ``--connect`` serve the CPU of this
machine, found as ``status`` and ``watch`` find it (web/cli/waiting.py, ``local_cpu``;
docs/cli.md, "The bus from a shell"): the one named with ``--cpu``, else the only one
running here; several running is a one-line error naming them; one not there yet is
waited for, said once on stderr, and ``--duration-s`` ends that wait with exit 2. Real
processes: CPUs started with ``run --web`` (their own sockets, written to the endpoint
files of a private folder), and the view and the OPC UA face."""

from __future__ import annotations

import os
import signal
from pathlib import Path

import pytest

from tests.web.cli.test_watch_waits import CHART, Lines, _local_cpu, _started
from tests.web.helpers import free_port

pytestmark = pytest.mark.timeout(240)

SEVERAL = (
    "s7graph: error: several CPUs run on this machine for this user (line1, line2): name "
    "one with --cpu NAME, or give the bus with --connect ENDPOINT\n"
)


def _machine(tmp_path: Path) -> tuple[dict[str, str], Path]:
    """An environment whose private folder of endpoints is fresh (XDG_RUNTIME_DIR), and
    the chart its CPUs run."""
    runtime = tmp_path / "runtime"
    runtime.mkdir(mode=0o700)
    chart = tmp_path / "wait.s7g"
    chart.write_text(CHART, encoding="utf-8")
    return {**os.environ, "XDG_RUNTIME_DIR": str(runtime)}, chart


def _ran(command: list[str], env: dict[str, str]) -> tuple[int, str, str]:
    """``s7graph COMMAND`` run to its end: (exit status, stdout, stderr)."""
    proc = _started(command, env)
    out, err = proc.communicate(timeout=90)
    return proc.returncode, out, err


def _ua() -> list[str]:
    return ["opcua", "--listen", f"opc.tcp://127.0.0.1:{free_port()}"]


def test_web_and_opcua_given_no_connect_serve_the_cpu_named_or_the_only_one_running_here(
    tmp_path: Path,
) -> None:
    """Two CPUs run: without ``--cpu`` neither command guesses (exit 2, both named); with
    it each serves its CPU. One killed leaves its endpoint file naming a dead socket: it no
    longer counts, and the face serves the only CPU still running."""
    env, chart = _machine(tmp_path)
    cpus = [_local_cpu(tmp_path, env, chart, name) for name in ("line1", "line2")]
    try:
        for command in (["web", "--port", "0"], _ua()):
            assert _ran([*command, "--duration-s", "1"], env) == (2, "", SEVERAL)
        code, out, err = _ran(["web", "--port", "0", "--cpu", "line2", "--duration-s", "1"], env)
        assert code == 0 and err == "s7graph: view stopped\n", err
        assert out.startswith("s7graph: CPU line2 (RUN, logins: demo): Seq_wait\n"), out
        assert " of line2/Seq_wait; Ctrl-C to stop" in out
        code, out, err = _ran([*_ua(), "--cpu", "line1", "--duration-s", "1"], env)
        assert code == 0 and err == "s7graph: opcua stopped\n", err
        assert out.startswith("s7graph: opcua opc.tcp://127.0.0.1:") and " of line1;" in out
        cpus[1].kill()
        cpus[1].wait(30)
        assert (tmp_path / "runtime" / "s7graph" / "line2.endpoint").exists()  # left behind
        code, out, err = _ran([*_ua(), "--duration-s", "1"], env)
        assert code == 0 and " of line1;" in out, (out, err)
    finally:
        for cpu in cpus:
            cpu.kill()
            cpu.wait(30)


def test_web_and_opcua_started_before_the_cpu_of_this_machine_say_once_they_wait_then_serve(
    tmp_path: Path,
) -> None:
    env, chart = _machine(tmp_path)
    url = f"opc.tcp://127.0.0.1:{free_port()}"
    faces = [
        _started(["web", "--port", "0", "--duration-s", "200"], env),
        _started(["opcua", "--listen", url, "--cpu", "cpu1", "--duration-s", "200"], env),
    ]
    cpu = None
    try:
        said = [Lines(face, stderr=True) for face in faces]
        said[0].wait_for(
            "s7graph: waiting for a CPU at s7graph/* on this machine (no CPU is on this "
            "machine's bus for this user yet)"
        )
        said[1].wait_for(
            "s7graph: waiting for CPU cpu1 at s7graph/cpu1 on this machine (no CPU cpu1 is on "
            "this machine's bus for this user yet)"
        )
        cpu = _local_cpu(tmp_path, env, chart)
        Lines(faces[0]).wait_for("s7graph: view http://127.0.0.1:")
        Lines(faces[1]).wait_for(f"s7graph: opcua {url} of cpu1; Ctrl-C to stop")
        for face in faces:
            face.send_signal(signal.SIGINT)
            assert face.wait(30) == 0
        for lines, what in zip(said, ("view", "opcua"), strict=True):
            rest = lines.rest()
            assert len(rest) == 2 and rest[1] == f"s7graph: {what} stopped", rest  # said once
    finally:
        for proc in [*faces, cpu]:
            if proc is not None and proc.poll() is None:
                proc.kill()
                proc.wait(30)


@pytest.mark.parametrize(
    ("command", "said"),
    [
        (
            ["web", "--port", "0"],
            "s7graph: waiting for a CPU at s7graph/* on this machine (no CPU is on this "
            "machine's bus for this user yet)\n"
            "s7graph: error: no CPU appeared at s7graph/* on this machine within 1.5 s "
            "(--duration-s)\n",
        ),
        (
            ["opcua", "--cpu", "line1"],
            "s7graph: waiting for CPU line1 at s7graph/line1 on this machine (no CPU line1 "
            "is on this machine's bus for this user yet)\n"
            "s7graph: error: CPU line1 did not appear at s7graph/line1 on this machine within "
            "1.5 s (--duration-s)\n",
        ),
    ],
    ids=["web", "opcua"],
)
def test_web_and_opcua_whose_local_cpu_does_not_appear_within_duration_s_exit_2_saying_so(
    tmp_path: Path, command: list[str], said: str
) -> None:
    env, _ = _machine(tmp_path)
    assert _ran([*command, "--duration-s", "1.5"], env) == (2, "", said)
