"""A state file deleted, replaced or damaged under a running CPU (engine/renew.py): the writer
notices it at its next commit, holds back every reply waiting for it, and builds the file
anew from the running CPU; what was at the path is kept aside, never deleted."""

from __future__ import annotations

import os
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest

from s7graph.engine import CallContext, Cpu, EventId, VirtualClock, ob, persistence, renew
from s7graph.engine.persistence import StateStore
from s7graph.engine.runner import Runner
from s7graph.engine.writer import StoreWriter


@ob(1)
def counts(ctx: CallContext) -> None:
    ctx.mem.set("MW0", (int(ctx.mem.get("MW0")) + 1) % 30000)  # type: ignore[call-overload]


def _until(check: Callable[[], bool], timeout: float = 10.0) -> bool:
    """``check()`` became true within ``timeout`` (the writer is a thread of its own)."""
    pause = threading.Event()
    for _ in range(int(timeout / 0.005)):
        if check():
            return True
        pause.wait(0.005)
    return check()


def _scan(clock: VirtualClock, cpu: Cpu, store: StateStore, writer: StoreWriter, mark: int) -> None:
    """One scan and its staging, as the runner does: whole when the writer asks for it."""
    clock.advance(10)
    cpu.scan()
    full = writer.wants_full
    writer.submit(store.stage(cpu, upto=mark, full=full), mark)


@contextmanager
def _running(clock: VirtualClock, path: Path) -> Iterator[tuple[Cpu, StateStore, StoreWriter]]:
    """A CPU whose state file was written by a run before (checkpointed into the file),
    opened again with a writer, its first scan durable."""
    cpu = Cpu(clock)
    cpu.load(counts)
    cpu.start()
    first = StateStore(path)
    first.save(cpu)
    first.close()
    store = StateStore(path)
    writer = StoreWriter(store)
    try:
        _scan(clock, cpu, store, writer, 1)
        assert writer.wait(1, timeout=10)
        yield cpu, store, writer
    finally:
        writer.close()
        store.close()


def _lose_and_renew(
    clock: VirtualClock,
    cpu: Cpu,
    store: StateStore,
    writer: StoreWriter,
    damage: Callable[[], None],
) -> tuple[list[str | None], list[str]]:
    """``damage()``, then a command's audit row and its scan: what its waiter heard before the
    writer had a whole staging (nothing), and the renewal notes once it had."""
    damage()
    store.log_audit(5, "ann", "mode", "MAN")
    _scan(clock, cpu, store, writer, 2)
    heard: list[str | None] = []
    writer.when_durable(2, heard.append)
    assert _until(lambda: writer.wants_full)
    early = list(heard)
    _scan(clock, cpu, store, writer, 3)
    assert writer.wait(3, timeout=10), writer.error
    assert heard == [None]
    return early, writer.take_renewals()


def _holds(path: Path, cpu: Cpu) -> None:
    """The file at ``path`` holds ``cpu``'s memory image and the audit row of the command."""
    again = StateStore(path)
    try:
        restored = Cpu(VirtualClock())
        restored.load(counts)
        assert again.load(restored) is not None
        assert restored.mem.get("MW0") == cpu.mem.get("MW0")
        assert [(r["user"], r["action"]) for r in again.audit()] == [("ann", "mode")]
    finally:
        again.close()


def test_a_state_file_deleted_under_a_running_cpu_is_written_anew_before_any_reply(
    clock: VirtualClock, tmp_path: Path
) -> None:
    path = tmp_path / "s.sqlite"
    with _running(clock, path) as (cpu, store, writer):
        early, notes = _lose_and_renew(clock, cpu, store, writer, path.unlink)
    assert early == []  # not answered while the file it went to was gone
    assert notes and notes[0].startswith("the state file was deleted while the CPU ran")
    assert "s.sqlite.damaged-1-wal" in notes[0]  # its log, kept aside
    _holds(path, cpu)


def test_a_write_ahead_log_deleted_under_a_running_cpu_is_written_anew_not_lost(
    clock: VirtualClock, tmp_path: Path
) -> None:
    path = tmp_path / "s.sqlite"
    wal = Path(f"{path}-wal")
    with _running(clock, path) as (cpu, store, writer):
        early, notes = _lose_and_renew(clock, cpu, store, writer, wal.unlink)
    assert early == []
    assert "its write-ahead log s.sqlite-wal was deleted while the CPU ran" in notes[0]
    assert (tmp_path / "s.sqlite.damaged-1").is_file()
    _holds(path, cpu)


def test_a_state_file_overwritten_under_a_running_cpu_is_kept_aside_and_written_anew(
    clock: VirtualClock, tmp_path: Path
) -> None:
    path = tmp_path / "s.sqlite"

    def garble() -> None:
        with open(path, "r+b") as f:  # in place: the same inode, SQLite may not read it soon
            f.write(os.urandom(path.stat().st_size))

    with _running(clock, path) as (cpu, store, writer):
        early, notes = _lose_and_renew(clock, cpu, store, writer, garble)
    assert early == []
    assert "the state file was overwritten while the CPU ran" in notes[0]
    assert (tmp_path / "s.sqlite.damaged-1").stat().st_size > 0  # kept as it was found
    _holds(path, cpu)


def test_a_state_file_cut_short_under_a_running_cpu_is_kept_aside_and_written_anew(
    clock: VirtualClock, tmp_path: Path
) -> None:
    """``truncate -s 0`` keeps the inode and leaves nothing to read: a file seen whole before
    is one cut short (a new one in WAL mode may have no page yet), noticed before the next
    commit, not after the next restart."""
    path = tmp_path / "s.sqlite"

    def cut() -> None:
        os.truncate(path, 0)

    with _running(clock, path) as (cpu, store, writer):
        early, notes = _lose_and_renew(clock, cpu, store, writer, cut)
    assert early == []
    assert "the state file was cut short while the CPU ran" in notes[0]
    _holds(path, cpu)


def test_a_page_sqlite_finds_damaged_under_a_running_cpu_is_kept_aside_and_written_anew(
    clock: VirtualClock, tmp_path: Path
) -> None:
    """Damage past the file's header is what SQLite finds when it reads the page."""
    path = tmp_path / "s.sqlite"

    def garble() -> None:
        store._db.execute("PRAGMA cache_size=1")  # read its pages again: they are garbage now
        with open(path, "r+b") as f:
            f.seek(100)  # the header and its magic stay
            f.write(os.urandom(path.stat().st_size - 100))

    with _running(clock, path) as (cpu, store, writer):
        early, notes = _lose_and_renew(clock, cpu, store, writer, garble)
    assert early == []
    assert notes[0].startswith("the file was damaged while the CPU ran: ")
    assert (tmp_path / "s.sqlite.damaged-1").stat().st_size > 0
    _holds(path, cpu)


def test_a_state_file_replaced_by_a_directory_is_moved_aside_never_deleted(
    clock: VirtualClock, tmp_path: Path
) -> None:
    path = tmp_path / "s.sqlite"

    def replace() -> None:
        path.unlink()
        path.mkdir()
        (path / "keep.txt").write_text("mine")

    with _running(clock, path) as (cpu, store, writer):
        _, notes = _lose_and_renew(clock, cpu, store, writer, replace)
    assert "was replaced by a directory while the CPU ran" in notes[0]
    assert (tmp_path / "s.sqlite.damaged-1" / "keep.txt").read_text() == "mine"
    _holds(path, cpu)


def test_a_running_cpu_notes_a_renewed_state_file_in_its_diagnostic_buffer(
    tmp_path: Path,
) -> None:
    """The runner stages the whole state when asked, and says what happened (not a STOP)."""
    from s7graph.engine import SystemClock

    path = tmp_path / "s.sqlite"
    cpu = Cpu(SystemClock())
    cpu.load(counts)
    store = StateStore(path)
    runner = Runner(cpu, cycle_ms=5, store=store, rt_priority=None, idle_gc=False)
    heard: list[str] = []
    runner.on_note = heard.append
    runner.startup("warm")
    thread = runner.start_thread(duration_s=30)
    try:
        assert _until(lambda: runner.writer is not None and runner.writer.committed > 2)
        path.unlink()
        assert _until(lambda: bool(heard))
    finally:
        runner.shutdown()
        thread.join(10)
        store.close()
    assert runner.write_error is None and runner.stopped == ""
    assert any(e.event_id == EventId.STATE_RENEWED for e in cpu.diagnostics)
    assert "deleted while the CPU ran" in heard[0]
    assert path.is_file()


def test_a_run_ending_before_the_file_was_built_anew_builds_it_in_its_last_save(
    clock: VirtualClock, tmp_path: Path
) -> None:
    """Closed while the writer waited for a whole staging: the rows it held go to the
    store's last save (``Runner.shutdown``), which builds the file with them."""
    path = tmp_path / "s.sqlite"
    with _running(clock, path) as (cpu, store, writer):
        path.unlink()
        store.log_audit(5, "ann", "mode", "MAN")
        _scan(clock, cpu, store, writer, 2)
        assert _until(lambda: writer.wants_full)
        writer.close()
        assert writer.left is not None
        store.save(cpu, clean=True, before=writer.left)
    assert any(e.event_id == EventId.STATE_RENEWED for e in cpu.diagnostics)
    _holds(path, cpu)


def test_a_file_lost_while_a_batch_was_committed_to_it_keeps_that_batch_once(
    clock: VirtualClock, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Deleted between the check before a commit and the commit: the check after it
    notices; the batch is in the old file (copied from there), not written twice."""
    path = tmp_path / "s.sqlite"
    answers: list[tuple[str, bool] | None] = [None, ("the state file was deleted", True)]

    def late(*args: Any) -> tuple[str, bool] | None:
        return answers.pop(0) if answers else renew.gone(*args)

    with _running(clock, path) as (cpu, store, writer):
        monkeypatch.setattr(persistence, "gone", late)
        early, notes = _lose_and_renew(clock, cpu, store, writer, lambda: None)
    assert early == [] and notes[0].startswith("the state file was deleted")
    _holds(path, cpu)  # the command's row once
