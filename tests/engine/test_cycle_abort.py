"""Cycle monitoring of a scan that never ends (engine/runner.py): a block still running at
twice the maximum cycle time is aborted and the CPU goes to STOP, naming it; SystemExit and
KeyboardInterrupt raised by a block are block errors, never a process exit.

The aborts need the real clock and threads (the monitor watches a scan that does not
return); the block errors run on the virtual clock."""

from __future__ import annotations

import threading
import time

import pytest

from s7graph.engine import CallContext, Cpu, CpuMode, EventId, InstanceDB, SystemClock, fb, ob
from s7graph.engine.clock import VirtualClock
from s7graph.engine.record import ScanRecord
from s7graph.engine.runner import Runner

MAX_MS = 100.0


class Hang:
    """What the hanging blocks below do, and when they started to."""

    def __init__(self) -> None:
        self.started = 0.0
        self.cycles = 0


hang = Hang()


@fb(7, "Spinner", STAT={"n": ("INT", 0)})
def spinner(ctx: CallContext, db: InstanceDB) -> None:
    hang.cycles += 1
    if hang.cycles == 3:
        hang.started = time.monotonic()
        while True:  # an endless loop in the program
            pass


@ob(1)
def calls_spinner(ctx: CallContext) -> None:
    ctx.call(spinner, 7)


@ob(1)
def sleeps(ctx: CallContext) -> None:
    hang.cycles += 1
    if hang.cycles == 3:
        hang.started = time.monotonic()
        time.sleep(60)


def _cpu(*blocks: object) -> Cpu:
    cpu = Cpu(SystemClock(), max_cycle_ms=MAX_MS)
    cpu.load(*blocks)  # type: ignore[arg-type]
    return cpu


def _run(cpu: Cpu, *, in_thread: bool = False) -> tuple[Runner, list[tuple[float, ScanRecord]]]:
    hang.__init__()  # type: ignore[misc]
    seen: list[tuple[float, ScanRecord]] = []
    runner = Runner(
        cpu, cycle_ms=5, end_on_stop=True, on_record=lambda r: seen.append((time.monotonic(), r))
    )
    runner.startup("warm")
    if in_thread:
        runner.start_thread(duration_s=20)
        runner.join(30)
    else:
        runner.run(duration_s=20)
    runner.shutdown()
    return runner, seen


@pytest.mark.timeout(60)
def test_a_block_in_an_endless_loop_is_aborted_and_the_cpu_stops_naming_it() -> None:
    """The FB loops for ever in its third call: at twice the maximum cycle time the scan
    is aborted, the CPU goes to STOP with a time error naming FB7, and the STOP is reported
    within 2 × maximum cycle time + 100 ms of the cycle's start."""
    cpu = _cpu(calls_spinner, spinner)
    cpu.create_instance_db(7, spinner)
    runner, seen = _run(cpu)
    assert cpu.mode is CpuMode.STOP
    aborted = [e for e in cpu.diagnostics if e.event_id == EventId.CYCLE_TIME_EXCEEDED]
    assert aborted and aborted[0].block == "FB7"
    assert "aborted: still running" in aborted[0].message
    assert cpu.stop_entry is not None and cpu.stop_entry.event_id == EventId.STOP_CYCLE_TIME
    assert "FB7: aborted" in runner.stopped
    stop_seen = next(t for t, r in seen if r.mode is CpuMode.STOP)
    assert stop_seen - hang.started <= (2 * MAX_MS + 100) / 1000


@pytest.mark.timeout(60)
def test_a_block_asleep_in_the_main_thread_is_woken_and_aborted() -> None:
    """A block sleeping 60 s (inside a C call, no bytecode to interrupt) is aborted too: the
    runner signals the main thread."""
    cpu = _cpu(sleeps)
    _run(cpu)
    assert cpu.mode is CpuMode.STOP
    assert [e.block for e in cpu.diagnostics if e.event_id == EventId.CYCLE_TIME_EXCEEDED] == [
        "OB1"
    ]
    assert time.monotonic() - hang.started < 30


@pytest.mark.timeout(60)
def test_a_scan_thread_other_than_main_is_aborted_by_an_asynchronous_exception() -> None:
    """Run in a thread of its own (a host that owns the main thread), the endless FB is
    aborted all the same."""
    cpu = _cpu(calls_spinner, spinner)
    cpu.create_instance_db(7, spinner)
    assert threading.current_thread() is threading.main_thread()
    runner, _ = _run(cpu, in_thread=True)
    assert cpu.mode is CpuMode.STOP and runner.aborts >= 1
    assert [e.block for e in cpu.diagnostics if e.event_id == EventId.CYCLE_TIME_EXCEEDED] == [
        "FB7"
    ]


# ---- SystemExit and KeyboardInterrupt in a block: block errors (virtual clock) ---------------

raised: list[BaseException] = []
handled: list[object] = []


@ob(1)
def exits(ctx: CallContext) -> None:
    raise raised[0]


@ob(121)
def programming_error(ctx: CallContext) -> None:
    handled.append(ctx.start_info["MESSAGE"])


@pytest.mark.parametrize("exc", [SystemExit(3), KeyboardInterrupt()])
def test_system_exit_or_keyboard_interrupt_in_a_block_stops_the_cpu_not_the_process(
    clock: VirtualClock, exc: BaseException
) -> None:
    raised[:] = [exc]
    cpu = Cpu(clock)
    cpu.load(exits)
    cpu.start()
    clock.advance(10)
    record = cpu.scan()  # returns: the process goes on
    assert record.mode is CpuMode.STOP
    assert [e.event_id for e in record.diagnostics] == [
        EventId.PYTHON_EXCEPTION,
        EventId.STOP_OB121_MISSING,
    ]
    assert record.diagnostics[0].message.startswith(type(exc).__name__)


def test_system_exit_in_a_block_calls_ob121_when_loaded(clock: VirtualClock) -> None:
    raised[:] = [SystemExit("bye")]
    handled.clear()
    cpu = Cpu(clock)
    cpu.load(exits, programming_error)
    cpu.start()
    clock.advance(10)
    assert cpu.scan().mode is CpuMode.RUN
    assert handled == ["SystemExit: bye"]
