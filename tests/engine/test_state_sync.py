"""A commit of the state file is on the disk when it returns: SQLite's write-ahead log with
``synchronous=FULL`` (in WAL mode NORMAL may lose the last commits on a power cut,
https://www.sqlite.org/pragma.html#pragma_synchronous). A command's reply *applied* waits
for that commit, so it survives a power cut."""

from __future__ import annotations

from pathlib import Path

import pytest

from s7graph.engine.persistence import SYNCHRONOUS, StateStore
from s7graph.web.access.audit import AuditStore

FULL = 2  # PRAGMA synchronous's answer for FULL


def test_the_state_file_and_its_audit_connection_sync_every_commit(tmp_path: Path) -> None:
    assert SYNCHRONOUS == "FULL"
    store = StateStore(tmp_path / "state.sqlite")
    audit = AuditStore(tmp_path / "state.sqlite", state=store)
    try:
        for db in (store._db, audit._db):
            assert db.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
            assert db.execute("PRAGMA synchronous").fetchone()[0] == FULL
    finally:
        audit.close()
        store.close()


def test_a_synchronous_setting_sqlite_does_not_know_is_refused(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="synchronous must be EXTRA, FULL, NORMAL or OFF"):
        StateStore(tmp_path / "state.sqlite", synchronous="FULL; DROP TABLE meta")
