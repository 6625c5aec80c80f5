"""Synchronization over the bus (docs/bus.md, "Synchronization: sync"): ``fb/<fb>/sync``
judges every step of a real ``s7graph run`` process's FB at its next scan boundary; an
unknown FB gets no answer; an FB not yet called, or whose judgement fails, says why;
``s7graph sync`` prints it from a shell (docs/cli.md, "s7graph sync"); a flood of queries
is answered by one judgement at most every 0.2 s."""

from __future__ import annotations

import subprocess
import sys
import threading
from pathlib import Path

import pytest

from s7graph.engine.clock import VirtualClock
from s7graph.engine.cpu import Cpu
from s7graph.sequencer.fb import GraphFB, install_all
from s7graph.sequencer.sync import SyncStep
from s7graph.web.bus.client import BusClient
from s7graph.web.bus.live import LiveGraph
from s7graph.web.bus.protocol import SyncReport
from s7graph.web.bus.session import BusEnds, open_session
from s7graph.web.bus.sync import EVERY_NS, sync_report
from s7graph.web.harness.session import compile_text
from s7graph.web.wiring.live_edge import LiveEdge
from tests.web.helpers import chart_session, cpu_process, free_port, wait_until

pytestmark = pytest.mark.timeout(120)

# S1 → S2 at once (M0.0 always on), then S2 waits for M0.1; S2's interlock M1.0 holds
CHART = """FUNCTION_BLOCK "Seq_sync"
  PARAMETERS := STANDARD;
PERMANENT BEFORE
  M0.0 := TRUE;
  M1.0 := TRUE;
END_PERMANENT
SEQUENCE 1 "Line"
  INITIAL_STEP S1 "Ready": END_STEP
  STEP S2 "Clamp": INTERLOCK := M1.0; N Q0.0; END_STEP
  STEP S3 "Drill": N Q0.1; END_STEP
  TRANSITION T1 FROM S1 TO S2 := M0.0;
  TRANSITION T2 FROM S2 TO S3 := M0.1;
  TRANSITION T3 FROM S3 TO S1 := M0.2;
END_SEQUENCE
END_FUNCTION_BLOCK
"""


def test_sync_judges_every_step_of_a_running_cpu_at_its_next_scan_boundary(
    tmp_path: Path,
) -> None:
    path = tmp_path / "sync.s7g"
    path.write_text(CHART, encoding="utf-8")
    args = [str(path), "--state", str(tmp_path / "s.sqlite"), "--duration-s", "110"]
    with cpu_process(tmp_path, args, fb="Seq_sync", terminate=True) as (_, client, _):
        report = client.synchronization("Seq_sync", timeout=30)
        assert report.error == "" and report.fb == "Seq_sync" and report.state == "RUN"
        steps = {s.number: s for s in report.steps}
        assert list(steps) == [1, 2, 3]
        assert steps[1].done == [1] and not steps[1].fits
        assert steps[2].active and steps[2].interlock and steps[2].likely
        assert steps[2].name == "Clamp" and steps[2].sequence == 1
        assert steps[3].fits and not steps[3].entered and not steps[3].likely
        assert report.cycle > 0 and report.mode == "AUTO"
        unknown = client.synchronization("Nope", timeout=2)
        assert "no answer" in unknown.error and unknown.steps == []
        shell = _sync("--connect", f"unixsock-stream/{tmp_path}/bus.sock")
        assert shell.returncode == 0, shell.stderr
        lines = shell.stdout.splitlines()
        assert "Seq_sync on cpu1" in lines[0] and "2 of 3 steps fit" in lines[0]
        assert lines[1:] == [
            "S2 Clamp  seq 1  likely  active",
            "S3 Drill  seq 1  fits",
            "S1 Ready  seq 1  done (T1 holds)",
        ]
        wrong = _sync("--connect", f"unixsock-stream/{tmp_path}/bus.sock", "--fb", "Nope")
        assert wrong.returncode == 2 and "runs no FB 'Nope'; it runs Seq_sync" in wrong.stderr


def _sync(*args: str) -> subprocess.CompletedProcess[str]:
    """``s7graph sync ARGS`` as a shell runs it."""
    command = [sys.executable, "-m", "s7graph", "sync", *args]
    return subprocess.run(command, capture_output=True, text=True, timeout=60)


class _Failing(GraphFB):
    """An FB whose judgement fails inside (what no condition of today's language does)."""

    def synchronization(self) -> tuple[SyncStep, ...]:
        raise RuntimeError("a condition broke")


def _installed(kind: type[GraphFB]) -> tuple[GraphFB, Cpu]:
    """An FB of ``kind`` running ``CHART``, installed in a CPU not started."""
    cc, _ = compile_text(CHART, "sync.s7g")
    cpu = Cpu(VirtualClock())
    graph = kind(cc)
    install_all(cpu, [graph])
    return graph, cpu


def test_a_judgement_that_fails_inside_is_a_report_with_why_never_an_exception() -> None:
    graph, cpu = _installed(_Failing)
    report = sync_report(graph, "Seq_sync", cpu)
    assert report.error == (
        "Seq_sync: cannot judge the steps: an internal error in the CPU: a condition broke "
        "(please report it)"
    )


def test_an_fb_not_called_yet_is_not_judged_and_says_why() -> None:
    graph, cpu = _installed(GraphFB)
    report = sync_report(graph, "Seq_sync", cpu)
    assert report.steps == [] and "not called yet" in report.error
    assert isinstance(report, SyncReport)


def test_a_flood_of_queries_is_answered_by_one_judgement_at_most_every_0_2_s(
    tmp_path: Path,
) -> None:
    session, _, clock, store = chart_session(tmp_path, "sync.s7g", CHART)
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    live = LiveGraph(session.graph)
    now = [0]
    try:
        with (
            LiveEdge(
                live, serve=False, bus=True, cpu_of=session.cpu, ends=BusEnds(listen=[endpoint])
            ) as edge,
            open_session(connect=[endpoint]) as bus,
            BusClient(bus, "cpu1") as client,
        ):
            assert edge.sync is not None
            edge.sync.clock = lambda: now[0]
            session.start()

            def scan() -> None:
                clock.advance(10)
                edge.on_record(session.scan())

            def ask(n: int) -> list[SyncReport]:
                got: list[SyncReport] = []
                askers = [
                    threading.Thread(target=lambda: got.append(client.synchronization("Seq_sync")))
                    for _ in range(n)
                ]
                for asker in askers:
                    asker.start()
                assert wait_until(lambda: edge.sync is not None and edge.sync.waiting == n, 10)
                return got

            scan()
            answers = ask(10)
            now[0] = EVERY_NS  # the first judgement
            scan()
            assert wait_until(lambda: len(answers) == 10, 10)
            assert edge.sync.judged == 1 and all(a.steps and not a.error for a in answers)
            later = ask(3)
            now[0] += EVERY_NS // 2  # too soon: they wait
            scan()
            assert edge.sync.judged == 1 and edge.sync.waiting == 3 and later == []
            now[0] += EVERY_NS // 2
            scan()
            assert wait_until(lambda: len(later) == 3, 10) and edge.sync.judged == 2
    finally:
        store.close()
