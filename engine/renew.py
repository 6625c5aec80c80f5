"""A state file deleted, replaced or damaged under a running CPU: noticed, and built anew.

The writer (``engine/writer.py``) writes through an open SQLite connection; SQLite never
looks at the path again. A state file deleted (or its ``-wal``) while the CPU runs keeps
taking commits that no restart will find, and the restart after a kill started fresh or
came back from the last checkpoint, the acknowledged commands gone. So before each commit
``gone`` compares the path and its ``-wal`` with the files the store opened (device and
inode) and reads the file's first bytes (written over in place, it keeps its inode), and a
commit SQLite finds damaged (SQLITE_CORRUPT, SQLITE_NOTADB) counts the same.

The CPU holds its whole state in memory, so the file is not lost with it: ``rebuild`` builds
a new file beside it — every table the open connection can still read copied (the alarm and
audit logs, through a deleted file or write-ahead log too), then the rows waiting, a whole
staging of the CPU among them — syncs it, keeps what is at the path as ``FILE.damaged-N``
(with its ``-wal`` and ``-shm``) and renames the new file in. Only then is anything waiting
durable. What cannot be built (the folder is gone or read-only, the disk is full) is a
write error as any other (the CPU goes to STOP).
"""

from __future__ import annotations

import contextlib
import os
import sqlite3
import stat
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

__all__ = ["Ident", "gone", "ident", "rebuild", "set_aside", "sync"]

Ident = tuple[int, int]
"""A file's device and inode."""


def ident(path: Path) -> Ident | None:
    """The device and inode of the file at ``path`` (None: none there)."""
    try:
        st = os.stat(path)
    except OSError:
        return None
    return (st.st_dev, st.st_ino)


def _kind(mode: int) -> str:
    return "a directory" if stat.S_ISDIR(mode) else "something that is not a file"


@dataclass
class Known:
    """The files a store writes — the state file's and its ``-wal``'s device and inode —
    and whether the state file has been seen starting as an SQLite database (``headed``:
    from then on a file too short to say is one cut short, not one not written yet)."""

    main: Ident | None
    wal: Ident | None
    headed: bool = False


def known(path: Path) -> Known:
    """What the store at ``path`` writes now (``gone`` checks against it)."""
    found = Known(ident(path), ident(Path(f"{path}-wal")))
    found.headed = _head(path) == _MAGIC
    return found


def gone(path: Path, files: Known) -> tuple[str, bool] | None:
    """Why ``path`` or its ``-wal`` no longer names the file the store writes (None: both
    still do), and whether a new file can be built there (not when the path cannot even be
    looked at; what is there, a directory too, is moved aside, never deleted)."""
    main, wal = files.main, files.wal
    for file, known, what in (
        (path, main, "the state file"),
        (Path(f"{path}-wal"), wal, f"its write-ahead log {path.name}-wal"),
    ):
        if known is None:
            continue
        try:
            st = os.stat(file)
        except FileNotFoundError:
            return f"{what} was deleted while the CPU ran", True
        except OSError as exc:
            return f"{what} cannot be looked at ({exc.strerror or exc})", False
        if not stat.S_ISREG(st.st_mode):
            return f"{what} was replaced by {_kind(st.st_mode)} while the CPU ran", True
        if (st.st_dev, st.st_ino) != known:
            return f"{what} was replaced by another file while the CPU ran", True
    if main is not None:  # written over or cut short in place, keeping its inode: noticed
        head = _head(path)  # here, before SQLite, which may not read it for a long time
        if head == _MAGIC:
            files.headed = True
        elif head is not None and len(head) >= len(_MAGIC):
            return "the state file was overwritten while the CPU ran", True
        elif head is not None and files.headed:  # (a new file in WAL mode has no page yet)
            return "the state file was cut short while the CPU ran", True
    return None


_MAGIC = b"SQLite format 3\x00"


def _head(path: Path) -> bytes | None:
    """The first bytes of the file at ``path`` (None: it cannot be read; ``gone`` has said
    what it can of the path)."""
    try:
        with open(path, "rb") as f:
            return f.read(len(_MAGIC))
    except OSError:
        return None


def _remove(path: Path) -> None:
    for suffix in ("", "-wal", "-shm", "-journal"):
        with contextlib.suppress(FileNotFoundError):
            os.unlink(f"{path}{suffix}")


def _tables(db: sqlite3.Connection) -> list[tuple[str, str]]:
    """The tables (name, CREATE statement) ``db`` can still read; none if it cannot."""
    try:
        rows = db.execute(
            "SELECT name, sql FROM main.sqlite_master WHERE type='table' AND sql IS NOT NULL"
        ).fetchall()
    except sqlite3.Error:
        return []
    return [(str(n), str(s)) for n, s in rows if not str(n).startswith("sqlite_")]


def _copy(db: sqlite3.Connection, table: str) -> None:
    """Copy ``table`` from ``main`` into the attached ``renew`` (the columns both have)."""
    quoted = '"' + table.replace('"', '""') + '"'
    old = [r[1] for r in db.execute(f"PRAGMA main.table_info({quoted})")]
    new = {r[1] for r in db.execute(f"PRAGMA renew.table_info({quoted})")}
    columns = ", ".join('"' + c.replace('"', '""') + '"' for c in old if c in new)
    if columns:
        db.execute(
            f"INSERT OR REPLACE INTO renew.{quoted} ({columns}) SELECT {columns} FROM main.{quoted}"
        )


def sync(path: Path, *, folder: bool = False) -> None:
    """``fsync`` the file (or, ``folder``, the folder: its entries) at ``path``; OSError
    when it cannot be done."""
    fd = os.open(path, (os.O_RDONLY | os.O_DIRECTORY) if folder else os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def set_aside(path: Path, label: str) -> list[Path]:
    """Rename what is at ``path`` and its ``-wal`` and ``-shm`` to ``FILE.<label>-N`` (with
    the same suffixes), the first N free for all three — never deleted; the new paths."""
    found = [s for s in ("", "-wal", "-shm") if os.path.lexists(f"{path}{s}")]
    n = 1
    while any(os.path.lexists(f"{path}.{label}-{n}{s}") for s in ("", "-wal", "-shm")):
        n += 1
    for suffix in found:
        os.rename(f"{path}{suffix}", f"{path}.{label}-{n}{suffix}")
    return [Path(f"{path}.{label}-{n}{suffix}") for suffix in found]


def rebuild(
    old: sqlite3.Connection,
    path: Path,
    *,
    schema: Callable[[sqlite3.Connection], None],
    fill: Callable[[sqlite3.Connection], object],
    release: Callable[[], None],
) -> tuple[list[str], list[str]]:
    """Build the state file at ``path`` anew: every table ``old`` (the open connection) can
    still read copied, then ``schema(db)`` (what is missing), then ``fill(db)`` (the rows
    waiting, with a whole staging); synced. ``release()`` then closes ``old`` (and what
    else holds the old file: closed last, a connection deletes its ``-wal`` by name), what
    is at the path goes aside as ``FILE.damaged-N`` and the new file takes its place.
    Returns the names the old files have now and the tables that could not be copied.
    ``OSError``/``sqlite3.Error`` when it cannot be built: nothing at the path changed,
    unless ``release`` was called."""
    tmp = Path(f"{path}.renew")
    _remove(tmp)
    tables = _tables(old)
    lost: list[str] = []
    try:
        new = sqlite3.connect(tmp, isolation_level=None)
        try:
            new.execute("PRAGMA page_size=1024")
            for _, sql in tables:
                new.execute(sql)
            schema(new)
        finally:
            new.close()
        old.execute("ATTACH DATABASE ? AS renew", (str(tmp),))
        try:
            for name, _ in tables:
                try:
                    _copy(old, name)
                except sqlite3.Error as exc:
                    lost.append(f"{name} ({exc})")
        finally:
            old.execute("DETACH DATABASE renew")
        new = sqlite3.connect(tmp, isolation_level=None)
        try:
            fill(new)
            new.execute("PRAGMA journal_mode=WAL")
        finally:
            new.close()
        sync(tmp)
    except BaseException:
        _remove(tmp)
        raise
    release()
    aside = [p.name for p in set_aside(path, "damaged")]
    os.replace(tmp, path)
    sync(path.parent, folder=True)
    return aside, lost
