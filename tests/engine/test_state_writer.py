"""The state file's writer (engine/writer.py): committed off the scan thread, written only
when something changed, durable marks for the command path, a foreign lock waited out and
a full disk reported with its own error."""

from __future__ import annotations

import contextlib
import sqlite3
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from s7graph.engine import (
    CallContext,
    Cpu,
    CpuMode,
    EventId,
    InstanceDB,
    SystemClock,
    VirtualClock,
    fb,
    ob,
)
from s7graph.engine.persistence import StateStore
from s7graph.engine.runner import Runner
from s7graph.engine.writer import StoreWriter


@ob(1)
def counts(ctx: CallContext) -> None:
    ctx.mem.set("MW0", (int(ctx.mem.get("MW0")) + 1) % 30000)  # type: ignore[call-overload]


@ob(1)
def idle(ctx: CallContext) -> None:
    pass


def _cpu(clock: object, body: object = idle) -> Cpu:
    cpu = Cpu(clock)  # type: ignore[arg-type]
    cpu.load(body)  # type: ignore[arg-type]
    cpu.start()
    return cpu


def test_a_scan_that_changed_nothing_stages_nothing(clock: VirtualClock, tmp_path: Path) -> None:
    store = StateStore(tmp_path / "s.sqlite")
    cpu = _cpu(clock)
    store.save(cpu)
    for _ in range(5):
        clock.advance(10)
        cpu.scan()
        assert store.stage(cpu) is None
    cpu.mem.set("MW0", 7)  # retentive
    batch = store.stage(cpu)
    assert batch is not None and list(batch.meta) == ["memory"]


def test_a_change_is_durable_once_its_scan_is_committed(
    clock: VirtualClock, tmp_path: Path
) -> None:
    """``when_durable(mark, fn)``: fn(None) once the batch of scan ``mark`` is committed;
    a scan that changed nothing is durable as soon as everything before it is."""
    store = StateStore(tmp_path / "s.sqlite")
    cpu = _cpu(clock, counts)
    store.save(cpu)
    writer = StoreWriter(store)
    calls: list[tuple[int, str | None]] = []
    try:
        for mark in (1, 2, 3):
            clock.advance(10)
            cpu.scan()
            writer.submit(store.stage(cpu, upto=mark), mark)
        writer.when_durable(3, lambda error: calls.append((3, error)))
        assert writer.wait(3, timeout=10)
        assert writer.next_mark() == 4
        writer.submit(None, 4)  # nothing changed in scan 4
        writer.when_durable(4, lambda error: calls.append((4, error)))
        assert writer.wait(4, timeout=10)
    finally:
        writer.close()
    assert calls == [(3, None), (4, None)]
    assert StateStore(tmp_path / "s.sqlite").meta("memory") == store.meta("memory")


def test_a_foreign_lock_holds_up_the_writer_never_the_scan(
    clock: VirtualClock, tmp_path: Path
) -> None:
    """Another connection holds the write lock: submissions go on (and merge), nothing is
    committed; once the lock is released the writer catches up with the latest state."""
    path = tmp_path / "s.sqlite"
    store = StateStore(path)
    cpu = _cpu(clock, counts)
    store.save(cpu)
    writer = StoreWriter(store)
    foreign = sqlite3.connect(path, isolation_level=None)
    try:
        foreign.execute("BEGIN IMMEDIATE")
        for mark in range(1, 201):
            clock.advance(10)
            cpu.scan()
            writer.submit(store.stage(cpu, upto=mark), mark)  # never waits on the lock
        assert writer.committed == 0 and writer.error is None
        foreign.execute("ROLLBACK")
        assert writer.wait(200, timeout=30)
    finally:
        foreign.close()
        writer.close()
    assert writer.commits < 200  # the scans that waited were committed together
    again = Cpu(VirtualClock())
    again.load(counts)
    assert StateStore(path).load(again)
    assert again.mem.get("MW0") == cpu.mem.get("MW0") == 200


def test_appended_rows_commit_with_the_next_scans_state(
    clock: VirtualClock, tmp_path: Path
) -> None:
    """``append`` (the audit of the bus gate): while a writer runs, a row waits for the next
    ``stage`` and commits in that scan's transaction; without one the caller writes it."""
    path = tmp_path / "s.sqlite"
    store = StateStore(path)
    cpu = _cpu(clock, counts)
    store.save(cpu)
    columns = ("t_ns", "user", "action", "detail")
    assert not store.append("audit", columns, (1, "ann", "ack", "before"))  # no writer
    with pytest.raises(ValueError, match="cannot append to meta"):
        store.append("meta", ("key", "value"), ("x", "y"))
    writer = StoreWriter(store)
    try:
        assert store.append("audit", columns, (2, "ann", "ack", "queued"))
        assert [r["detail"] for r in store.audit()] == []  # not written by append
        clock.advance(10)
        cpu.scan()
        batch = store.stage(cpu, upto=1)
        assert batch is not None and batch.appended and batch.meta  # the row with the state
        writer.submit(batch, 1)
        assert writer.wait(1, timeout=10)
    finally:
        writer.close()
    assert [r["detail"] for r in StateStore(path).audit()] == ["queued"]


def _fill_up(store: StateStore) -> None:
    """Make the file full: no page more may be added (SQLITE_FULL, as on a full disk)."""
    pages = store._db.execute("PRAGMA page_count").fetchone()[0]
    store._db.execute(f"PRAGMA max_page_count={pages + 1}")


def test_a_full_disk_is_reported_with_its_own_error_and_waiters_hear_of_it(
    clock: VirtualClock, tmp_path: Path
) -> None:
    store = StateStore(tmp_path / "s.sqlite")
    cpu = _cpu(clock)
    store.save(cpu)
    _fill_up(store)
    writer = StoreWriter(store)
    heard: list[str | None] = []
    try:
        for mark in range(1, 400):
            store.log_audit(mark, "ann", "ack", "x" * 500)  # rows the file has no room for
            clock.advance(10)
            cpu.scan()
            writer.submit(store.stage(cpu, upto=mark), mark)
            if writer.error is not None:
                break
        writer.when_durable(10_000, heard.append)
        writer.flush(10)
    finally:
        writer.close()
    assert writer.error is not None
    assert "database or disk is full" in str(writer.error)
    assert heard and heard[0] is not None and "database or disk is full" in heard[0]


@pytest.mark.timeout(60)
def test_a_run_whose_state_cannot_be_written_stops_the_cpu_naming_the_error(
    tmp_path: Path,
) -> None:
    store = StateStore(tmp_path / "s.sqlite")
    cpu = Cpu(SystemClock())
    cpu.load(counts)
    for n in range(16):  # retentive markers change every scan
        cpu.mem.set(f"MB{n}", n)
    runner = Runner(cpu, cycle_ms=5, store=store)
    runner.startup("warm")
    _fill_up(store)
    store.log_audit(0, "ann", "ack", "y" * 4000)
    done = threading.Event()
    runner.run(duration_s=20)
    done.set()
    runner.shutdown()
    assert runner.write_error is not None
    assert "database or disk is full" in runner.write_error.problem
    assert cpu.mode is CpuMode.STOP
    assert any(
        e.event_id == EventId.STOP_STATE_WRITE and "database or disk is full" in e.message
        for e in cpu.diagnostics
    )


# ---- the instance DBs encoded in the idle part of the cycle -------------------------------


@fb(7, STAT={"total": ("DINT", 0)})
def tally(ctx: CallContext, db: InstanceDB) -> None:
    db.total = int(db.total) + 1  # type: ignore[call-overload]


@ob(1)
def calls_tally(ctx: CallContext) -> None:
    for number in (7, 8, 9):
        ctx.call(tally, number)


def _tallies(clock: object) -> Cpu:
    cpu = Cpu(clock)  # type: ignore[arg-type]
    cpu.load(calls_tally, tally)
    for number in (7, 8, 9):
        cpu.create_instance_db(number, tally)
    cpu.start()
    return cpu


@contextlib.contextmanager
def _writing(clock: VirtualClock, path: Path) -> Iterator[tuple[Cpu, StateStore, StoreWriter]]:
    """Three tallies saved in a fresh file, and a writer for it (closed at the end)."""
    store = StateStore(path)
    cpu = _tallies(clock)
    store.save(cpu)
    writer = StoreWriter(store)
    try:
        yield cpu, store, writer
    finally:
        writer.close()


def _totals(path: Path) -> dict[int, object]:
    store = StateStore(path)
    try:
        return {n: store.instance_state(n)["total"] for n in (7, 8, 9)}  # type: ignore[index]
    finally:
        store.close()


def test_a_deferred_staging_is_encoded_by_the_writer_while_the_scan_thread_idles(
    clock: VirtualClock, tmp_path: Path
) -> None:
    """``stage(defer=True)`` leaves the instance DBs to the writer, which encodes them
    before ``until`` and commits them as ``stage`` would have: the scan thread's
    ``finish`` then finds nothing left."""
    with _writing(clock, tmp_path / "s.sqlite") as (cpu, store, writer):
        clock.advance(10)
        cpu.scan()
        batch = store.stage(cpu, upto=1, defer=True)
        assert batch is not None and [n for n, _ in batch.unencoded] == [7, 8, 9]
        assert not batch.instances  # nothing encoded in the scan thread
        writer.submit(batch, 1, until=time.monotonic() + 60)
        assert writer.wait(1, timeout=10)
        assert writer.finish() == 0
    assert writer.encoded_here == 3 and writer.encoded_late == 0
    assert _totals(tmp_path / "s.sqlite") == {7: 1, 8: 1, 9: 1}


def test_a_staging_not_encoded_by_its_next_scan_is_carried_under_that_scans_staging(
    clock: VirtualClock, tmp_path: Path
) -> None:
    """The deadline passed (or the encoder was held up): the next scan starts at once, and
    what was encoded lies under its staging, which stages every instance DB again; scan 1
    is not durable on its own. The next staging in a row not encoded by its scan is
    encoded by the scan thread, so its rows hold that scan's state, not the one after."""
    with _writing(clock, tmp_path / "s.sqlite") as (cpu, store, writer):
        clock.advance(10)
        cpu.scan()
        writer.submit(store.stage(cpu, upto=1, defer=True), 1, until=time.monotonic() - 1)
        assert writer.finish() == 0 and writer.carried == 1  # the scan need not wait
        assert not writer.wait(1, timeout=0.2)  # nothing committed of it on its own
        clock.advance(10)
        cpu.scan()  # scan 2 changes every instance DB
        writer.submit(store.stage(cpu, upto=2, defer=True), 2, until=time.monotonic() - 1)
        assert writer.finish() == 3  # the second in a row: encoded here, before the scan
        clock.advance(10)
        cpu.scan()  # scan 3, after the rows were encoded
        assert writer.wait(2, timeout=10)
    assert writer.encoded_here == 0 and writer.encoded_late == 3 and writer.carried == 1
    assert _totals(tmp_path / "s.sqlite") == {7: 2, 8: 2, 9: 2}  # scan 2's, not scan 3's


def test_at_the_end_of_the_loop_a_carried_staging_is_encoded_not_lost(
    clock: VirtualClock, tmp_path: Path
) -> None:
    """``finish(carry=False)``: no scan follows, so a carried staging (its state unchanged
    since) is encoded now and committed."""
    with _writing(clock, tmp_path / "s.sqlite") as (cpu, store, writer):
        clock.advance(10)
        cpu.scan()
        writer.submit(store.stage(cpu, upto=1, defer=True), 1, until=time.monotonic() - 1)
        assert writer.finish() == 0 and writer.carried == 1
        assert writer.finish(carry=False) == 3
        assert writer.wait(1, timeout=10)
    assert _totals(tmp_path / "s.sqlite") == {7: 1, 8: 1, 9: 1}


def test_a_deferred_staging_that_changed_nothing_is_durable_once_encoded(
    clock: VirtualClock, tmp_path: Path
) -> None:
    with _writing(clock, tmp_path / "s.sqlite") as (cpu, store, writer):
        batch = store.stage(cpu, upto=1, defer=True)  # no scan since the save: unchanged
        assert batch is not None and batch.unencoded
        writer.submit(batch, 1, until=time.monotonic() + 60)
        assert writer.wait(1, timeout=10)
    assert writer.commits == 0  # nothing to write


def test_a_staging_is_finished_before_the_next_is_submitted(
    clock: VirtualClock, tmp_path: Path
) -> None:
    with _writing(clock, tmp_path / "s.sqlite") as (cpu, store, writer):
        clock.advance(10)
        cpu.scan()
        writer.submit(store.stage(cpu, upto=1, defer=True), 1)  # until None: not here
        with pytest.raises(RuntimeError, match="submit before finish"):
            writer.submit(store.stage(cpu, upto=2, defer=True), 2)
        writer.finish(carry=False)
        assert writer.wait(1, timeout=10)


def test_an_instance_db_that_cannot_be_encoded_is_a_write_error_not_an_exception(
    clock: VirtualClock, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A failure while encoding, in the writer or in the scan thread's ``finish``, is kept
    as the writer's error (the runner stops the CPU naming it); waiters hear of it."""

    def broken(self: InstanceDB, *, live: bool = False) -> dict[str, object]:
        raise RuntimeError("a value that cannot be read")

    heard: list[str | None] = []
    with _writing(clock, tmp_path / "s.sqlite") as (cpu, store, writer):
        monkeypatch.setattr(InstanceDB, "snapshot", broken)
        clock.advance(10)
        cpu.scan()
        writer.submit(store.stage(cpu, upto=1, defer=True), 1)
        assert writer.finish(carry=False) == 3  # no exception in the scan thread
        writer.when_durable(1, heard.append)
    assert writer.error is not None
    assert (
        "cannot encode the state: an internal error while encoding it: a value that cannot "
        "be read (please report it)"
    ) in str(writer.error)
    assert heard and heard[0] is not None and "cannot encode" in heard[0]


@pytest.mark.timeout(60)
def test_a_running_cpu_leaves_its_instance_dbs_to_the_writer_and_finds_them_on_disk(
    tmp_path: Path,
) -> None:
    """The runner stages after the scan boundary and the writer encodes in the idle part:
    at a 20 ms cycle of three small FBs the scan thread encodes (almost) none itself; what
    the file holds after the run is the last scan's state."""
    path = tmp_path / "s.sqlite"
    store = StateStore(path)
    cpu = _tallies(SystemClock())
    runner = Runner(cpu, cycle_ms=20, store=store, rt_priority=None)
    runner.startup("warm")
    runner.run(duration_s=1.0)
    writer = runner.writer
    assert writer is not None
    assert runner.writer is not None and writer.flush(10)
    assert writer.encoded_here > writer.encoded_late
    assert runner.profile.mean_ns("encode") < runner.profile.mean_ns("scan") + 1_000_000
    totals = {n: cpu.instance_db(n).total for n in (7, 8, 9)}
    runner.shutdown()
    assert _totals(path) == totals


def test_one_slow_encoding_does_not_keep_the_encoder_out_for_good(
    clock: VirtualClock, tmp_path: Path
) -> None:
    """The encoder starts on an instance DB only when twice the longest recent encoding
    fits before the deadline; that figure fades at every staging, so after a stall of the
    machine it takes its share again instead of leaving every encoding to the scan."""
    with _writing(clock, tmp_path / "s.sqlite") as (cpu, store, writer):
        writer.encode_ns = 2_000_000_000  # once took 2 s: nothing fits in a second
        for mark in range(1, 121):
            clock.advance(10)
            cpu.scan()
            writer.submit(
                store.stage(cpu, upto=mark, defer=True), mark, until=time.monotonic() + 1.0
            )
            writer.finish()
        assert writer.encoded_late > 0  # the scan thread did it while the figure was high
        assert writer.encode_ns < 2_000_000  # faded: 2 s x (15/16)^120
        before = writer.encoded_here
        clock.advance(10)
        cpu.scan()
        writer.submit(store.stage(cpu, upto=121, defer=True), 121, until=time.monotonic() + 10)
        assert writer.wait(121, timeout=10)
    assert writer.encoded_here == before + 3
