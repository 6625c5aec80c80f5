"""``s7graph run CHART --web``: the CPU in one process, the browser view in another
(web/cli/view_process.py). Real processes: the drill demo with its plant, its view as a
child ``s7graph web``; the view killed is restarted while the CPU scans on, a Ctrl-C stops
both with one line each, and a CPU killed takes its view with it."""

from __future__ import annotations

import ctypes
import os
import queue
import re
import signal
import subprocess
import sys
import threading
import time
import urllib.request
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

from s7graph.engine.cores import machine_claims
from s7graph.engine.runner import PR_SET_THP_DISABLE, RT_PRIORITY, realtime_allowed
from s7graph.web.bus.client import BusClient
from s7graph.web.bus.protocol import CpuStatus
from s7graph.web.bus.session import open_session
from s7graph.web.cli.view_process import view_endpoints
from tests.paths import ROOT
from tests.web.helpers import free_port, wait_until

pytestmark = pytest.mark.timeout(180)
DRILL = ROOT / "examples" / "drill"
CYCLE_MS = 10  # s7graph run's default cycle


def _as_from_a_shell() -> None:
    """In the child before it runs s7graph: huge pages allowed again, as a shell starts it
    (this test process may have kept small pages itself, and children inherit that)."""
    ctypes.CDLL(None).prctl(PR_SET_THP_DISABLE, 0, 0, 0, 0)


def _children(parent: int) -> list[int]:
    pids: list[int] = []
    for task in Path(f"/proc/{parent}/task").iterdir():
        with open(task / "children") as f:
            pids += [int(p) for p in f.read().split()]
    return pids


def _cmdline(pid: int) -> list[str]:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes().decode().split("\0")
    except OSError:  # ended meanwhile
        return []


class Run:
    """``s7graph run`` of the drill demo with ``--web``, in a session of its own (so that a
    signal to its process group is what a Ctrl-C at its terminal sends)."""

    def __init__(self, tmp_path: Path, *extra: str) -> None:
        self.port = free_port()
        self.proc = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "s7graph",
                "run",
                str(DRILL / "drill.s7g"),
                "--symbols",
                str(DRILL / "symbols.txt"),
                "--plant",
                str(DRILL / "demo_plant.py"),
                "--state",
                str(tmp_path / "drill.sqlite"),
                "--web",
                "--port",
                str(self.port),
                "--duration-s",
                "150",
                # the processes are tested, not the watchdog: a loaded CI machine's slow
                # scan must not stop the CPU on a time error
                "--max-cycle-ms",
                "5000",
                *extra,
            ],
            cwd=ROOT,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            start_new_session=True,
            preexec_fn=_as_from_a_shell,
        )
        self.out: queue.Queue[str] = queue.Queue()
        self.err: list[str] = []
        assert self.proc.stdout is not None and self.proc.stderr is not None
        out, err = self.proc.stdout, self.proc.stderr
        threading.Thread(target=lambda: [self.out.put(x) for x in out], daemon=True).start()
        threading.Thread(target=lambda: [self.err.append(x) for x in err], daemon=True).start()

    def view_line(self, timeout: float = 60) -> re.Match[str]:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            try:
                found = re.search(r"view (\S+) \(bus (\S+)\)", self.out.get(timeout=0.5))
            except queue.Empty:
                assert self.proc.poll() is None, "".join(self.err)
                continue
            if found:
                return found
        raise AssertionError(f"no view line; stderr: {''.join(self.err)}")

    @property
    def cpu(self) -> int:
        """The CPU's process: the child of ``s7graph run``, its supervisor."""
        (pid,) = _children(self.proc.pid)
        return pid

    def children(self) -> list[int]:
        """The view processes the CPU started (not its compiler process)."""
        return [pid for pid in _children(self.cpu) if "--child" in _cmdline(pid)]

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
        self.proc.wait(30)


@pytest.fixture
def run(tmp_path: Path) -> Iterator[Run]:
    r = Run(tmp_path)
    try:
        yield r
    finally:
        for pid in _children(r.cpu) if r.proc.poll() is None else []:
            os.kill(pid, signal.SIGKILL)
        r.stop()


def _serves(url: str) -> bool:
    try:
        with urllib.request.urlopen(url, timeout=5) as page:
            return page.status == 200 and b"<html" in page.read(2000).lower()
    except OSError:
        return False


def _alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().split(") ", 1)[1][0] != "Z"
    except FileNotFoundError:
        return False


def test_the_view_killed_is_restarted_while_the_cpu_scans_on(run: Run) -> None:
    url, endpoint = run.view_line().groups()
    assert url == f"http://127.0.0.1:{run.port}/" and _serves(url)
    (view,) = run.children()
    with open_session(connect=[endpoint]) as session:
        client = BusClient(session, "cpu1")

        def status() -> CpuStatus:
            got = client.status()
            assert got is not None and got.stats is not None
            return got

        before = status()
        assert before.state == "RUN"
        os.kill(view, signal.SIGKILL)
        assert wait_until(lambda: any("view process ended" in x for x in run.err), 30)
        line = next(x for x in run.err if "view process ended" in x)
        assert line == "s7graph: the view process ended (killed by SIGKILL); restarting it in 1 s\n"
        assert wait_until(lambda: run.children() not in ([], [view]), 30)
        assert wait_until(lambda: _serves(url), 60)  # the same page again, a new process
        after = status()
        client.close()
    assert after.state == "RUN" and after.cycle > before.cycle
    # The CPU scanned on at its 10 ms cycle while its view was dead and restarted: no scan
    # waited for the view (one that did would lose its cycles for as long). Not "no
    # overrun": a cycle the machine itself made late (a new process starting on two
    # processors) is the machine's, and bench/jitter.py is where those are counted.
    scanned_ms = (after.cycle - before.cycle) * CYCLE_MS
    assert scanned_ms >= 0.9 * (after.t_ms - before.t_ms)
    assert "Traceback" not in "".join(run.err)


def test_ctrl_c_stops_the_cpu_and_its_view_with_one_line_each(run: Run) -> None:
    url, _ = run.view_line().groups()
    (view,) = run.children()
    os.killpg(run.proc.pid, signal.SIGINT)  # what the terminal sends its foreground group
    assert run.proc.wait(30) == 0, run.err
    assert wait_until(lambda: not _alive(view), 30)
    assert not _serves(url)
    assert wait_until(lambda: len(run.err) >= 3, 10)
    start, *stopped = run.err
    assert "drill.s7g (Seq_drill) in RUN" in start
    assert sorted(stopped) == sorted(
        [
            "s7graph: view stopped\n",
            f"s7graph: drill.s7g (Seq_drill) stopped (state saved in {run_state(run)})\n",
        ]
    )


def run_state(run: Run) -> str:
    return str(run.proc.args[run.proc.args.index("--state") + 1])  # type: ignore[union-attr]


def _thp(pid: int) -> str:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("THP_enabled:"):
            return line.split()[1]
    pytest.skip("this kernel does not say whether a process may use huge pages")


def test_the_cpu_and_its_view_keep_their_memory_out_of_huge_pages(run: Run) -> None:
    """The kernel merging a process's pages into huge ones held scans up for milliseconds
    (engine.runner.keep_small_pages): the CPU process and the view it starts are kept out."""
    run.view_line()
    (view,) = run.children()
    assert (_thp(run.cpu), _thp(view)) == ("0", "0")


def _cpus(tid: int) -> set[int]:
    return set(os.sched_getaffinity(tid))


@pytest.mark.skipif(len(os.sched_getaffinity(0)) < 2, reason="one processor: none to keep")
def test_the_scan_keeps_its_processor_and_the_bus_and_the_view_run_on_the_others(
    tmp_path: Path,
) -> None:
    """``--core N`` (engine/cores.py): the scan thread (the CPU process's main thread) on
    processor N, with the state writer's encoder, which works while the scan sleeps; the
    process's other threads (bus, writer, monitor) and the view's process on the rest."""
    allowed = _cpus(0)
    core = max(allowed)
    run = Run(tmp_path, "--core", str(core))
    try:
        run.view_line()
        (view,) = run.children()
        pid = run.cpu
        rest = allowed - {core}

        def placed() -> bool:
            threads = [int(t) for t in os.listdir(f"/proc/{pid}/task") if int(t) != pid]
            on = [_cpus(t) for t in threads]  # one on the core: the encoder
            return _cpus(pid) == {core} and on.count({core}) == 1 == len(on) - on.count(rest)

        assert wait_until(placed, 30), run.err
        assert _cpus(view) == rest
    finally:
        for pid in run.children() if run.proc.poll() is None else []:
            os.kill(pid, signal.SIGKILL)
        run.stop()


@contextmanager
def _beside_a_real_time_cpu(tmp_path: Path) -> Iterator[tuple[Run, int, list[Run]]]:
    """A first CPU (``--core auto``) on the processor it keeps (yielded), and a list for the
    CPUs a test starts beside it (``tmp_path / "b"`` is there for one); all stopped at the
    end. Skipped where the scan cannot run real-time: ``auto`` keeps nothing there."""
    if not realtime_allowed(RT_PRIORITY):
        pytest.skip("the scan cannot run real-time here: auto keeps no processor")
    for name in ("a", "b"):
        (tmp_path / name).mkdir()
    first = Run(tmp_path / "a")
    more: list[Run] = []
    try:
        first.view_line()
        assert wait_until(lambda: len(_cpus(first.cpu)) == 1, 30), first.err
        (kept,) = _cpus(first.cpu)
        yield first, kept, more
    finally:
        for run in (first, *more):
            run.stop()


@pytest.mark.skipif(len(os.sched_getaffinity(0)) < 2, reason="one processor: none to keep")
def test_two_cpus_on_one_machine_never_keep_the_same_processor(tmp_path: Path) -> None:
    """``--core auto`` (engine/cores.py): a second CPU leaves the processor the first
    keeps — both scan threads real-time at one priority on one processor, a scan of one
    hanging in C code would keep the other's from running at all."""
    with _beside_a_real_time_cpu(tmp_path) as (first, kept, more):
        second = Run(tmp_path / "b")
        more.append(second)
        found = second.view_line()
        with open_session(connect=[found[2]]) as session:
            client = BusClient(session, "cpu1")
            assert wait_until(lambda: (s := client.status()) is not None and s.cycle > 5, 30)
            stats = client.status().stats  # type: ignore[union-attr]
            assert stats is not None and stats.priority == RT_PRIORITY and stats.core != kept
        assert _cpus(first.cpu) == {kept}
        assert kept not in _cpus(second.cpu) or len(_cpus(second.cpu)) > 1
        assert machine_claims().holder(kept) == first.cpu


@pytest.mark.skipif(len(os.sched_getaffinity(0)) < 2, reason="one processor: none to keep")
def test_a_cpu_given_a_processor_keeps_its_threads_off_the_one_another_cpu_keeps(
    tmp_path: Path,
) -> None:
    """``--core N`` beside a CPU that keeps another processor (engine/cores.py): the bus,
    the view and the writer stay off that one — a scan of the other CPU hanging in C code
    would keep them from running — and share the scan's own when no other is left."""
    with _beside_a_real_time_cpu(tmp_path) as (_, kept, more):
        mine = min(_cpus(0) - {kept})
        second = Run(tmp_path / "b", "--core", str(mine))
        more.append(second)
        second.view_line()
        (view,) = second.children()
        pid = second.cpu

        def off_the_other() -> bool:
            threads = [int(t) for t in os.listdir(f"/proc/{pid}/task")]
            return _cpus(pid) == {mine} and all(kept not in _cpus(t) for t in threads)

        assert wait_until(off_the_other, 30), second.err
        assert kept not in _cpus(view)


def test_a_processor_that_is_not_there_is_refused_naming_the_option(tmp_path: Path) -> None:
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "s7graph",
            "run",
            str(DRILL / "drill.s7g"),
            "--symbols",
            str(DRILL / "symbols.txt"),
            "--state",
            str(tmp_path / "d.sqlite"),
            "--duration-s",
            "1",
            "--core",
            "4096",
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=60,
    )
    there = ", ".join(map(str, sorted(_cpus(0))))
    assert proc.returncode == 2
    assert proc.stderr == (
        f"s7graph: error: --core: core 4096 is not a processor this process may use ({there})\n"
    )
    assert not (tmp_path / "d.sqlite").exists()  # refused before anything was opened


def test_a_cpu_killed_takes_its_view_with_it(run: Run) -> None:
    url, _ = run.view_line().groups()
    (view,) = run.children()
    run.proc.kill()
    run.proc.wait(30)
    assert wait_until(lambda: not _alive(view), 30)  # its stdin closed: it ended by itself
    assert wait_until(lambda: not _serves(url), 10)


def test_the_view_joins_the_bus_where_the_cpu_is() -> None:
    assert view_endpoints(["tcp/0.0.0.0:7447"], []) == ["tcp/127.0.0.1:7447"]
    assert view_endpoints(["tcp/[::]:7447", "tcp/10.0.0.1:7447"], []) == ["tcp/[::1]:7447"]
    assert view_endpoints(["unixsock-stream//tmp/x/bus.sock"], []) == [
        "unixsock-stream//tmp/x/bus.sock"
    ]
    assert view_endpoints([], ["tcp/router:7447", "tcp/backup:7447"]) == [
        "tcp/router:7447",
        "tcp/backup:7447",
    ]
