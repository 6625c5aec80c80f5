"""A STOP because the state file could not be written (engine/write_stop.py): its reason on
``on_stop`` at once and in the diagnostic buffer, naming the full disk and the file; the
entry written into the file at the end of the run when the file takes it again, so that the
next start reads why the last run stopped; said when it does not."""

from __future__ import annotations

import errno
import os
from pathlib import Path

import pytest

from s7graph.engine import CallContext, Cpu, CpuMode, EventId, SystemClock, ob
from s7graph.engine.diag_events import last_error_stop
from s7graph.engine.persistence import Batch, StateStore
from s7graph.engine.restart import error_blocker
from s7graph.engine.runner import Runner


@ob(1)
def counts(ctx: CallContext) -> None:
    ctx.mem.set("MW0", (int(ctx.mem.get("MW0")) + 1) % 30000)  # type: ignore[call-overload]


class FullDisk:
    """``StateStore.write`` failing with ENOSPC (the disk full) from its ``after``-th call on,
    ``times`` times (None: for good)."""

    def __init__(self, store: StateStore, *, after: int = 1, times: int | None = None) -> None:
        self.store = store
        self.write = store.write
        self.after = after
        self.times = times
        self.calls = 0
        self.failed = 0
        store.write = self  # type: ignore[method-assign]

    def __call__(self, batch: Batch) -> None:
        self.calls += 1
        if self.calls > self.after and (self.times is None or self.failed < self.times):
            self.failed += 1
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(self.store.path))
        self.write(batch)


@pytest.fixture
def state(tmp_path: Path) -> Path:
    return tmp_path / "s.sqlite"


def _run(path: Path, *, times: int | None) -> tuple[Runner, list[str]]:
    """A run whose second write meets a full disk (``times`` times); the reasons ``on_stop``
    heard while the loop ran."""
    store = StateStore(path)
    cpu = Cpu(SystemClock())
    cpu.load(counts)
    heard: list[str] = []
    runner = Runner(cpu, cycle_ms=5, store=store, rt_priority=None)
    runner.on_stop = heard.append
    runner.startup("warm")
    FullDisk(store, after=0, times=times)
    runner.run(duration_s=20)
    runner.shutdown()
    store.close()
    return runner, heard


@pytest.mark.timeout(60)
def test_a_full_disk_stops_the_cpu_naming_the_disk_and_the_file_at_once(state: Path) -> None:
    runner, heard = _run(state, times=None)
    why = f"the state file could not be written: disk full (No space left on device), {state}"
    assert heard == [why] and runner.stopped == why  # while the loop ran, not at its end
    assert runner.cpu.mode is CpuMode.STOP
    stop = runner.cpu.stop_entry
    assert stop is not None and (stop.event_id, stop.message) == (EventId.STOP_STATE_WRITE, why)
    assert error_blocker(why) in runner.cpu.hot_blockers


@pytest.mark.timeout(60)
def test_the_stop_a_full_disk_caused_is_read_back_once_the_file_takes_it(state: Path) -> None:
    runner, _ = _run(state, times=1)  # the disk has room again at the end of the run
    why = f"the state file could not be written: disk full (No space left on device), {state}"
    assert (
        runner.trace == f"the STOP is recorded in {state}: its next start says why the run stopped"
    )
    again = Cpu(SystemClock())
    again.load(counts)
    store = StateStore(state)
    report = store.load(again)
    store.close()
    assert report is not None and report.stopped == why and not report.clean
    assert error_blocker(why) in again.hot_blockers  # and only a warm restart, as before
    assert [e.message for e in again.diagnostics].count(why) == 1


@pytest.mark.timeout(60)
def test_a_disk_still_full_at_the_end_says_the_stop_is_not_recorded(state: Path) -> None:
    runner, heard = _run(state, times=None)
    assert heard and runner.trace == (
        f"the STOP could not be recorded in {state} either (No space left on device): its "
        "next start cannot say why the run stopped"
    )
    again = Cpu(SystemClock())
    again.load(counts)
    store = StateStore(state)
    report = store.load(again)
    store.close()
    assert report is not None and report.stopped == ""


def test_the_last_stop_by_an_error_is_the_reason_until_a_start_to_run(clock: object) -> None:
    cpu = Cpu(clock)  # type: ignore[arg-type]
    cpu.load(counts)
    cpu.start()
    cpu.stop_by_error(EventId.STOP_STATE_WRITE, "", "the state file could not be written: x")
    assert last_error_stop(cpu.diagnostics) == "the state file could not be written: x"
    cpu.start()
    assert last_error_stop(cpu.diagnostics) is None
    cpu.stop("by hand")
    assert last_error_stop(cpu.diagnostics) is None
