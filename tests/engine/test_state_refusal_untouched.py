"""A state file the CPU refuses at startup is left as it was found (engine/persistence.py,
web/harness/persist.py): byte for byte, its mode too, and no ``-wal`` or ``-shm`` made,
removed or checkpointed beside it — the file is recognised and read on a read-only
connection and opened for writing only once it is taken. Each kind of refusal, on a file a
run closed cleanly (no ``-wal``) and on one a run left when it was killed (its last
commits still in its ``-wal``, with or without its ``-shm``)."""

from __future__ import annotations

import fcntl
import os
import shutil
import sqlite3
import zlib
from collections.abc import Callable
from pathlib import Path

import pytest

from s7graph.engine import Cpu
from s7graph.engine.persistence import StateFileError, StateStore
from s7graph.engine.state_identity import Program
from s7graph.web.harness.persist import open_state
from tests.engine.test_state_trust import _cpu, other

Edit = tuple[str, tuple[object, ...]]

# what makes a file written by ``_cpu()`` refused: SQL run on it, the CPU that reads it, the
# restart asked for, a fragment of the refusal
LOADED: dict[str, tuple[list[Edit], Callable[[], Cpu], str | None, str]] = {
    "another application's": (
        [("DROP TABLE " + t, ()) for t in ("meta", "instances", "diagnostics", "alarms")]
        + [("DROP TABLE " + t, ()) for t in ("parts", "audit", "alarm_summary")]
        + [("CREATE TABLE recipes (name TEXT)", ())],
        _cpu,
        None,
        "not an s7graph state file",
    ),
    "older format": (
        [("ALTER TABLE instances ADD COLUMN state TEXT", ())],
        _cpu,
        None,
        "older s7graph",
    ),
    "unknown format": (
        [("UPDATE meta SET value='s7graph-state 9' WHERE key='format'", ())],
        _cpu,
        None,
        "unknown format",
    ),
    "instances gone": ([("DROP TABLE instances", ())], _cpu, None, "instances table is gone"),
    "no memory image": ([("DELETE FROM meta WHERE key='memory'", ())], _cpu, None, "no memory"),
    "malformed memory image": (
        [("UPDATE meta SET value='{\"markers\": 5}' WHERE key='memory'", ())],
        _cpu,
        None,
        "malformed memory image",
    ),
    "malformed meta": (
        [("INSERT OR REPLACE INTO meta VALUES ('mode', 'BANANA')", ())],
        _cpu,
        None,
        "malformed meta 'mode'",
    ),
    "meta not UTF-8": (
        [("INSERT OR REPLACE INTO meta VALUES ('mode', CAST(X'FF' AS TEXT))", ())],
        _cpu,
        None,
        "is not UTF-8",
    ),
    "another FB's instance": ([], lambda: _cpu(other), None, "not of FB2 'other'"),
    "a DB the program lacks": ([], lambda: _cpu(number=3), None, "does not have"),
    "malformed instance": (
        [("UPDATE instances SET data=? WHERE number=2", (zlib.compress(b"[1, 2]"),))],
        _cpu,
        None,
        "malformed data of DB2",
    ),
    "malformed diagnostics row": (
        [("INSERT INTO diagnostics (seq, t_ns) VALUES (99, 'x')", ())],
        _cpu,
        None,
        "malformed diagnostics row 99",
    ),
    "hot restart not possible": ([], _cpu, "hot", "cannot restart hot"),
}


def _files(folder: Path) -> dict[str, tuple[int, bytes]]:
    """Every file of ``folder``: its mode and its bytes — but a ``-shm``'s, which SQLite
    rebuilds as any reader of the ``-wal`` needs it: an index of the ``-wal`` with no
    persistent content (sqlite.org, "WAL-mode File Format", the "-shm" file)."""
    return {
        p.name: (p.stat().st_mode, b"" if p.is_dir() or p.name.endswith("-shm") else p.read_bytes())
        for p in sorted(folder.iterdir())
    }


def _state(folder: Path, edits: list[Edit], *, killed: bool, shm: bool = True) -> Path:
    """A state file of ``_cpu()`` with ``edits`` made, in ``folder``: as a run left it when
    it stopped, or (``killed``) as one left it when killed — its last commits, the edits
    among them, in its ``-wal`` (with its ``-shm``, unless ``shm`` is False); readable by
    others (mode 644), as a file copied in may be."""
    work = folder.parent / f"{folder.name}-work"
    work.mkdir()
    path = work / "s.sqlite"
    store = StateStore(path)
    cpu = _cpu()
    cpu.start()
    cpu.scan()
    store.save(cpu, clean=False)
    con = sqlite3.connect(path)
    for sql, args in edits:
        con.execute(sql, args)
    con.commit()
    folder.mkdir()
    if killed:  # taken while both connections have it open: nothing checkpointed
        for suffix in ("", "-wal", "-shm") if shm else ("", "-wal"):
            shutil.copy(f"{path}{suffix}", folder / f"s.sqlite{suffix}")
    con.close()
    store.close()
    if not killed:
        shutil.copy(path, folder / "s.sqlite")
    for part in folder.iterdir():
        part.chmod(0o644)
    return folder / "s.sqlite"


def _refused_untouched(
    path: Path, cpu: Cpu, restart: str | None = None, program: Program | None = None
) -> str:
    """The refusal of ``path``, asserting its folder as it was before, byte for byte."""
    before = _files(path.parent)
    with pytest.raises(StateFileError) as info:
        open_state(path, cpu, restart=restart, program=program)
    assert _files(path.parent) == before
    return info.value.problem


@pytest.mark.parametrize("kind", LOADED)
@pytest.mark.parametrize("ended", ["stopped", "killed", "killed without its -shm"])
def test_a_refused_state_file_is_left_byte_for_byte_with_no_file_made_beside_it(
    tmp_path: Path, kind: str, ended: str
) -> None:
    edits, cpu, restart, fragment = LOADED[kind]
    killed = ended != "stopped"
    path = _state(tmp_path / "run", edits, killed=killed, shm=ended == "killed")
    assert Path(f"{path}-wal").exists() is killed
    assert fragment in _refused_untouched(path, cpu(), restart)


@pytest.mark.parametrize("ended", ["stopped", "killed", "killed without its -shm"])
def test_the_file_of_another_program_is_refused_and_left_byte_for_byte(
    tmp_path: Path, ended: str
) -> None:
    recorded = [
        ("INSERT OR REPLACE INTO meta VALUES (?, ?)", ("program_kind", "scl")),
        ("INSERT OR REPLACE INTO meta VALUES (?, ?)", ("program_source", "far.scl")),
    ]
    killed = ended != "stopped"
    path = _state(tmp_path / "run", recorded, killed=killed, shm=ended == "killed")
    problem = _refused_untouched(path, _cpu(), program=Program("chart", "far.s7g"))
    assert problem.startswith("the state of another program: the S7-SCL program far.scl's")


@pytest.mark.parametrize(
    ("kind", "make", "fragment"),
    [
        ("empty", lambda p: p.write_bytes(b""), "empty file"),
        ("garbled", lambda p: p.write_bytes(bytes(range(256)) * 32), "not a readable state"),
        ("a directory", lambda p: p.mkdir(), "a directory"),
        ("its -wal alone", lambda p: Path(f"{p}-wal").write_bytes(b"w" * 4096), "missing, but"),
        ("its .renew alone", lambda p: Path(f"{p}.renew").write_bytes(b"r"), "missing, but"),
    ],
)
def test_a_file_refused_before_it_is_opened_is_left_as_it_was(
    tmp_path: Path, kind: str, make: Callable[[Path], object], fragment: str
) -> None:
    path = tmp_path / "s.sqlite"
    make(path)
    before = {p.name: p.stat().st_mode for p in tmp_path.iterdir()}
    assert fragment in _refused_untouched(path, _cpu())
    assert {p.name: p.stat().st_mode for p in tmp_path.iterdir()} == before


def test_a_truncated_file_is_refused_and_left_as_it_was(tmp_path: Path) -> None:
    rows = [("INSERT INTO audit (t_ns, detail) VALUES (?, ?)", (n, "x" * 900)) for n in range(50)]
    path = _state(tmp_path / "run", rows, killed=False)
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    problem = _refused_untouched(path, _cpu())
    assert problem.startswith(("damaged file", "not a readable state file")), problem


def test_a_copy_without_its_write_ahead_log_is_refused_and_left_as_it_was(
    tmp_path: Path,
) -> None:
    path = _state(tmp_path / "run", [], killed=True)
    os.unlink(f"{path}-wal")
    os.unlink(f"{path}-shm")
    assert "without a single table" in _refused_untouched(path, _cpu())


def test_a_file_another_run_holds_is_refused_as_in_use_and_left_as_it_was(tmp_path: Path) -> None:
    path = _state(tmp_path / "run", [], killed=True)
    fd = os.open(path, os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)  # as another run's store holds it
        assert "in use by another process" in _refused_untouched(path, _cpu())
    finally:
        os.close(fd)


def test_a_file_another_connection_writes_is_refused_as_in_use_and_left_as_it_was(
    tmp_path: Path,
) -> None:
    path = _state(tmp_path / "run", [], killed=False)
    holder = sqlite3.connect(path, isolation_level=None)
    holder.execute("PRAGMA locking_mode=EXCLUSIVE")
    holder.execute("BEGIN EXCLUSIVE")
    holder.execute("UPDATE meta SET value=value WHERE key='format'")
    try:
        assert "in use by another process" in _refused_untouched(path, _cpu())
    finally:
        holder.execute("ROLLBACK")
        holder.close()


def test_a_file_taken_is_opened_for_writing_only_then(tmp_path: Path) -> None:
    """The counterpart: a file that is recognised and loaded is written — made its owner's
    alone (mode 600) and set up for this code — only once ``open_state`` takes it."""
    path = _state(tmp_path / "run", [], killed=True, shm=False)
    store = StateStore(path)
    store.load(_cpu())
    assert _files(path.parent)[path.name][0] & 0o777 == 0o644
    store.close()
    assert sorted(_files(path.parent)) == ["s.sqlite", "s.sqlite-wal"]
    opened = open_state(path, _cpu())
    assert path.stat().st_mode & 0o777 == 0o600 and opened.store.made_private
    opened.store.close()
