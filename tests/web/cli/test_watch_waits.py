"""``s7graph watch --address`` waits for a CPU that goes away, as ``s7graph watch`` does
(web/cli/watch_table.py, docs/cli.md, "s7graph watch --address"): it says ``CPU cpu1
disconnected``, stays, says ``CPU cpu1 reachable`` when the CPU is back and shows its values
again. Both watches wait for a CPU not there yet at their start too (web/cli/waiting.py,
docs/cli.md, "The bus from a shell"): said once on stderr, with where; ``--duration-s``
ends the wait with exit 2 and why. Given no ``--connect``, a CPU of this machine started
again on a new socket is joined there (web/cli/rejoin.py). Real processes: a CPU running a
program of blocks (or a chart) on a unix socket, killed and started again, and the shell's
watch."""

from __future__ import annotations

import os
import queue
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from s7graph.web.access.scram import MIN_ITERATIONS
from s7graph.web.access.users import UsersFile
from s7graph.web.bus.client import BusClient
from s7graph.web.bus.cpu_side import CpuSide
from s7graph.web.bus.protocol import WatchValues
from s7graph.web.bus.session import open_session
from s7graph.web.cli.net import NetOptions
from s7graph.web.cli.rejoin import PROBE_S, answer
from s7graph.web.cli.waiting import Reached, cpu_reached
from s7graph.web.cli.watch_table import _Follower
from tests.paths import ROOT
from tests.web.cli.test_program_bus import _bus, _program
from tests.web.helpers import PASSWORD, cpu_process, free_port

if TYPE_CHECKING:
    from tests.conftest import BusCerts

pytestmark = pytest.mark.timeout(240)


class Lines:
    """The stdout lines of ``proc``, read by a thread."""

    def __init__(self, proc: subprocess.Popen[str], *, stderr: bool = False) -> None:
        self.proc = proc
        self.seen: list[str] = []
        self._lines: queue.Queue[str] = queue.Queue()
        out = proc.stderr if stderr else proc.stdout
        assert out is not None
        threading.Thread(target=lambda: [self._lines.put(x) for x in out], daemon=True).start()

    def wait_for(self, test: str, after: int = 0, timeout: float = 60) -> int:
        """The index of the first line from ``after`` on that starts with ``test``."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            for i, line in enumerate(self.seen[after:], after):
                if line.startswith(test):
                    return i
            try:
                self.seen.append(self._lines.get(timeout=0.5).rstrip("\n"))
            except queue.Empty:
                assert self.proc.poll() is None, f"watch ended: {self.seen}"
        raise AssertionError(f"no line {test!r} after line {after}: {self.seen}")

    def rest(self) -> list[str]:
        """Every line, once the process has ended and its stream is read to the end."""
        while True:
            try:
                self.seen.append(self._lines.get(timeout=2).rstrip("\n"))
            except queue.Empty:
                return self.seen


def test_watch_address_waits_for_a_cpu_that_goes_and_shows_it_again_when_it_is_back(
    tmp_path: Path,
) -> None:
    args = [*_program(tmp_path), "--fresh"]
    command = [sys.executable, "-m", "s7graph", "watch", *_bus(tmp_path), "--address"]
    command += ["MW10:INT", "--interval-ms", "50", "--duration-s", "200"]
    watch = None
    try:
        with cpu_process(tmp_path, args):
            watch = subprocess.Popen(
                command, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
            )
            lines = Lines(watch)
            first = lines.wait_for("cycle ")
            lines.wait_for("cycle ", first + 2)  # watching a while: it has heard the CPU
        # the CPU killed (cpu_process kills it at its end)
        gone = lines.wait_for("CPU cpu1 disconnected")
        time.sleep(1.0)
        assert watch.poll() is None  # still there, waiting
        (tmp_path / "bus.sock").unlink(missing_ok=True)  # a killed CPU leaves its socket
        with cpu_process(tmp_path, args[:-1]):  # started again (no --fresh)
            back = lines.wait_for("CPU cpu1 reachable", gone)
            lines.wait_for("cycle ", back)  # its values again
        watch.send_signal(signal.SIGINT)
        _, err = watch.communicate(timeout=30)
        assert watch.returncode == 0 and "Traceback" not in err, err
    finally:
        if watch is not None and watch.poll() is None:
            watch.kill()
            watch.wait(30)


CHART = """FUNCTION_BLOCK "Seq_wait"
  PARAMETERS := STANDARD;
SEQUENCE 1 "Line"
  INITIAL_STEP S1 "Ready": END_STEP
  STEP S2 "Run": N Q0.0; END_STEP
  TRANSITION T1 FROM S1 TO S2 := M0.0;
  TRANSITION T2 FROM S2 TO S1 := M0.1;
END_SEQUENCE
END_FUNCTION_BLOCK
"""


def _started(command: list[str], env: dict[str, str] | None = None) -> subprocess.Popen[str]:
    """``s7graph COMMAND`` as a real process (``env``: its environment, None: this one's)."""
    return subprocess.Popen(
        [sys.executable, "-m", "s7graph", *command],
        cwd=ROOT,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def test_watch_address_started_before_its_cpu_says_once_it_waits_and_shows_it_when_it_is_up(
    tmp_path: Path,
) -> None:
    socket = f"unixsock-stream/{tmp_path}/bus.sock"
    command = ["watch", "--connect", socket, "--address", "MW10:INT", "--interval-ms", "50"]
    watch = _started([*command, "--duration-s", "200"])
    try:
        said = Lines(watch, stderr=True)
        said.wait_for(f"s7graph: waiting for CPU cpu1 at {socket} (nothing answers there yet)")
        time.sleep(1.5)  # several tries meanwhile
        assert watch.poll() is None  # still there, waiting
        with cpu_process(tmp_path, [*_program(tmp_path), "--fresh"]):
            lines = Lines(watch)
            up = lines.wait_for("CPU cpu1 reachable")
            first = lines.wait_for("cycle ", up)  # its values
            lines.wait_for("cycle ", first + 1)  # watching a while
            watch.send_signal(signal.SIGINT)
            assert watch.wait(30) == 0
        err = said.rest()
        assert "Traceback" not in "\n".join(err), err
        assert err.count(err[0]) == 1 and err[0].startswith("s7graph: waiting")  # said once
    finally:
        if watch.poll() is None:
            watch.kill()
            watch.wait(30)


def test_watch_started_before_its_cpu_waits_then_follows_its_steps(tmp_path: Path) -> None:
    chart = tmp_path / "wait.s7g"
    chart.write_text(CHART, encoding="utf-8")
    watch = _started(["watch", *_bus(tmp_path), "--duration-s", "200"])
    try:
        said = Lines(watch, stderr=True)
        said.wait_for("s7graph: waiting for CPU cpu1 at unixsock-stream/")
        args = [str(chart), "--state", str(tmp_path / "s.sqlite"), "--duration-s", "110"]
        with cpu_process(tmp_path, args, fb="Seq_wait"):
            lines = Lines(watch)
            up = lines.wait_for("CPU cpu1 reachable")
            step = lines.wait_for("cycle ", up)
            assert "Seq_wait" in lines.seen[step] and "active S1" in lines.seen[step]
            time.sleep(1.0)  # following its steps a while (S1 stays: no more lines)
            watch.send_signal(signal.SIGINT)
            assert watch.wait(30) == 0
        err = said.rest()
        assert len(err) == 1 and "Traceback" not in err[0], err  # said once, nothing else
    finally:
        if watch.poll() is None:
            watch.kill()
            watch.wait(30)


def test_a_watch_whose_cpu_does_not_appear_within_duration_s_exits_2_saying_so(
    tmp_path: Path,
) -> None:
    socket = f"unixsock-stream/{tmp_path}/bus.sock"
    for how in ([], ["--address", "MW10:INT"]):
        started = time.monotonic()
        watch = _started(["watch", "--connect", socket, *how, "--duration-s", "1.5"])
        out, err = watch.communicate(timeout=60)
        assert watch.returncode == 2 and out == "", (how, out, err)
        assert err == (
            f"s7graph: waiting for CPU cpu1 at {socket} (nothing answers there yet)\n"
            f"s7graph: error: CPU cpu1 did not appear at {socket} within 1.5 s "
            "(--duration-s)\n"
        )
        assert time.monotonic() - started >= 1.5


def test_a_watch_given_no_connect_waits_until_its_cpu_writes_where_it_listens(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """No CPU line1 on this machine yet: the watch waits for its endpoint file
    (``web.bus.local``) and goes on once the CPU, started a second later, has written it."""
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    sides: list[CpuSide] = []
    later = threading.Timer(1.0, lambda: sides.append(CpuSide({}, cpu="line1")))
    later.start()
    try:
        with cpu_reached(NetOptions(cpu="line1"), 60) as reached:
            assert isinstance(reached, Reached), reached
            assert reached.waited and reached.status.cpu == "line1"
            assert reached.left_s is not None and 0 < reached.left_s < 59
    finally:
        later.join()
        for side in sides:
            side.close()
    assert capsys.readouterr().err == (
        "s7graph: waiting for CPU line1 at s7graph/line1 on this machine (no CPU line1 is on "
        "this machine's bus for this user yet)\n"
    )


def test_watch_address_with_user_logs_in_signs_its_requests_and_logs_out(
    tmp_path: Path, bus_certs: BusCerts
) -> None:
    """``--user``: the shell logs in (the password from S7GRAPH_PASSWORD), watches with
    requests signed by that login (the CPU keeps them in olga's own share:
    tests/web/bus/test_watch_proven_shares.py) and logs out at the end; a wrong password
    is exit 1, with the CPU's reason. A CPU with a users file on mutual TLS."""
    users = UsersFile(tmp_path / "users.json")
    users.add("olga", "viewer", PASSWORD, iterations=MIN_ITERATIONS)
    endpoint = f"tls/localhost:{free_port()}"
    run = ["run", *_program(tmp_path), "--fresh", "--users", str(users.path)]
    cpu = _started([*run, "--listen", endpoint, *bus_certs.args("cpu.cpu1")])
    command = [sys.executable, "-m", "s7graph", "watch", "--connect", endpoint, "--user", "olga"]
    command += [*bus_certs.args("client.olga"), "--address", "MW10:INT", "--interval-ms", "50"]
    command += ["--duration-s", "2"]
    env = {**os.environ, "S7GRAPH_PASSWORD": PASSWORD}
    try:
        Lines(cpu).wait_for("s7graph: CPU cpu1 on the bus")
        done = subprocess.run(command, cwd=ROOT, env=env, capture_output=True, text=True)
        assert done.returncode == 0 and done.stderr == "", done.stderr
        lines = done.stdout.splitlines()
        assert len(lines) > 2 and all(line.startswith("cycle ") for line in lines), lines
        env["S7GRAPH_PASSWORD"] = "not it"
        wrong = subprocess.run(command, cwd=ROOT, env=env, capture_output=True, text=True)
        assert wrong.returncode == 1 and wrong.stdout == ""
        assert wrong.stderr == "s7graph: error: login refused: wrong user name or password\n"
        with (
            open_session(connect=[endpoint], tls=bus_certs.tls("client.olga")) as session,
            BusClient(session, "cpu1") as client,
        ):
            audit = client.audit()
        assert audit is not None
        rows = [(e.user, e.op, e.outcome) for e in audit.entries if e.op in ("login", "logout")]
        assert rows == [
            ("olga", "login", "applied"),
            ("olga", "logout", "applied"),
            ("(unauthenticated)", "login", "refused"),
        ], rows
    finally:
        cpu.kill()
        cpu.wait(30)


def test_watch_address_with_user_goes_on_unsigned_once_a_cpu_started_again_ends_its_login(
    tmp_path: Path, bus_certs: BusCerts
) -> None:
    users = UsersFile(tmp_path / "users.json")
    users.add("olga", "viewer", PASSWORD, iterations=MIN_ITERATIONS)
    endpoint = f"tls/localhost:{free_port()}"
    run = ["run", *_program(tmp_path), "--users", str(users.path), "--listen", endpoint]
    run += bus_certs.args("cpu.cpu1")
    command = ["watch", "--connect", endpoint, "--user", "olga", *bus_certs.args("client.olga")]
    command += ["--address", "MW10:INT", "--interval-ms", "50", "--duration-s", "200"]
    procs = [_started([*run, "--fresh"])]
    try:
        Lines(procs[0]).wait_for("s7graph: CPU cpu1 on the bus")
        procs.append(_started(command, {**os.environ, "S7GRAPH_PASSWORD": PASSWORD}))
        watch, lines, said = procs[1], Lines(procs[1]), Lines(procs[1], stderr=True)
        first = lines.wait_for("cycle ")
        first = lines.wait_for("cycle ", first + 2)  # watching a while: it has heard the CPU
        procs[0].kill()  # the CPU, and the session olga's login was
        procs[0].wait(30)
        gone = lines.wait_for("CPU cpu1 disconnected", first)
        procs[0] = _started(run)  # started again: it knows no session of before
        Lines(procs[0]).wait_for("s7graph: CPU cpu1 on the bus")
        back = lines.wait_for("CPU cpu1 reachable", gone)
        lines.wait_for("cycle ", back)  # its values again, without the login
        said.wait_for(
            "s7graph: cpu1: watch refused: invalid token: log in again; watching without a "
            "login from now on"
        )
        watch.send_signal(signal.SIGINT)
        assert watch.wait(30) == 0
        assert len(said.rest()) == 1, said.seen  # said once, nothing else
    finally:
        for proc in procs:
            if proc.poll() is None:
                proc.kill()
                proc.wait(30)


def test_watch_user_without_address_is_a_usage_error_before_anything_is_joined() -> None:
    done = subprocess.run(
        [sys.executable, "-m", "s7graph", "watch", "--user", "olga", "--duration-s", "1"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert done.returncode == 2 and done.stdout == ""
    assert "--user signs --address's requests: an FB's steps need none" in done.stderr
    assert "waiting for CPU" not in done.stderr


def _local_cpu(
    tmp_path: Path, env: dict[str, str], chart: Path, cpu: str = "cpu1"
) -> subprocess.Popen[str]:
    """``s7graph run CHART --cpu CPU --web`` given no endpoint: a CPU of this machine on a
    socket of its own run, written to its endpoint file in ``env``'s XDG_RUNTIME_DIR;
    returned once it serves (its stdout read by a thread from then on)."""
    state = tmp_path / f"{cpu}.sqlite"
    args = ["run", str(chart), "--cpu", cpu, "--state", str(state), "--web", "--port", "0"]
    proc = _started([*args, "--duration-s", "150"], env)
    Lines(proc).wait_for("s7graph: view http")
    return proc


def test_watches_given_no_connect_rejoin_a_cpu_of_this_machine_started_again_on_a_new_socket(
    tmp_path: Path,
) -> None:
    """Killed (SIGKILL: its endpoint file left, naming a dead socket) or stopped (Ctrl-C: the
    file taken away), the CPU started again listens on a new socket and writes it: both
    watches, given no ``--connect``, read the file again while the CPU is gone, join there
    and show its lines again (``web.cli.rejoin``)."""
    runtime = tmp_path / "runtime"
    runtime.mkdir(mode=0o700)
    env = {**os.environ, "XDG_RUNTIME_DIR": str(runtime)}
    chart = tmp_path / "wait.s7g"
    chart.write_text(CHART, encoding="utf-8")
    endpoint = runtime / "s7graph" / "cpu1.endpoint"
    procs = [_local_cpu(tmp_path, env, chart)]
    try:
        sockets = [endpoint.read_text(encoding="utf-8")]
        address = ["--address", "Q0.0", "--interval-ms", "50"]
        for command in (["watch"], ["watch", *address]):
            procs.append(_started([*command, "--duration-s", "200"], env))
        watches = [(Lines(p), Lines(p, stderr=True)) for p in procs[1:]]
        seen = [lines.wait_for("cycle ") for lines, _ in watches]
        for how in (signal.SIGKILL, signal.SIGINT):
            procs[0].send_signal(how)
            assert procs[0].wait(30) in (-9, 0)
            gone = [
                lines.wait_for("CPU cpu1 disconnected", at)
                for (lines, _), at in zip(watches, seen, strict=True)
            ]
            procs[0] = _local_cpu(tmp_path, env, chart)
            sockets.append(endpoint.read_text(encoding="utf-8"))
            back = [
                lines.wait_for("CPU cpu1 reachable", at)
                for (lines, _), at in zip(watches, gone, strict=True)
            ]
            seen = [
                lines.wait_for("cycle ", at) for (lines, _), at in zip(watches, back, strict=True)
            ]
        assert len(set(sockets)) == 3  # each run on a socket of its own
        for proc in procs[1:]:
            proc.send_signal(signal.SIGINT)
        assert [proc.wait(30) for proc in procs[1:]] == [0, 0]
        assert watches[0][1].rest() == []  # nothing on stderr
        # a request on its way when the CPU was killed may be said to have no answer
        late = "s7graph: cpu1: no answer from CPU 'cpu1': the bus ended the request"
        assert all(line.startswith(late) for line in watches[1][1].rest()), watches[1][1].seen
    finally:
        for proc in procs:
            if proc.poll() is None:
                proc.kill()
                proc.wait(30)


def test_watch_address_with_a_login_that_joins_a_new_run_says_once_it_goes_on_unsigned(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A login does not outlive the CPU's run it was made at: the watch joined to a run
    started again (``web.cli.rejoin``) says so once and asks without it from then on."""
    with open_session(listen=[f"unixsock-stream/{tmp_path}/bus.sock"]) as session:
        before, after = BusClient(session, "cpu1"), BusClient(session, "cpu1")
        follower = _Follower(before, ["MW10"], WatchValues(), threading.Event(), "cpu1", "t")
        follower.rebind(before)  # the same run: the login stays
        assert follower.token == "t" and capsys.readouterr().err == ""
        follower.rebind(after)
        follower.rebind(after)
    assert follower.client is after and follower.token == ""
    assert capsys.readouterr().err == (
        "s7graph: cpu1: the login ended with the CPU's run; watching without a login from now on\n"
    )


def test_a_watch_s_first_look_and_its_rejoin_ask_the_cpu_the_same_way(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``rejoin.answer`` is the one status query of both: a CPU that answers gives its
    status, a name no CPU on the bus has gives None, within ``PROBE_S``."""
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    side = CpuSide({}, cpu="line1")
    try:
        with open_session(connect=[side.endpoint]) as session:
            status = answer(session, "line1")
            assert status is not None and status.cpu == "line1"
            asked = time.monotonic()
            assert answer(session, "line2") is None
            assert time.monotonic() - asked < PROBE_S + 1.0
    finally:
        side.close()
