"""Whose state a file holds, for a chart and a program of one name (web/harness/persist.py,
engine/state_identity.py): each has a default state file of its own; a file from before
the program was recorded is judged by whether it holds a chart's sequencer; the file of
the other name is looked at without a byte of it changing, and passed over, said so, when
it is another program's; a renamed chart keeps the state its GRAPH FB's instance DB is in.
The drill demo on the virtual clock."""

from __future__ import annotations

from pathlib import Path

import pytest

from s7graph.engine.clock import VirtualClock
from s7graph.engine.persistence import StateFileError, StateStore
from s7graph.engine.state_identity import Program
from s7graph.web.harness.persist import default_state, open_state, refusal
from s7graph.web.harness.session import ChartSession
from tests.engine.test_state_identity import SCL, _record, _written
from tests.engine.test_state_refusal_untouched import _files, _state
from tests.engine.test_state_trust import _cpu
from tests.paths import ROOT

DRILL = ROOT / "examples" / "drill"
CHART = Program("chart", "far.s7g")


def _session() -> ChartSession:
    return ChartSession.load(DRILL / "drill.s7g", DRILL / "symbols.txt", VirtualClock(10**12))


def _chart_file(path: Path, program: Program | None) -> Path:
    """A state file of the drill chart after a scan, written by a run of ``program``."""
    session = _session()
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
