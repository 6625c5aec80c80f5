"""A state file records the program it belongs to — its kind (chart, S7-SCL program, Python
program) and its source file's name — and another program's file is refused naming both,
never warm-restarted from (engine/state_identity.py, engine/persistence.py); a changed
version of the same program is carried over as before; a file from before the record is
taken and records it once written."""

from __future__ import annotations

import sqlite3
from pathlib import Path

import pytest

from s7graph.engine import Cpu
from s7graph.engine.persistence import StateFileError, StateStore
from s7graph.engine.state_identity import Program
from tests.engine.test_state_trust import _cpu, acc_grown

SCL = Program("scl", "far.scl")
CHART = Program("chart", "far.s7g")


def _written(path: Path, program: Program | None) -> Path:
    """A state file of ``_cpu()`` after a scan, written by a run of ``program``."""
    store = StateStore(path, program=program)
    cpu = _cpu()
    cpu.start()
    cpu.scan()
    store.save(cpu)
    store.close()
    return path


def _record(path: Path) -> list[tuple[str, str]]:
    with sqlite3.connect(path) as con:
        rows = con.execute(
            "SELECT key, value FROM meta WHERE key LIKE 'program_%' ORDER BY key"
        ).fetchall()
    con.close()
    return rows


def _refusal(path: Path, program: Program | None, cpu: Cpu | None = None) -> StateFileError:
    store = StateStore(path, program=program)
    try:
        with pytest.raises(StateFileError) as info:
            store.load(cpu or _cpu())
    finally:
        store.close()
    return info.value


def test_a_file_records_the_program_of_the_run_that_writes_it(tmp_path: Path) -> None:
    path = _written(tmp_path / "s.sqlite", SCL)
    assert _record(path) == [("program_kind", "scl"), ("program_source", "far.scl")]


def test_the_file_of_another_kind_of_program_is_refused_naming_both(tmp_path: Path) -> None:
    path = _written(tmp_path / "s.sqlite", SCL)
    before = path.read_bytes()
    refused = _refusal(path, CHART)
    assert refused.problem == (
        "the state of another program: the S7-SCL program far.scl's, not the chart far.s7g's"
    )
    assert refused.way_out == (
        "run far.s7g with a state file of its own (--state FILE), or start anew with --fresh "
        f"(keeps this file, the other program's state, as {path}.old-N)"
    )
    assert path.read_bytes() == before


def test_the_file_of_another_source_file_of_the_same_kind_is_refused(tmp_path: Path) -> None:
    path = _written(tmp_path / "s.sqlite", Program("python", "line_a.py"))
    refused = _refusal(path, Program("python", "line_b.py"))
    assert refused.problem == (
        "the state of another program: the Python program line_a.py's, not the Python "
        "program line_b.py's"
    )


def test_a_changed_version_of_the_same_program_is_carried_over_not_refused(
    tmp_path: Path,
) -> None:
    path = _written(tmp_path / "s.sqlite", SCL)
    store = StateStore(path, program=SCL)
    try:
        report = store.load(_cpu(acc_grown))
    finally:
        store.close()
    assert report is not None and report.changed == [2]
    assert "DB2 FB2 'acc': new, at their initial values: extra" in report.notes


def test_a_file_from_before_the_record_is_taken_and_records_the_program_once_written(
    tmp_path: Path,
) -> None:
    path = _written(tmp_path / "s.sqlite", None)
    assert _record(path) == []
    store = StateStore(path, program=SCL)
    try:
        assert store.load(_cpu()) is not None
        assert _record(path) == []  # read-only until taken
        store.open_writing()
    finally:
        store.close()
    assert _record(path) == [("program_kind", "scl"), ("program_source", "far.scl")]


def test_a_store_opened_without_a_program_neither_checks_nor_changes_the_record(
    tmp_path: Path,
) -> None:
    path = _written(tmp_path / "s.sqlite", SCL)
    store = StateStore(path)
    try:
        assert store.load(_cpu()) is not None
        store.save(_cpu())
    finally:
        store.close()
    assert _record(path) == [("program_kind", "scl"), ("program_source", "far.scl")]


@pytest.mark.parametrize(
    ("key", "value", "problem"),
    [
        ("program_kind", "plc", "malformed meta 'program_kind': 'plc'"),
        ("program_source", "../far.scl", "malformed meta 'program_source': '../far.scl'"),
        ("program_source", "", "malformed meta 'program_source': ''"),
    ],
)
def test_a_program_record_this_code_never_writes_is_refused_naming_its_key(
    tmp_path: Path, key: str, value: str, problem: str
) -> None:
    path = _written(tmp_path / "s.sqlite", SCL)
    with sqlite3.connect(path) as con:
        con.execute("UPDATE meta SET value=? WHERE key=?", (value, key))
    con.close()
    assert _refusal(path, SCL).problem == problem
    assert _refusal(path, None).problem == problem  # whoever reads it


def test_a_kind_without_its_source_is_refused(tmp_path: Path) -> None:
    path = _written(tmp_path / "s.sqlite", SCL)
    with sqlite3.connect(path) as con:
        con.execute("DELETE FROM meta WHERE key='program_source'")
    con.close()
    assert _refusal(path, SCL).problem == "malformed meta 'program_source': ''"


def test_a_file_built_anew_under_the_running_cpu_keeps_its_program(tmp_path: Path) -> None:
    path = tmp_path / "s.sqlite"
    store = StateStore(path, program=SCL)
    cpu = _cpu()
    cpu.start()
    try:
        store.save(cpu)
        path.unlink()
        cpu.scan()
        store.save(cpu)  # noticed, and built anew from the running CPU
    finally:
        store.close()
    assert (tmp_path / "s.sqlite.damaged-1-wal").exists()
    assert _record(path) == [("program_kind", "scl"), ("program_source", "far.scl")]


def test_the_kind_of_program_is_told_by_its_files_suffix() -> None:
    assert Program.of(Path("x/far.s7g")) == CHART
    assert Program.of(Path("far.SCL")) == Program("scl", "far.SCL")
    assert Program.of(Path("far.py")) == Program("python", "far.py")
    assert str(Program.of(Path("far.awl"))) == "the program far.awl"
