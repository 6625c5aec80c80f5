"""The scan thread's priority (engine/runner.py): real-time while the loop runs where the
system allows it — the scan at ``rt_priority``, its monitor above, the process's other
threads below, taking turns with every thread of their priority (another CPU's helper busy
for seconds does not keep them from running) — and every thread back at the normal policy
afterwards."""

from __future__ import annotations

import os
import subprocess
import sys
import threading
import time

import pytest

from s7graph.engine import CallContext, Cpu, SystemClock, ob
from s7graph.engine.runner import HELPERS_BELOW, Runner, set_realtime
from s7graph.engine.switching import SWITCH_S
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
    assert seen["helper"] == (os.SCHED_RR, 40 - HELPERS_BELOW)  # helpers take turns
    me = threading.get_native_id()
    assert _policy(me) == (os.SCHED_OTHER, 0)  # back to normal afterwards


BUSY = """
import os, sys, time
from s7graph.engine.runner import set_realtime
os.sched_setaffinity(0, {int(sys.argv[1])})
assert set_realtime(int(sys.argv[2]), turns=True)
print("busy", flush=True)
end = time.monotonic() + 4.0
while time.monotonic() < end:
    pass
"""


@needs_realtime
@pytest.mark.timeout(60)
def test_a_helper_busy_in_another_process_does_not_keep_one_of_its_priority_waiting() -> None:
    core = max(os.sched_getaffinity(0))
    priority = 40 - HELPERS_BELOW
    other = subprocess.Popen(
        [sys.executable, "-c", BUSY, str(core), str(priority)], stdout=subprocess.PIPE, text=True
    )
    waited: list[float] = []

    def helper() -> None:  # a writer waking for commits, as the runner schedules helpers
        os.sched_setaffinity(0, {core})
        assert set_realtime(priority, turns=True)
        started = time.monotonic()
        for _ in range(5):
            time.sleep(0.01)
        waited.append(time.monotonic() - started)
        set_realtime(None)

    try:
        assert other.stdout is not None and other.stdout.readline() == "busy\n"
        thread = threading.Thread(target=helper)
        thread.start()
        thread.join(30)
    finally:
        other.kill()
        other.wait(30)
    assert waited and waited[0] < 2.0, waited  # ~0.5 s: a slice each; SCHED_FIFO: ~4 s


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


@pytest.mark.timeout(30)
def test_while_the_loop_runs_other_threads_get_the_interpreter_within_switch_s() -> None:
    cpu = Cpu(SystemClock())
    cpu.load(idle)
    seen: list[float] = []
    runner = Runner(
        cpu, cycle_ms=5, rt_priority=None, on_record=lambda _: seen.append(sys.getswitchinterval())
    )
    before = sys.getswitchinterval()
    runner.startup()
    runner.run(duration_s=0.1)
    runner.shutdown()
    loop = sorted(seen)[: len(seen) - 2]  # the start-up's and the last scan's aside
    assert len(loop) > 5 and max(loop) <= SWITCH_S < before
    assert sys.getswitchinterval() == before  # given back when the loop ends
