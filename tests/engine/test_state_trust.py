"""A state file is trusted only when recognised (engine/persistence.py): anything else is
refused with the file and the problem named — never a silent fresh start, never a row
deleted."""

from __future__ import annotations

import json
import os
import sqlite3
import zlib
from pathlib import Path

import msgspec
import pytest

from s7graph.engine import CallContext, Cpu, InstanceDB, VirtualClock, fb, ob
from s7graph.engine.persistence import FORMAT, StateFileError, StateStore


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
            con.execute("INSERT INTO audit (t_ns, user, action, detail) VALUES (?, ?, ?, ?)",
                        (n, "ann", "ack", "x" * 900))  # fmt: skip
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
    volatile keys inside): they are still read, and the file is marked with the format it
    now holds rows of (an older s7graph refuses it by name)."""
    path = _written(tmp_path / "s.sqlite")
    with sqlite3.connect(path) as con:
        con.execute("UPDATE meta SET value=? WHERE key='format'", (mark,))
        con.execute("UPDATE instances SET data=? WHERE number=2", (zlib.compress(row),))
    con.close()
    store = StateStore(path)
    cpu = _cpu()
    store.load(cpu)
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
