"""The garbage collector of a real-time run (engine/runner.py ``IdleGc``): frozen after the
load, no automatic collection, collected in the idle part of the cycle only."""

from __future__ import annotations

import gc
import weakref
from collections.abc import Iterator

import pytest

from s7graph.engine import CallContext, Cpu, SystemClock, ob
from s7graph.engine.runner import IdleGc, Runner


class Node:
    """A reference cycle: only the collector frees it."""

    def __init__(self) -> None:
        self.me = self


def _garbage(n: int) -> weakref.ref[Node]:
    """``n`` cycles of garbage; a weak reference to the last one."""
    node = Node()
    for _ in range(n):
        node = Node()
    return weakref.ref(node)


@pytest.fixture
def idle_gc() -> Iterator[IdleGc]:
    collector = IdleGc(min_idle_s=0.002)
    collector.start()
    try:
        yield collector
    finally:
        collector.stop()


def test_start_freezes_the_load_and_stops_automatic_collection(idle_gc: IdleGc) -> None:
    assert not gc.isenabled()
    assert gc.get_freeze_count() > 0
    dead = _garbage(5 * gc.get_threshold()[0])  # far past the threshold: nobody collects
    assert dead() is not None


def test_idle_collects_only_when_due_and_there_is_time(idle_gc: IdleGc) -> None:
    gc.collect(0)
    assert not idle_gc.idle(1.0)  # nothing due
    dead = _garbage(2 * gc.get_threshold()[0])
    assert not idle_gc.idle(0.0005)  # due, but the next cycle starts too soon
    assert dead() is not None
    assert idle_gc.idle(0.008)
    assert dead() is None and idle_gc.collections[0] >= 1


def test_garbage_piled_up_is_collected_even_without_idle_time(idle_gc: IdleGc) -> None:
    dead = _garbage((IdleGc.OVERDUE + 1) * gc.get_threshold()[0])
    assert idle_gc.idle(0.0)
    assert dead() is None


def test_stop_gives_the_collector_back(idle_gc: IdleGc) -> None:
    idle_gc.stop()
    assert gc.isenabled() and gc.get_freeze_count() == 0
    idle_gc.stop()  # twice is harmless
    assert gc.isenabled()


@ob(1)
def litters(ctx: CallContext) -> None:
    for _ in range(200):
        Node()


@pytest.mark.timeout(30)
def test_a_run_collects_between_its_scans_and_restores_the_collector() -> None:
    cpu = Cpu(SystemClock())
    cpu.load(litters)
    seen: list[bool] = []
    runner = Runner(cpu, cycle_ms=10, on_record=lambda _: seen.append(gc.isenabled()))
    assert runner.gc is not None
    runner.startup()
    runner.run(duration_s=0.5)
    during = list(seen)
    runner.shutdown()
    assert during and not any(during)  # no automatic collection inside the loop
    assert runner.gc.collections[0] > 0  # the litter was collected in the idle time
    assert gc.isenabled()
