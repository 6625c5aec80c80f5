"""``s7graph audit --state FILE`` on a file whose audit it cannot read: one line naming the
file, that it is not a state file s7graph can read the audit of, and what was wrong in
words — never SQLite's or Python's bare message — exit 2; the file read without a change
(web/access/audit.py opens it read-only)."""

from __future__ import annotations

import sqlite3
from pathlib import Path

import pytest

from s7graph.engine.persistence import StateFileError, StateStore
from s7graph.web.cli.audit import audit_command

T0 = 1_700_000_000 * 10**9


def _state(path: Path, rows: int = 3) -> Path:
    """A state file with ``rows`` audit rows (closed: no -wal, no -shm)."""
    store = StateStore(path)
    for n in range(rows):
        store.log_audit(T0 + n, "ann", "ack", "x" * 900)
    store.close()
    return path


def _edit(path: Path, *statements: tuple[str, tuple[object, ...]]) -> None:
    with sqlite3.connect(path) as con:
        for sql, args in statements:
            con.execute(sql, args)
    con.close()


def _files(path: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(path.parent.iterdir())}


def _refused(path: Path, capsys: pytest.CaptureFixture[str], *, summary: bool = False) -> str:
    """The one line ``s7graph audit`` prints for ``path`` (exit 2, the file unchanged)."""
    before = _files(path)
    capsys.readouterr()
    assert audit_command(path, None, summary=summary) == 2
    out, err = capsys.readouterr()
    assert out == ""
    assert _files(path) == before  # nothing written, no -wal or -shm left
    (line,) = err.splitlines()
    prefix = f"s7graph: error: {path}: not a state file s7graph can read the audit of ("
    assert line.startswith(prefix) and line.endswith(")")
    return line.removeprefix(prefix)[:-1]


@pytest.mark.parametrize("summary", [False, True], ids=["rows", "summary"])
def test_a_garbled_file_is_refused_naming_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], summary: bool
) -> None:
    """Before: ``s7graph: error: file is not a database`` — no file named."""
    path = tmp_path / "s.sqlite"
    path.write_bytes(b"garbage, not SQLite " * 400)
    assert _refused(path, capsys, summary=summary) == "it is not an SQLite database"


def test_a_truncated_state_file_is_refused_as_damaged(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Before: ``s7graph: error: database disk image is malformed``."""
    path = _state(tmp_path / "s.sqlite", rows=50)
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    assert _refused(path, capsys).startswith("it is damaged")


def test_an_audit_row_with_a_text_time_is_refused_naming_the_row(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Before: ``s7graph: error: invalid literal for int() with base 10: 'x'``."""
    path = _state(tmp_path / "s.sqlite")
    _edit(path, ("UPDATE audit SET t_ns='x' WHERE id=2", ()))
    assert _refused(path, capsys) == "audit row 2: t_ns is 'x', not an integer"


def test_a_schema_that_is_not_utf8_is_refused_in_words(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Before: ``Could not decode to UTF-8 column 'name' with text '…'``, the bytes with it."""
    path = _state(tmp_path / "s.sqlite")
    name = b"ju\xffk"
    _edit(
        path,
        ("CREATE TABLE junk (x)", ()),
        ("PRAGMA writable_schema=ON", ()),
        (
            "UPDATE sqlite_master SET name=CAST(? AS TEXT), tbl_name=CAST(? AS TEXT), "
            "sql=CAST(? AS TEXT) WHERE name='junk'",
            (name, name, b'CREATE TABLE "' + name + b'" (x)'),
        ),
    )
    assert _refused(path, capsys) == "column 'name' holds text that is not UTF-8"


def test_an_audit_table_of_another_shape_is_refused_naming_what_it_lacks(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Before: ``s7graph: error: no such column: id``."""
    path = tmp_path / "s.sqlite"
    _edit(path, ("CREATE TABLE audit (x)", ()))
    assert _refused(path, capsys) == "its audit table has no column id, t_ns, user, action, detail"


def test_a_summary_row_with_a_text_count_is_refused_naming_the_row(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _state(tmp_path / "s.sqlite")
    _edit(
        path,
        (
            "CREATE TABLE audit_summary (day TEXT, user TEXT, op TEXT, outcome TEXT, "
            "count INTEGER, first_ns INTEGER, last_ns INTEGER)",
            (),
        ),
        (
            "INSERT INTO audit_summary "
            "VALUES ('2026-11-18', 'ann', 'ack', 'applied', 'many', 1, 2)",
            (),
        ),
    )
    problem = "audit_summary row of '2026-11-18': count is 'many', not an integer"
    assert _refused(path, capsys, summary=True) == problem


def test_a_state_file_that_reads_is_listed_and_left_as_it_was(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _state(tmp_path / "s.sqlite")
    before = _files(path)
    assert audit_command(path, None) == 0
    assert len(capsys.readouterr().out.splitlines()) == 3
    assert _files(path) == before


def test_a_file_a_running_cpu_replaces_while_it_is_read_is_tried_again(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A CPU building its state file anew moves it aside for a moment: "unable to open"
    then is tried again (3 tries) before it is the answer; any other problem is at once."""
    from s7graph.web.access import audit

    state = _state(tmp_path / "s.sqlite")
    real = audit._read_once
    calls: list[int] = []

    def flaky(path: Path, read: object) -> object:
        calls.append(1)
        if len(calls) == 1:
            raise audit.UnreadableAudit(path, "unable to open database file")
        return real(path, read)  # type: ignore[arg-type]

    monkeypatch.setattr(audit, "time", type("T", (), {"sleep": staticmethod(lambda s: None)}))
    monkeypatch.setattr(audit, "_read_once", flaky)
    assert len(audit.read_audit(state)) == 3 and len(calls) == 2
    calls.clear()

    def gone(path: Path, read: object) -> object:
        calls.append(1)
        raise audit.UnreadableAudit(path, "unable to open database file")

    monkeypatch.setattr(audit, "_read_once", gone)
    with pytest.raises(audit.UnreadableAudit, match="unable to open"):
        audit.read_audit(state)
    assert len(calls) == audit._OPEN_TRIES


def test_a_folder_or_an_empty_file_is_refused_in_the_words_run_refuses_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """One check for both (``engine.persistence.not_a_state_file``), with its way out but
    a run's ``--fresh``; before, audit kept a copy of run's words and a folder's went
    without its way out. A folder was once ``no such state file``, an empty file an empty
    audit with exit 0."""
    empty = tmp_path / "empty.sqlite"
    empty.write_bytes(b"")
    for path, said in (
        (
            tmp_path,
            "a directory, not a state file; give --state the path of a file (or move the "
            "directory away)",
        ),
        (empty, "empty file (0 bytes), not a state file"),
    ):
        with pytest.raises(StateFileError) as run:
            StateStore(path)
        assert audit_command(path, None) == 2
        assert capsys.readouterr() == ("", f"s7graph: error: {path}: {said}\n")
        assert said.startswith(run.value.problem) and said.endswith(run.value.way_out)
    assert empty.read_bytes() == b""


def test_a_missing_file_is_no_such_state_file_and_is_not_made(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "none.sqlite"
    assert audit_command(path, None) == 2
    assert capsys.readouterr() == ("", f"s7graph: error: {path}: no such state file\n")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("since", ["99999999999h", "9999-12-31", "100000000000000000000d"])
def test_a_since_beyond_what_the_file_can_hold_lists_the_rows_in_range(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], since: str
) -> None:
    """An age before 1970 lists every row, a time past 2262 none; before, both were an
    internal error (``Python int too large to convert to SQLite INTEGER``)."""
    path = _state(tmp_path / "s.sqlite")
    assert audit_command(path, since) == 0
    rows = len(capsys.readouterr().out.splitlines())
    assert rows == (0 if since == "9999-12-31" else 3)


@pytest.mark.parametrize("summary", [False, True], ids=["rows", "summary"])
def test_another_applications_sqlite_file_is_refused_as_run_refuses_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], summary: bool
) -> None:
    """Before: exit 0 and nothing printed, as if the trail were empty."""
    path = tmp_path / "other.sqlite"
    _edit(
        path, ("CREATE TABLE contacts (name TEXT)", ()), ("INSERT INTO contacts VALUES ('x')", ())
    )
    before = _files(path)
    capsys.readouterr()
    assert audit_command(path, None, summary=summary) == 2
    out, err = capsys.readouterr()
    assert out == ""
    assert err == f"s7graph: error: {path}: an SQLite file, but not an s7graph state file\n"
    assert _files(path) == before


def test_an_sqlite_file_without_a_table_is_refused_as_run_refuses_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "s.sqlite"
    _edit(path, ("CREATE TABLE t (x)", ()), ("DROP TABLE t", ()))
    assert audit_command(path, None) == 2
    (line,) = capsys.readouterr().err.splitlines()
    assert line == f"s7graph: error: {path}: an SQLite file without a single table: its " + (
        "content may be in a write-ahead log that is missing (copied without its -wal file?)"
    )
