"""The scan thread's priority (engine/runner.py): real-time while the loop runs where the
system allows it — the scan at ``rt_priority``, its monitor above, the process's other
threads below — and every thread back at the normal policy afterwards."""

from __future__ import annotations

import os
import threading

import pytest

from s7graph.engine import CallContext, Cpu, SystemClock, ob
from s7graph.engine.runner import HELPERS_BELOW, Runner, set_realtime
from tests.engine.bystander import bystander


@ob(1)
def idle(ctx: CallContext) -> None:
    pass


def _policy(tid: int) -> tuple[int, int]:
    policy = os.sched_getscheduler(tid) & ~os.SCHED_RESET_ON_FORK
    return policy, os.sched_getparam(tid).sched_priority


def _allowed() -> bool:
    result: list[bool] = []
    probe = threading.Thread(target=lambda: result.append(set_realtime(1)))
    probe.start()
    probe.join()
    return result[0]


needs_realtime = pytest.mark.skipif(
    not hasattr(os, "sched_setscheduler") or not _allowed(),
    reason="the system refuses real-time scheduling here",
)


@needs_realtime
@pytest.mark.timeout(30)
def test_while_the_loop_runs_the_scan_is_real_time_above_its_helpers() -> None:
    cpu = Cpu(SystemClock())
    cpu.load(idle)
    seen: dict[str, tuple[int, int]] = {}

    def on_record(_: object) -> None:
        if runner.scans == 20 and "scan" not in seen:
            seen["scan"] = _policy(threading.get_native_id())
            seen["helper"] = _policy(helper)
            runner.stop()

    runner = Runner(cpu, cycle_ms=5, rt_priority=40, on_record=on_record)
    with bystander() as helper:
        runner.startup()
        try:
            runner.run(duration_s=10)
        finally:
            runner.shutdown()
    assert seen["scan"] == (os.SCHED_FIFO, 40)
    assert seen["helper"] == (os.SCHED_FIFO, 40 - HELPERS_BELOW)
    me = threading.get_native_id()
    assert _policy(me) == (os.SCHED_OTHER, 0)  # back to normal afterwards


@pytest.mark.timeout(30)
def test_without_a_priority_the_scan_keeps_the_normal_policy() -> None:
    cpu = Cpu(SystemClock())
    cpu.load(idle)
    seen: list[tuple[int, int]] = []
    runner = Runner(
        cpu,
        cycle_ms=5,
        rt_priority=None,
        on_record=lambda _: seen.append(_policy(threading.get_native_id())),
    )
    runner.startup()
    runner.run(duration_s=0.1)
    runner.shutdown()
    assert seen and set(seen) == {(os.SCHED_OTHER, 0)} and not runner.realtime


def test_a_priority_out_of_range_is_refused() -> None:
    with pytest.raises(ValueError, match=r"1\.\.98"):
        Runner(Cpu(SystemClock()), rt_priority=99)
