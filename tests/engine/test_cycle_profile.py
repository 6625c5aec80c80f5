"""Where a cycle's time went (engine/profile.py, the runner's stamps): each phase of the
loop, the processor time, the time waited for a processor and blocked, and the long cycles
kept with their breakdowns."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable

import pytest

from s7graph.engine import CallContext, Cpu, SystemClock, ob
from s7graph.engine.modes import CpuMode
from s7graph.engine.profile import PHASE_NAMES, CycleProfile, OpenCycle, describe
from s7graph.engine.record import ScanRecord
from s7graph.engine.runner import Runner
from s7graph.engine.watchdog import Watchdog

_MS = 1_000_000


def _cycle(scan: int, stamps_ms: list[float], idle_ms: float) -> OpenCycle:
    stamps = [int(ms * _MS) for ms in stamps_ms]
    return OpenCycle(scan, 0, stamps, 5 * _MS, 1 * _MS, int(idle_ms * _MS), idle_ms == 0)


def test_a_cycle_is_split_into_the_phases_of_the_loop_and_the_late_start() -> None:
    # encode 0-0, scan 0-2, alarms 2-2.1, edge 2.1-3.1, stage 3.1-3.6, gc 3.6-3.6; asked
    # 6.4 idle; the next scan starts at 15 ms: 5 ms late
    open_cycle = _cycle(7, [0, 0, 2, 2.1, 3.1, 3.6, 3.6], idle_ms=6.4)
    cycle = open_cycle.close(15 * _MS, cpu_ns=8 * _MS, runq_ns=4 * _MS)
    assert cycle.scan == 7 and cycle.cycle_ns == 15 * _MS and not cycle.overrun
    ms = {name: round(ns / _MS, 3) for name, ns in zip(PHASE_NAMES, cycle.phases, strict=True)}
    assert ms == {
        "encode": 0,
        "scan": 2,
        "alarms": 0.1,
        "edge": 1,
        "stage": 0.5,
        "gc": 0,
        "idle": 6.4,
        "late": 5,
    }
    assert cycle.busy_ns == round(8.6 * _MS)  # all but the wait asked for
    assert cycle.cpu_ns == 3 * _MS and cycle.runq_ns == 3 * _MS
    assert cycle.blocked_ns == round(2.6 * _MS)  # neither ran nor waited for a processor
    assert cycle.describe() == (
        "15.0 ms: scan 2.0, alarms 0.1, edge 1.0, stage 0.5, late 5.0 "
        "(ran 3.0, waited for a processor 3.0, blocked 2.6)"
    )


def test_without_the_systems_figures_the_wait_is_not_guessed() -> None:
    open_cycle = OpenCycle(1, 0, [0, 0, 1, 1, 1, 1, 1], 0, None, 0, True)
    cycle = open_cycle.close(1 * _MS, cpu_ns=1 * _MS, runq_ns=None)
    assert cycle.overrun and cycle.runq_ns is None and cycle.blocked_ns is None
    assert "processor" not in cycle.parts() and "waited" not in cycle.describe()
    assert describe(3.0, {}) == "3.0 ms: nothing measured"


def test_the_profile_keeps_the_longest_cycle_and_the_last_long_ones() -> None:
    profile = CycleProfile(10 * _MS)
    lengths = [10, 11.9, 12.5, 10, 30, 10.2, 13]
    for scan, ms in enumerate(lengths, start=1):
        end = ms - 1
        profile.add(_cycle(scan, [0, 0, 1, 1, 1, 1, 1], end).close(int(ms * _MS), 0, 0))
    assert profile.count == 7
    assert profile.long == 3  # over 10 ms + 2 ms
    assert [c.scan for c in profile.recent] == [3, 5, 7]
    assert profile.longest is not None and profile.longest.scan == 5
    assert profile.longest_ns("scan") == 1 * _MS and profile.mean_ns("scan") == 1 * _MS
    assert [c.scan for c in profile.since(4)] == [5, 7]


@ob(1)
def idle(ctx: CallContext) -> None:
    pass


def runner_with(after_scan: dict[int, Callable[[], object]]) -> Runner:
    """A 10 ms runner of an empty OB1 that runs ``after_scan[n]`` after scan ``n``."""
    cpu = Cpu(SystemClock())
    cpu.load(idle)
    runner = Runner(cpu, cycle_ms=10.0, idle_gc=False, rt_priority=None)

    def on_record(record: ScanRecord) -> None:
        action = after_scan.get(runner.scans)
        if action is not None:
            action()

    runner.on_record = on_record
    runner.startup()
    return runner


def spin(seconds: float) -> None:
    """Compute for ``seconds`` of this thread's processor time (not wall time: on a
    virtual machine, time the host takes away is neither run nor waited for)."""
    end = time.thread_time() + seconds
    while time.thread_time() < end:
        pass


@pytest.mark.timeout(30)
def test_a_cycle_that_computes_long_after_the_scan_is_put_down_to_the_edge_and_cpu() -> None:
    runner = runner_with({5: lambda: spin(0.015)})
    runner.run(duration_s=0.2)
    (long,) = [c for c in runner.profile.recent if c.scan == 5]
    assert long.overrun and long.cycle_ns >= 15 * _MS
    assert long.phase("edge") >= 15 * _MS  # where the time went
    assert long.phase("scan") < long.phase("edge")
    if long.runq_ns is not None:  # Linux: it ran, or waited for a processor to run
        assert long.cpu_ns + long.runq_ns >= 12 * _MS
    assert runner.overruns >= 1 and runner.profile.long >= 1


@pytest.mark.timeout(30)
def test_a_cycle_that_waits_on_a_lock_is_put_down_as_blocked() -> None:
    held = threading.Event()
    runner = runner_with({5: lambda: held.wait(0.015)})
    runner.run(duration_s=0.2)
    (long,) = [c for c in runner.profile.recent if c.scan == 5]
    assert long.phase("edge") >= 15 * _MS
    if long.blocked_ns is not None:
        assert long.blocked_ns >= 12 * _MS
        assert long.cpu_ns < 5 * _MS


@pytest.mark.timeout(30)
def test_a_stop_by_the_cycle_time_says_where_that_cycles_time_went() -> None:
    runner = runner_with({5: lambda: spin(0.080)})
    runner.cpu.watchdog = Watchdog(max_cycle_ms=50)  # no OB80: STOP at once
    runner.run(duration_s=1.0)
    assert runner.cpu.mode is CpuMode.STOP
    reason, went = runner.stopped.split("; where the cycle's time went: ")
    assert "cycle time" in reason and "exceeds 50 ms" in reason
    (long,) = [c for c in runner.profile.recent if c.scan == 5]
    assert went == long.describe() and long.phase("edge") >= 80 * _MS
    assert f"edge {long.phase('edge') / _MS:.1f}" in went  # the phase that took it, in ms


@pytest.mark.timeout(30)
def test_a_stop_of_another_cause_has_no_cycle_breakdown() -> None:
    runner = runner_with({5: lambda: runner.cpu.stop("STP")})
    runner.run(duration_s=0.5)
    assert runner.cpu.mode is CpuMode.STOP
    assert runner.stopped and "where the cycle" not in runner.stopped
