"""Whose state a file holds, for a chart and a program of one name (web/harness/persist.py,
engine/state_identity.py): each has a default state file of its own; a file from before
the program was recorded is judged by whether it holds a chart's sequencer; the file of
the other name is looked at without a byte of it changing, and passed over, said so, when
it is another program's; a renamed chart keeps the state its GRAPH FB's instance DB is in,
and without a file of its own starts fresh naming that one beside it. The drill demo on the
virtual clock."""

from __future__ import annotations

from pathlib import Path

import pytest

from s7graph.engine.clock import VirtualClock
from s7graph.engine.diagnostics import EventId
from s7graph.engine.persistence import StateFileError, StateStore
from s7graph.engine.state_identity import Program
from s7graph.web.harness.persist import default_state, open_state, refusal
from s7graph.web.harness.session import ChartSession
from tests.engine.test_state_identity import SCL, _record, _written
from tests.engine.test_state_refusal_untouched import _files, _state
from tests.engine.test_state_trust import _cpu
from tests.paths import ROOT

DRILL = ROOT / "examples" / "drill"
MIXING = ROOT / "examples" / "mixing"
CHART = Program("chart", "far.s7g")


def _session() -> ChartSession:
    return ChartSession.load(DRILL / "drill.s7g", DRILL / "symbols.txt", VirtualClock(10**12))


def _chart_file(path: Path, program: Program | None, *, chart: Path = DRILL) -> Path:
    """A state file of the drill chart (or the one in folder ``chart``) after a scan,
    written by a run of ``program``."""
    session = (
        _session()
        if chart == DRILL
        else ChartSession.load(
            chart / f"{chart.name}.s7g", chart / "symbols.txt", VirtualClock(10**12)
        )
    )
    store = StateStore(path, program=program)
    session.start()
    session.scan()
    store.save(session.cpu)
    store.close()
    return path


def test_an_older_file_holding_no_charts_sequencer_is_refused_for_a_chart(
    tmp_path: Path,
) -> None:
    """The user's case: ``run far.s7g`` warm-restarted from ``far.scl``'s file, its own
    sequencer at its initial values with nothing but a note."""
    path = _written(tmp_path / "far.state.sqlite", None)
    before = _files(tmp_path)
    with pytest.raises(StateFileError) as info:
        open_state(path, _session().cpu, program=CHART)
    assert refusal(info.value) == (
        f"s7graph: error: {path}: written by an s7graph that did not record its program, and "
        "it holds no chart's sequencer (no GRAPH FB's instance DB): another program's (an "
        "S7-SCL or Python program of the same name?), not the chart far.s7g's; run far.s7g "
        "with a state file of its own (--state FILE), or start anew with --fresh (keeps this "
        f"file, the other program's state, as {path}.old-N)"
    )
    assert _files(tmp_path) == before


def test_an_older_charts_file_is_refused_for_a_program_without_a_graph_fb(
    tmp_path: Path,
) -> None:
    path = _chart_file(tmp_path / "far.state.sqlite", None)
    with pytest.raises(StateFileError) as info:
        open_state(path, _cpu(), program=SCL)
    assert info.value.problem == (
        "written by an s7graph that did not record its program, and it holds a chart's "
        "sequencer (DB1 FB1 'Seq_drill'): a chart's, not the S7-SCL program far.scl's"
    )


def test_an_older_charts_file_is_taken_by_the_chart_and_records_it(tmp_path: Path) -> None:
    path = _chart_file(tmp_path / "far.state.sqlite", None)
    opened = open_state(path, _session().cpu, program=CHART)
    opened.store.close()
    assert opened.report is not None and not opened.report.notes
    assert _record(path) == [("program_kind", "chart"), ("program_source", "far.s7g")]


def test_a_renamed_chart_takes_the_state_of_its_graph_fb_saying_so_and_records_its_name(
    tmp_path: Path,
) -> None:
    """``far.s7g`` renamed ``far_v2.s7g``, run with ``--state far.state.sqlite``."""
    path = _chart_file(tmp_path / "far.state.sqlite", CHART)
    renamed = Program("chart", "far_v2.s7g")
    opened = open_state(path, _session().cpu, program=renamed)
    opened.store.close()
    assert opened.report is not None and opened.report.notes == [
        "the file was the state of the chart far.s7g and now records the chart far_v2.s7g "
        "(a renamed source: its instance DBs are this program's)"
    ]
    assert _record(path) == [("program_kind", "chart"), ("program_source", "far_v2.s7g")]
    again = open_state(path, _session().cpu, program=renamed)
    again.store.close()
    assert again.report is not None and not again.report.notes


def test_a_renamed_chart_is_not_given_a_programs_state_of_the_same_blocks(
    tmp_path: Path,
) -> None:
    """Another kind stays another program, whatever its instance DBs."""
    path = _chart_file(tmp_path / "far.state.sqlite", Program("python", "far.py"))
    before = _files(tmp_path)
    with pytest.raises(StateFileError) as info:
        open_state(path, _session().cpu, program=CHART)
    assert info.value.problem == (
        "the state of another program: the Python program far.py's, not the chart far.s7g's"
    )
    assert _files(tmp_path) == before


def test_a_chart_and_a_program_of_one_name_default_to_state_files_of_their_own(
    tmp_path: Path,
) -> None:
    cpu = _cpu()
    assert default_state(tmp_path / "far.s7g", cpu) == (tmp_path / "far.state.sqlite", None)
    assert default_state(tmp_path / "far.scl", cpu) == (tmp_path / "far.scl.state.sqlite", None)
    assert default_state(tmp_path / "far.py", cpu) == (tmp_path / "far.py.state.sqlite", None)


def test_a_programs_older_state_file_of_the_shared_name_stays_its_own(tmp_path: Path) -> None:
    """An existing user's ``far.state.sqlite`` of ``far.scl``: still found."""
    path = _written(tmp_path / "far.state.sqlite", None)
    assert default_state(tmp_path / "far.scl", _cpu()) == (path, None)
    recorded = _written(tmp_path / "line.state.sqlite", Program("python", "line.py"))
    assert default_state(tmp_path / "line.py", _cpu()) == (recorded, None)


def test_a_file_of_the_programs_own_name_comes_before_the_shared_one(tmp_path: Path) -> None:
    _written(tmp_path / "far.state.sqlite", None)
    own = _written(tmp_path / "far.scl.state.sqlite", SCL)
    assert default_state(tmp_path / "far.scl", _cpu()) == (own, None)


@pytest.mark.parametrize("ended", ["stopped", "killed", "killed without its -shm"])
def test_another_programs_file_of_the_shared_name_is_passed_over_said_and_left_as_it_was(
    tmp_path: Path, ended: str
) -> None:
    recorded = [
        ("INSERT OR REPLACE INTO meta VALUES (?, ?)", ("program_kind", "scl")),
        ("INSERT OR REPLACE INTO meta VALUES (?, ?)", ("program_source", "far.scl")),
    ]
    killed = ended != "stopped"
    folder = _state(tmp_path / "project", recorded, killed=killed, shm=ended == "killed").parent
    for part in list(folder.iterdir()):
        part.rename(folder / part.name.replace("s.sqlite", "far.state.sqlite"))
    assert Path(f"{folder / 'far.state.sqlite'}-wal").exists() is killed
    before = _files(folder)
    path, note = default_state(folder / "far.s7g", _session().cpu)
    assert path == folder / "far.s7g.state.sqlite"
    assert note == (
        "far.state.sqlite is passed over (the state of another program: the S7-SCL program "
        "far.scl's, not the chart far.s7g's); the state of the chart far.s7g is kept in "
        "far.s7g.state.sqlite"
    )
    assert _files(folder) == before


def test_a_renamed_chart_without_a_state_file_of_its_own_starts_fresh_naming_the_one_beside_it(
    tmp_path: Path,
) -> None:
    """``far.s7g`` renamed ``far_v2.s7g``, run without ``--state``: before, a fresh start in
    ``far_v2.state.sqlite`` without a word about ``far.state.sqlite``. Now the note names it
    and how to carry it over, on stderr and in the diagnostic buffer; it is not taken, and
    the files beside the chart stay as they were — the S7-SCL program's among them, which
    is not named."""
    _chart_file(tmp_path / "far.state.sqlite", CHART)
    _written(tmp_path / "far.scl.state.sqlite", SCL)
    before = _files(tmp_path)
    cpu = _session().cpu
    path, note = default_state(tmp_path / "far_v2.s7g", cpu)
    assert path == tmp_path / "far_v2.state.sqlite"
    assert note == (
        "far.state.sqlite beside it holds the state of the chart far.s7g, whose instance DBs "
        "are the chart far_v2.s7g's (a renamed source?): not taken without --state; to carry "
        f"it over, run far_v2.s7g with --state {tmp_path / 'far.state.sqlite'}"
    )
    assert [(e.event_id, e.message) for e in cpu.diagnostics] == [(EventId.STATE_NOT_TAKEN, note)]
    assert _files(tmp_path) == before


def test_a_file_beside_a_chart_is_named_only_when_its_instance_dbs_are_the_charts(
    tmp_path: Path,
) -> None:
    """Another chart's file (the mixing chart's GRAPH FB) and another kind's file (the same
    blocks, a Python program's) are not this chart's state: a fresh start, no note."""
    _chart_file(tmp_path / "mixing.state.sqlite", None, chart=MIXING)
    _chart_file(tmp_path / "far.py.state.sqlite", Program("python", "far.py"))
    cpu = _session().cpu
    assert default_state(tmp_path / "far_v2.s7g", cpu) == (
        tmp_path / "far_v2.state.sqlite",
        None,
    )
    assert not list(cpu.diagnostics)


def test_several_files_beside_a_chart_holding_its_state_are_all_named(tmp_path: Path) -> None:
    _chart_file(tmp_path / "far.state.sqlite", CHART)
    _chart_file(tmp_path / "old copy.state.sqlite", None)
    path, note = default_state(tmp_path / "far_v2.s7g", _session().cpu)
    assert path == tmp_path / "far_v2.state.sqlite"
    assert note == (
        "far.state.sqlite (the state of the chart far.s7g), old copy.state.sqlite (a state "
        "that records no program) beside it hold states whose instance DBs are the chart "
        "far_v2.s7g's (a renamed source?): none taken without --state; to carry one over, "
        "run far_v2.s7g with --state FILE"
    )
