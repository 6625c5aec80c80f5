"""A state file is trusted only when recognised (engine/persistence.py): anything else is
refused with the file and the problem named — never a silent fresh start, never a row
deleted."""

from __future__ import annotations

import json
import os
import sqlite3
import zlib
from pathlib import Path
from typing import Any

import msgspec
import pytest

from s7graph.engine import CallContext, Cpu, InstanceDB, VirtualClock, fb, ob
from s7graph.engine.modes import CpuMode
from s7graph.engine.persistence import FORMAT, StateFileError, StateStore, not_a_state_file


@fb(2, "acc", STAT={"total": ("DINT", 0)})
def acc(ctx: CallContext, db: InstanceDB) -> None:
    db.total = int(db.total) + 1  # type: ignore[call-overload]


@fb(2, "other", STAT={"total": ("DINT", 0)})
def other(ctx: CallContext, db: InstanceDB) -> None:
    pass


@fb(2, "acc", STAT={"total": ("DINT", 0), "extra": ("INT", 5)})
def acc_grown(ctx: CallContext, db: InstanceDB) -> None:
    pass


@ob(1)
def main(ctx: CallContext) -> None:
    ctx.call(acc, 2)


def _cpu(block: object = acc, *, number: int = 2) -> Cpu:
    cpu = Cpu(VirtualClock())
    cpu.load(main, block)  # type: ignore[arg-type]
    cpu.create_instance_db(number, block)  # type: ignore[arg-type]
    return cpu


def _written(path: Path, scans: int = 3) -> Path:
    """A state file of ``main`` + ``acc`` after a few scans (checkpointed, closed)."""
    store = StateStore(path)
    cpu = _cpu()
    cpu.start()
    for _ in range(scans):
        cpu.scan()
    store.save(cpu)
    store.close()
    return path


def _refused(path: Path, cpu: Cpu | None = None) -> str:
    with pytest.raises(StateFileError) as info:
        store = StateStore(path)
        try:
            store.load(cpu or _cpu())
        finally:
            store.close()
    assert info.value.path == path
    return info.value.problem


def test_a_missing_file_is_a_fresh_start(tmp_path: Path) -> None:
    store = StateStore(tmp_path / "new.sqlite")
    assert store.load(_cpu()) is None


def test_an_empty_file_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "s.sqlite"
    path.write_bytes(b"")
    assert "empty file (0 bytes)" in _refused(path)
    assert path.stat().st_size == 0  # left as it was


def test_a_garbled_file_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "s.sqlite"
    path.write_bytes(os.urandom(8192))
    assert "not a readable state file" in _refused(path)


def test_a_truncated_file_is_refused(tmp_path: Path) -> None:
    path = _written(tmp_path / "s.sqlite")
    for n in range(50):
        with sqlite3.connect(path) as con:  # some history, so the file spans many pages
            con.execute(
                "INSERT INTO audit (t_ns, user, action, detail) VALUES (?, ?, ?, ?)",
                (n, "ann", "ack", "x" * 900),
            )
        con.close()
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    problem = _refused(path)
    assert "damaged file" in problem or "not a readable state file" in problem


def test_another_applications_sqlite_file_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "s.sqlite"
    with sqlite3.connect(path) as con:
        con.execute("CREATE TABLE recipes (name TEXT)")
    con.close()
    assert "not an s7graph state file" in _refused(path)


def test_a_file_of_the_older_format_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "s.sqlite"
    with sqlite3.connect(path) as con:
        con.execute("CREATE TABLE instances (number INTEGER PRIMARY KEY, fb TEXT, state TEXT)")
        con.execute("INSERT INTO instances VALUES (2, 'FB2', '{}')")
    con.close()
    assert "older s7graph" in _refused(path)


def _rows(path: Path) -> list[tuple[object, ...]]:
    with sqlite3.connect(path) as con:
        rows = con.execute("SELECT number, fb, name FROM instances").fetchall()
    con.close()
    return rows


def test_the_state_of_another_fb_is_refused_and_its_row_kept(tmp_path: Path) -> None:
    path = _written(tmp_path / "s.sqlite")
    problem = _refused(path, _cpu(other))
    assert problem == "DB2 holds an instance of FB2 'acc', not of FB2 'other'"
    assert _rows(path) == [(2, "FB2", "acc")]


def test_an_instance_db_the_program_does_not_have_is_refused(tmp_path: Path) -> None:
    path = _written(tmp_path / "s.sqlite")
    problem = _refused(path, _cpu(acc, number=3))
    assert problem == "DB2 holds an instance of FB2 'acc', which this program does not have"
    assert _rows(path) == [(2, "FB2", "acc")]


@pytest.mark.parametrize(
    ("data", "fragment"),
    [
        (b"\x00\xff garbage", "malformed data of DB2"),
        (zlib.compress(b"[1, 2]"), "malformed data of DB2"),
        (zlib.compress(json.dumps({"total": "many"}).encode()), "malformed state of DB2"),
        (zlib.compress(json.dumps({"total": 1, "ghost": 2}).encode()), "malformed state of DB2"),
        (zlib.compress(msgspec.msgpack.encode({"total": "many"})), "malformed state of DB2"),
        (zlib.compress(msgspec.msgpack.encode({"total": 1})[:-1]), "malformed data of DB2"),
        (zlib.compress(msgspec.msgpack.encode([1, 2])), "malformed data of DB2"),
        (zlib.compress(msgspec.msgpack.encode([{"total": 1}, 5])), "malformed data of DB2"),
        (
            zlib.compress(msgspec.msgpack.encode([{"total": 1}, {"total": {"calls": 1}}])),
            "malformed data of DB2",
        ),
    ],
)
def test_a_malformed_instance_is_refused(tmp_path: Path, data: bytes, fragment: str) -> None:
    path = _written(tmp_path / "s.sqlite")
    with sqlite3.connect(path) as con:
        con.execute("UPDATE instances SET data=? WHERE number=2", (data,))
    con.close()
    assert fragment in _refused(path)


@pytest.mark.parametrize(
    ("mark", "row"),
    [
        ("s7graph-state 2", json.dumps({"total": 41}).encode()),
        ("s7graph-state 3", msgspec.msgpack.encode({"total": 41})),
    ],
)
def test_a_file_of_an_older_readable_format_is_read_and_marked_with_the_current_one(
    tmp_path: Path, mark: str, row: bytes
) -> None:
    """Format 2 kept instance rows as compressed JSON, format 3 as one MessagePack map (the
    volatile keys inside): they are still read, and the file, once written, is marked with
    the format it now holds rows of (an older s7graph refuses it by name) — not before: a
    load alone writes nothing."""
    path = _written(tmp_path / "s.sqlite")
    with sqlite3.connect(path) as con:
        con.execute("UPDATE meta SET value=? WHERE key='format'", (mark,))
        con.execute("UPDATE instances SET data=? WHERE number=2", (zlib.compress(row),))
    con.close()
    store = StateStore(path)
    cpu = _cpu()
    store.load(cpu)
    assert store.meta("format") == mark
    store.save(cpu)
    store.close()
    assert cpu.instance_db(2).total == 41
    with sqlite3.connect(path) as con:
        assert con.execute("SELECT value FROM meta WHERE key='format'").fetchone() == (FORMAT,)
    con.close()


def test_a_file_of_an_unknown_format_is_refused_by_its_mark(tmp_path: Path) -> None:
    path = _written(tmp_path / "s.sqlite")
    with sqlite3.connect(path) as con:
        con.execute("UPDATE meta SET value='s7graph-state 9' WHERE key='format'")
    con.close()
    assert _refused(path) == "unknown format 's7graph-state 9'"


def test_a_malformed_memory_image_is_refused(tmp_path: Path) -> None:
    path = _written(tmp_path / "s.sqlite")
    with sqlite3.connect(path) as con:
        con.execute("UPDATE meta SET value='{\"markers\": 5}' WHERE key='memory'")
    con.close()
    assert "malformed memory image" in _refused(path)


def test_an_fb_whose_interface_changed_keeps_its_variables_by_name(tmp_path: Path) -> None:
    path = _written(tmp_path / "s.sqlite", scans=4)
    cpu = _cpu(acc_grown)
    store = StateStore(path)
    report = store.load(cpu)
    assert report is not None and report.changed == [2]
    assert cpu.instance_db(2).total == 4 and cpu.instance_db(2).extra == 5
    assert any("new, at their initial values: extra" in n for n in report.notes)
    assert "program download" in cpu.hot_blockers  # a changed program: no hot restart


def test_the_same_program_may_restart_hot(tmp_path: Path) -> None:
    path = _written(tmp_path / "s.sqlite")
    cpu = _cpu()
    report = StateStore(path).load(cpu)
    assert report is not None and not report.changed
    assert "program download" not in cpu.hot_blockers


# ---- what was still taken silently ---------------------------------------------------------


def _edit(path: Path, *statements: tuple[str, tuple[object, ...]]) -> None:
    with sqlite3.connect(path) as con:
        for sql, args in statements:
            con.execute(sql, args)
    con.close()


def test_a_state_file_whose_instances_table_is_gone_is_refused(tmp_path: Path) -> None:
    """Not taken for a state without instance DBs: the table would come back empty and every
    FB (a sequencer's position with it) start at its initial values."""
    path = _written(tmp_path / "s.sqlite")
    _edit(path, ("DROP TABLE instances", ()))
    assert "the instances table is gone" in _refused(path)
    with sqlite3.connect(path) as con:  # not recreated
        tables = {r[0] for r in con.execute("SELECT name FROM sqlite_master")}
    con.close()
    assert "instances" not in tables


def test_an_instance_row_without_one_of_its_variables_is_refused(tmp_path: Path) -> None:
    path = _written(tmp_path / "s.sqlite")
    _edit(
        path,
        (
            "UPDATE instances SET data=? WHERE number=2",
            (zlib.compress(msgspec.msgpack.encode([{}, {}])),),
        ),
    )
    assert _refused(path) == "malformed state of DB2: no total"


def test_an_instance_db_the_file_holds_no_row_of_is_noted_and_blocks_a_hot_restart(
    tmp_path: Path,
) -> None:
    """A DB new in the program starts at its initial values, said so; as after a download,
    only a warm restart."""
    path = _written(tmp_path / "s.sqlite")
    _edit(path, ("DELETE FROM instances", ()))
    cpu = _cpu()
    report = StateStore(path).load(cpu)
    assert report is not None
    assert report.notes == ["DB2 FB2 'acc': no state saved, at its initial values"]
    assert {"program download", "no state saved for DB2"} <= cpu.hot_blockers


def test_a_copy_without_its_write_ahead_log_is_refused_not_started_fresh(tmp_path: Path) -> None:
    """A run's commits sit in FILE-wal until a checkpoint: the main file alone, copied while
    the run is on, holds no table at all, and was taken for a new file."""
    path = tmp_path / "s.sqlite"
    store = StateStore(path)
    cpu = _cpu()
    store.load(cpu)
    cpu.start()
    store.save(cpu, clean=False)
    copy = tmp_path / "copy.sqlite"
    copy.write_bytes(path.read_bytes())  # what `cp s.sqlite copy.sqlite` takes
    store.close()
    with pytest.raises(StateFileError) as info:
        StateStore(copy)
    assert "without a single table" in info.value.problem
    assert f"{copy}-wal" in info.value.way_out and "--fresh" in info.value.way_out
    assert not Path(f"{copy}-wal").exists()


def _image(path: Path, key: str) -> dict[str, Any]:
    with sqlite3.connect(path) as con:
        (text,) = con.execute("SELECT value FROM meta WHERE key=?", (key,)).fetchone()
    con.close()
    return dict(json.loads(text))


@pytest.mark.parametrize(
    ("change", "fragment"),
    [
        (lambda m: m.update(markers={"start": 0, "data": "!!not base64!!"}), "not valid base64"),
        (
            lambda m: m.update(markers={"start": 250, "data": "AAAAAAAAAAAAAAAAAAAAAA=="}),
            "beyond the CPU's 256 marker bytes",
        ),
        (lambda m: m.update(markers={"start": -4, "data": "AAAA"}), "'markers' starts at -4"),
        (lambda m: m.update(counters={"9999": {"value": 3}}), "the CPU has 256 cells"),
        (lambda m: m.update(counters={"0": {"value": "many"}}), "'value' is 'many'"),
        (lambda m: m.update(counters={"0": {"value": 5000}}), "the count 5000 is not in 0..999"),
        (lambda m: m.update(counters={"10": {"value": -7}}), "the count -7 is not in 0..999"),
        (lambda m: m.update(counters={"0": {"ghost": 1}}), "unknown key(s) 'ghost'"),
        (lambda m: m.update(spare=1), "unknown key(s) 'spare'"),
        (
            lambda m: m.update(dbs={"7": {"data": 5, "initial": "", "created": False}}),
            "DB '7' data is 5",
        ),
        (lambda m: m.update(dbs=[]), "'dbs' is list"),
    ],
)
def test_a_malformed_retentive_memory_image_is_refused_not_taken(
    tmp_path: Path, change: Any, fragment: str
) -> None:
    """Taken unchecked, invalid base64 read as fewer bytes, a marker span past the area grew
    it, a cell the CPU does not have was skipped and a field of the wrong type set."""
    path = _written(tmp_path / "s.sqlite")
    image = _image(path, "memory")
    change(image)
    _edit(path, ("UPDATE meta SET value=? WHERE key='memory'", (json.dumps(image),)))
    problem = _refused(path)
    assert problem.startswith("malformed memory image: ") and fragment in problem
    assert "ValueError" not in problem


def test_a_hot_restart_image_of_another_size_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "s.sqlite"
    store = StateStore(path, hot=True)
    cpu = _cpu()
    store.load(cpu)
    cpu.start()
    store.save(cpu)
    store.close()
    image = _image(path, "hot_memory")
    image["outputs"] = "AAAA"
    _edit(path, ("UPDATE meta SET value=? WHERE key='hot_memory'", (json.dumps(image),)))
    problem = _refused(path)
    assert "malformed hot restart image" in problem and "'outputs' holds 3 bytes" in problem


def test_a_file_locked_by_another_connection_is_refused_as_in_use_not_unreadable(
    tmp_path: Path,
) -> None:
    """Locked is not garbled: the way out is to stop the other process, never --fresh."""
    path = _written(tmp_path / "s.sqlite")
    holder = sqlite3.connect(path, isolation_level=None)
    holder.execute("PRAGMA locking_mode=EXCLUSIVE")
    holder.execute("BEGIN EXCLUSIVE")
    holder.execute("UPDATE meta SET value=value WHERE key='format'")
    try:
        with pytest.raises(StateFileError) as info:
            StateStore(path)
    finally:
        holder.execute("ROLLBACK")
        holder.close()
    assert info.value.problem.startswith("in use by another process (database is locked)")
    assert "stop the process that holds it" in info.value.way_out
    assert "fresh" not in info.value.way_out


@ob(1)
def failing(ctx: CallContext) -> None:
    raise RuntimeError("boom")  # no OB121: STOP


@pytest.mark.parametrize(
    ("stop", "blocked"),
    [
        (lambda cpu: cpu.stop("s7graph run ended"), None),
        (lambda cpu: (cpu.load(failing), cpu.hot_blockers.clear(), cpu.scan()), None),
        (lambda cpu: cpu.abort("OB1"), "STOP by an error (block aborted by cycle monitoring)"),
    ],
    ids=["a stop request", "an OB not loaded", "cycle monitoring"],
)
def test_the_stop_on_disk_decides_whether_a_hot_restart_is_possible(
    tmp_path: Path, stop: Any, blocked: str | None
) -> None:
    """S7-400 resumes hot after a STOP by the mode selector, a programming device, a
    programmed STOP or an OB not loaded; not after one by an error such as a block aborted
    by cycle monitoring."""
    path = tmp_path / "s.sqlite"
    store = StateStore(path, hot=True)
    cpu = _cpu()
    store.load(cpu)
    cpu.start()
    cpu.scan()
    stop(cpu)
    assert cpu.mode is CpuMode.STOP
    store.save(cpu, clean=True)
    store.close()
    again = _cpu()
    StateStore(path, hot=True).load(again)
    stops = {b for b in again.hot_blockers if b.startswith("STOP")}
    assert stops == (set() if blocked is None else {blocked})


def test_instance_rows_without_a_memory_image_are_refused(tmp_path: Path) -> None:
    path = _written(tmp_path / "s.sqlite")
    _edit(path, ("DELETE FROM meta WHERE key='memory'", ()))
    assert _refused(path) == "no memory image (an incomplete state)"


def test_two_stores_of_one_process_may_share_a_file(tmp_path: Path) -> None:
    """The lock keeps other processes out; a tool of the same process (a test, the view's
    audit) reads on."""
    path = _written(tmp_path / "s.sqlite")
    first, second = StateStore(path), StateStore(path)
    assert first.has_state() and second.has_state()
    first.close()
    second.close()


def test_a_write_ahead_log_without_its_file_is_refused_not_started_fresh(tmp_path: Path) -> None:
    """The file deleted while a run wrote it leaves its ``-wal``: SQLite would start a new,
    empty file beside it and the state would be gone without a word."""
    path = _written(tmp_path / "s.sqlite")
    wal = Path(f"{path}-wal")
    wal.write_bytes(os.urandom(4096))
    path.unlink()
    with pytest.raises(StateFileError) as info:
        StateStore(path)
    assert info.value.problem.startswith("missing, but its write-ahead log s.sqlite-wal is there")
    assert "--fresh" in info.value.way_out and "put the file back" in info.value.way_out
    assert not path.exists() and wal.stat().st_size == 4096


def test_a_directory_or_a_missing_folder_is_refused_without_pointing_to_fresh(
    tmp_path: Path,
) -> None:
    for path, problem in (
        (tmp_path, "a directory, not a state file"),
        (tmp_path / "nothere" / "s.sqlite", f"its folder {tmp_path / 'nothere'} does not exist"),
    ):
        with pytest.raises(StateFileError) as info:
            StateStore(path)
        assert info.value.problem == problem
        assert info.value.way_out and "--fresh" not in info.value.way_out


def test_what_cannot_be_a_state_file_is_told_without_opening_it_and_anything_else_passes(
    tmp_path: Path,
) -> None:
    """``not_a_state_file``: the check a run makes before SQLite opens the path, public so
    that ``s7graph audit`` says the same; a file not there, or one SQLite will judge, is
    not its to refuse."""
    empty = tmp_path / "empty.sqlite"
    empty.write_bytes(b"")
    folder = not_a_state_file(tmp_path)
    assert folder is not None and folder.problem == "a directory, not a state file"
    assert folder.way_out.startswith("give --state the path of a file")
    nothing = not_a_state_file(empty)
    assert nothing is not None and (nothing.problem, nothing.way_out) == (
        "empty file (0 bytes), not a state file",
        "",  # only starting anew: a run's --fresh
    )
    assert empty.read_bytes() == b""
    for fine in (tmp_path / "none.sqlite", _written(tmp_path / "s.sqlite")):
        assert not_a_state_file(fine) is None
    assert not (tmp_path / "none.sqlite").exists()


def test_a_state_file_being_built_anew_when_its_run_ended_is_refused_not_started_fresh(
    tmp_path: Path,
) -> None:
    """Killed between setting the old file aside and renaming the new one in
    (``engine/renew.py``): the new one waits as ``FILE.renew``."""
    built = _written(tmp_path / "s.sqlite.renew")
    path = tmp_path / "s.sqlite"
    with pytest.raises(StateFileError) as info:
        StateStore(path)
    assert info.value.problem.startswith("missing, but s.sqlite.renew is there")
    assert info.value.way_out.startswith(f"rename {built} to s.sqlite")
    os.rename(built, path)
    assert _loads(path)


def _loads(path: Path) -> bool:
    store = StateStore(path)
    try:
        return store.load(_cpu()) is not None
    finally:
        store.close()


@pytest.mark.parametrize(("key", "value"), [("mode", "BANANA"), ("clean", "maybe")])
def test_a_meta_value_this_code_never_writes_is_refused(
    tmp_path: Path, key: str, value: str
) -> None:
    """A mode or a clean mark someone edited is not trusted for what it says (``clean``
    decides whether the last run ended cleanly)."""
    path = _written(tmp_path / "s.sqlite")
    _edit(path, ("INSERT OR REPLACE INTO meta VALUES (?, ?)", (key, value)))
    assert _refused(path) == f"malformed meta {key!r}: {value!r}"
