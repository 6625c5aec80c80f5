"""A state file records the program it belongs to — its kind (chart, S7-SCL program, Python
program) and its source file's name — and another program's file is refused naming both,
never warm-restarted from (engine/state_identity.py, engine/persistence.py); a changed
version of the same program is carried over as before, and so is a renamed source of the
same kind whose instance DBs the file holds, said in a note; a file from before the record
is taken and records it once written."""

from __future__ import annotations

import sqlite3
from collections.abc import Callable
from pathlib import Path

import pytest

from s7graph.engine import Cpu
from s7graph.engine.persistence import StateFileError, StateStore
from s7graph.engine.state_identity import Evidence, Held, Program, beside, foreign, recognised
from tests.engine.test_state_trust import _cpu, acc_grown, other

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


@pytest.mark.parametrize(
    ("cpu", "why"),
    [(lambda: _cpu(other), "another FB"), (lambda: _cpu(number=3), "another DB number")],
)
def test_another_source_file_of_the_same_kind_whose_instance_dbs_differ_is_refused(
    tmp_path: Path, cpu: Callable[[], Cpu], why: str
) -> None:
    path = _written(tmp_path / "s.sqlite", Program("python", "line_a.py"))
    before = path.read_bytes()
    refused = _refusal(path, Program("python", "line_b.py"), cpu())
    assert refused.problem == (
        "the state of another program: the Python program line_a.py's, not the Python "
        "program line_b.py's"
    ), why
    assert path.read_bytes() == before


def test_a_renamed_source_whose_instance_dbs_the_file_holds_is_carried_over_saying_so(
    tmp_path: Path,
) -> None:
    path = _written(tmp_path / "s.sqlite", Program("python", "line_a.py"))
    store = StateStore(path, program=Program("python", "line_b.py"))
    cpu = _cpu(acc_grown)
    try:
        report = store.load(cpu)
        assert _record(path)[1] == ("program_source", "line_a.py")  # read-only until taken
        store.open_writing()
    finally:
        store.close()
    assert report is not None and report.changed == [2]
    assert report.notes[0] == (
        "the file was the state of the Python program line_a.py and now records the Python "
        "program line_b.py (a renamed source: its instance DBs are this program's)"
    )
    assert "DB2 FB2 'acc': new, at their initial values: extra" in report.notes
    assert _record(path) == [("program_kind", "python"), ("program_source", "line_b.py")]


def test_a_renamed_source_unchanged_otherwise_makes_no_hot_restart(tmp_path: Path) -> None:
    """As a download: the file's instance DBs say the same program, not the same code."""
    path = _written(tmp_path / "s.sqlite", Program("scl", "line_a.scl"))
    renamed, same = _cpu(), _cpu()
    for program, cpu in (
        (Program("scl", "line_b.scl"), renamed),
        (Program("scl", "line_a.scl"), same),
    ):
        store = StateStore(path, program=program)
        try:
            store.load(cpu)
        finally:
            store.close()
    assert "program download" in renamed.hot_blockers
    assert "program download" not in same.hot_blockers


GRAPH = Held(1, "FB1", "Seq_drill", chart=True)
ACC = Held(2, "FB2", "acc", chart=False)
TIMER = Held(9, "SFB4", "TON", chart=False)
OWN = {(1, "FB1", "Seq_drill"), (2, "FB2", "acc")}


@pytest.mark.parametrize(
    ("kind", "held", "same"),
    [
        ("chart", [GRAPH, ACC], True),
        ("chart", [GRAPH, TIMER], True),  # a system block's instance: anyone's
        ("chart", [ACC], False),  # no GRAPH FB's: not a chart's state
        ("chart", [GRAPH._replace(name="Seq_mix")], False),
        ("chart", [GRAPH._replace(number=3)], False),
        ("scl", [ACC], True),
        ("scl", [ACC, Held(5, "FB5", "gone", chart=False)], False),  # one not the program's
        ("python", [], False),  # nothing to recognise it by
        ("python", [TIMER], False),
    ],
)
def test_a_renamed_source_is_recognised_by_the_fb_instance_dbs_the_file_holds(
    kind: str, held: list[Held], same: bool
) -> None:
    assert recognised(Program(kind, "x"), held, OWN) is same


def _seen(saved: Program | None, held: tuple[Held, ...], *, has_chart: bool = True) -> Evidence:
    """What a file holding ``held`` and recording ``saved`` shows a program of ``OWN``."""
    return Evidence(saved, bool(held), held, frozenset(OWN), has_chart)


@pytest.mark.parametrize(
    ("mine", "seen", "whose", "named"),
    [
        (CHART, _seen(CHART, (GRAPH, ACC)), None, "the state of the chart far.s7g"),
        (Program("chart", "near.s7g"), _seen(CHART, (GRAPH, ACC)), None, "the state of the"),
        (CHART, _seen(SCL, (ACC,)), "the state of another program: the S7-SCL", None),
        (CHART, _seen(None, (GRAPH,)), None, "a state that records no program"),
        (CHART, _seen(None, (ACC,)), "written by an s7graph that did not record", None),
        (SCL, _seen(None, (GRAPH,), has_chart=False), "it holds a chart's sequencer (DB1", None),
        (SCL, _seen(None, (ACC, Held(5, "FB5", "gone", chart=False))), None, None),
    ],
)
def test_whose_a_file_is_and_whether_it_is_named_beside_are_judged_on_one_record(
    mine: Program, seen: Evidence, whose: str | None, named: str | None
) -> None:
    """``foreign`` and ``beside`` take the same ``Evidence``, gathered once from the file
    and the CPU: a file ``foreign`` finds another's is never named beside a run."""
    why = foreign(mine, seen)
    assert why is None if whose is None else why is not None and whose in why
    said = beside(mine, seen)
    assert said is None if named is None else said is not None and said.startswith(named)
    with pytest.raises(AttributeError):
        seen.saved = mine  # type: ignore[misc]


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
