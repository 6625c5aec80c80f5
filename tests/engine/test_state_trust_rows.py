"""Rows SQLite types only by affinity, and text that is not UTF-8, are damage like any other
(engine/persistence.py, engine/state_checks.py): refused in the one line that names the
file and the row, with the way out (``--fresh``) — never an internal error, never an
exception's class in the line, never the file changed."""

from __future__ import annotations

import json
import re
import sqlite3
import zlib
from pathlib import Path

import msgspec
import pytest

from s7graph.engine import Cpu
from s7graph.engine.persistence import StateFileError, StateStore
from s7graph.web.cli import main
from s7graph.web.harness.persist import open_state, refusal
from tests.engine.test_state_trust import _cpu, _edit, _written
from tests.paths import ROOT

_CLASS = re.compile(r"\b[A-Z]\w*(Error|Exception)\b")


def _line(path: Path, cpu: Cpu | None = None) -> str:
    """The refusal line ``s7graph run`` prints for ``path`` (the store closed again)."""
    with pytest.raises(StateFileError) as info:
        open_state(path, cpu or _cpu())
    assert info.value.path == path
    return refusal(info.value)


def _fresh(path: Path, problem: str) -> str:
    return (
        f"s7graph: error: {path}: {problem}; start anew with --fresh "
        f"(keeps this file as {path}.old-N)"
    )


def _content(path: Path) -> list[tuple[object, ...]]:
    """Every row of every table, text as bytes (what is not UTF-8 too), in an order of
    their own (rewriting a row as it was may move it)."""
    con = sqlite3.connect(path)
    con.text_factory = bytes
    tables = [r[0] for r in con.execute("SELECT name FROM sqlite_master WHERE type='table'")]
    rows = [
        (table, *row)
        for table in sorted(tables)
        for row in con.execute(f'SELECT * FROM "{table.decode()}"')
    ]
    con.close()
    return sorted(rows, key=repr)


def _damaged(
    tmp_path: Path, sql: str, args: tuple[object, ...] = ()
) -> tuple[Path, list[tuple[object, ...]]]:
    """A written state file with ``sql`` run on it: the path and its content."""
    path = _written(tmp_path / "s.sqlite")
    _edit(path, (sql, args))
    return path, _content(path)


def _diag_row(path: Path, seq: int) -> tuple[object, ...] | None:
    with sqlite3.connect(path) as con:
        row = con.execute("SELECT * FROM diagnostics WHERE seq=?", (seq,)).fetchone()
    con.close()
    return None if row is None else tuple(row)


def test_a_diagnostics_row_with_nulls_is_refused_naming_the_file(tmp_path: Path) -> None:
    """Before: ``internal error: TypeError: int() argument must be …, not 'NoneType'``."""
    path, before = _damaged(
        tmp_path,
        "INSERT INTO diagnostics (seq, t_ns, event_id, block, message, address) "
        "VALUES (99, NULL, NULL, NULL, NULL, NULL)",
    )
    problem = "malformed diagnostics row 99: t_ns is NULL, not an integer"
    assert _line(path) == _fresh(path, problem)
    assert _content(path) == before  # left as it was, the row with it
    assert _diag_row(path, 99) == (99, None, None, None, None, None, 0, 0, 0)


@pytest.mark.parametrize(
    ("values", "problem"),
    [
        ("'x', 1, 'b', 'm', 'a', 0, 0, 0", "t_ns is 'x', not an integer"),
        ("1, 'y', 'b', 'm', 'a', 0, 0, 0", "event_id is 'y', not an integer"),
        ("1, 1.5, 'b', 'm', 'a', 0, 0, 0", "event_id is 1.5, not an integer"),
        ("1, 1, 'b', 'm', 'a', 'z', 0, 0", "ob is 'z', not an integer"),
        ("1, 1, 'b', 'm', 'a', 0, 0, 'w'", "wall_ns is 'w', not an integer"),
        ("1, 99999999, 'b', 'm', 'a', 0, 0, 0", "event_id is 99999999, not an event id (a WORD)"),
        ("1, 1, 'b', x'00ff', 'a', 0, 0, 0", "message is b'\\x00\\xff', not text"),
    ],
)
def test_a_diagnostics_row_of_the_wrong_types_is_refused_naming_its_column(
    tmp_path: Path, values: str, problem: str
) -> None:
    """Before: a text where a number belongs was ``internal error: ValueError: …``."""
    path, before = _damaged(
        tmp_path,
        "INSERT INTO diagnostics (seq, t_ns, event_id, block, message, address, ob, priority, "
        f"wall_ns) VALUES (99, {values})",
    )
    assert _line(path) == _fresh(path, f"malformed diagnostics row 99: {problem}")
    assert _content(path) == before


def test_a_diagnostics_row_without_its_texts_is_read_with_them_empty(tmp_path: Path) -> None:
    """NULL block, message and address (the table allows them) are not damage."""
    path = _written(tmp_path / "s.sqlite")
    _edit(path, ("INSERT INTO diagnostics (seq, t_ns, event_id) VALUES (99, 7, 16896)", ()))
    cpu = _cpu()
    store = StateStore(path)
    store.load(cpu)
    store.close()
    entry = list(cpu.diagnostics)[-1]
    assert (entry.t_ns, entry.event_id, entry.block, entry.message) == (7, 0x4200, "", "")


@pytest.mark.parametrize("key", ["memory", "hot_memory", "forces", "mode", "format"])
def test_a_meta_value_that_is_not_utf8_is_refused_naming_its_key(tmp_path: Path, key: str) -> None:
    """Before: ``internal error: OperationalError: Could not decode to UTF-8 column 'value'``
    for every key but ``format``, whose refusal did not name it."""
    path, before = _damaged(
        tmp_path, "INSERT OR REPLACE INTO meta VALUES (?, CAST(? AS TEXT))", (key, b"{\xff}")
    )
    problem = f"not a readable state file (meta {key!r} is not UTF-8 text)"
    assert _line(path) == _fresh(path, problem)
    assert _content(path) == before


def test_text_that_is_not_utf8_in_another_table_is_refused_naming_its_column(
    tmp_path: Path,
) -> None:
    """Not the bytes SQLite could not decode (they may be long, and are not text): the
    column."""
    path, before = _damaged(
        tmp_path, "UPDATE instances SET name=CAST(? AS TEXT) WHERE number=2", (b"ac\xffc",)
    )
    problem = "not a readable state file (column 'name' holds text that is not UTF-8)"
    assert _line(path) == _fresh(path, problem)
    assert _content(path) == before


@pytest.mark.parametrize(
    ("sql", "args", "problem"),
    [
        (
            "UPDATE meta SET value='{' WHERE key='memory'",
            (),
            "malformed memory image: not valid JSON (Expecting property name enclosed in "
            "double quotes: line 1 column 2 (char 1))",
        ),
        (
            "UPDATE instances SET data=? WHERE number=2",
            (zlib.compress(msgspec.msgpack.encode({"total": 1})[:-1]),),
            "malformed data of DB2: not valid MessagePack (Input data was truncated)",
        ),
        (
            "UPDATE instances SET data=? WHERE number=2",
            (b"\x00\xff garbage",),
            "malformed data of DB2: not compressed data (Error -3 while decompressing data: "
            "incorrect header check)",
        ),
        (
            "UPDATE instances SET shape='{' WHERE number=2",
            (),
            "malformed data of DB2: not valid JSON (Expecting property name enclosed in "
            "double quotes: line 1 column 2 (char 1))",
        ),
        (
            "UPDATE meta SET value=? WHERE key='memory'",
            (json.dumps({"markers": 5}),),
            "malformed memory image: 'markers' is int, not an object",
        ),
    ],
)
def test_a_refusal_says_what_was_wrong_in_words_without_an_exception_class(
    tmp_path: Path, sql: str, args: tuple[object, ...], problem: str
) -> None:
    """Before: ``malformed memory image: JSONDecodeError: …``, ``malformed data of DB1:
    DecodeError: …``."""
    path, before = _damaged(tmp_path, sql, args)
    line = _line(path)
    assert line == _fresh(path, problem)
    assert _CLASS.search(line) is None
    assert _content(path) == before


def test_run_refuses_a_diagnostics_row_with_nulls_in_one_line_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``s7graph run`` on the probe's file: one line naming it, no internal error."""
    drill = ROOT / "examples" / "drill"
    state = tmp_path / "drill.sqlite"
    run = ["run", str(drill / "drill.s7g"), "--symbols", str(drill / "symbols.txt")]
    run += ["--no-web", "--state", str(state), "--duration-s", "0.1"]
    assert main(run) == 0
    _edit(
        state,
        ("INSERT INTO diagnostics (seq, t_ns, event_id) VALUES (9999, NULL, NULL)", ()),
    )
    before = _content(state)
    capsys.readouterr()
    assert main(run) == 2
    err = capsys.readouterr().err
    problem = "malformed diagnostics row 9999: t_ns is NULL, not an integer"
    assert err.splitlines() == [_fresh(state, problem)]
    assert _content(state) == before


@pytest.mark.parametrize("column", ["seq", "t_ns", "message"])
def test_a_diagnostics_table_without_one_of_its_columns_is_refused_naming_it(
    tmp_path: Path, column: str
) -> None:
    """Before: ``internal error: KeyError: 't_ns'`` (``OperationalError: no such column:
    seq``). The columns added since (``ob``, ``priority``, ``wall_ns``) a file from before
    may lack: those read as their defaults."""
    path, before = _damaged(
        tmp_path, f"ALTER TABLE diagnostics RENAME COLUMN {column} TO was_{column}"
    )
    problem = f"the diagnostics table has no {column} column"
    assert _line(path) == _fresh(path, problem)
    assert _content(path) == before


def test_a_damaged_schema_sqlite_cannot_quote_as_utf8_is_refused_in_words(
    tmp_path: Path,
) -> None:
    """SQLite's own message quotes the damaged schema, byte 0xBA with it: Python could not
    decode the message. Before: ``internal error: 'utf-8' codec can't decode byte 0xba``."""
    path = _written(tmp_path / "s.sqlite")
    _edit(
        path,
        ("PRAGMA writable_schema=ON", ()),
        (
            "UPDATE sqlite_master SET sql=CAST(? AS TEXT) WHERE name='audit'",
            (b"CREATE TABLE audit(t_ns INTEGER NOT \xbaULL)",),
        ),
    )
    problem = (
        'not a readable state file (malformed database schema (audit) - near "\ufffdULL": '
        "syntax error)"
    )
    assert _line(path) == _fresh(path, problem)
