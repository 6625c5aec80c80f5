"""A chart's state file is trusted only when recognised, its sequencer state included, and
``--restart hot`` is honoured or refused, never turned warm (web/harness/persist.py,
engine/persistence.py, sequencer/state.py): the drill demo in one CPU on the virtual clock.

S7-400 ("Programming with STEP 7", Operating Modes) allows a manual hot restart only when
the CPU's parameters allow it, the program was not changed in STOP, and the CPU went to
STOP by the mode selector, a programmed STOP, an OB not loaded or a programming device;
after a power cut in RUN it restarts hot by itself."""

from __future__ import annotations

import sqlite3
import zlib
from pathlib import Path
from typing import Any

import msgspec
import pytest

from s7graph.engine.clock import VirtualClock
from s7graph.engine.modes import CpuMode
from s7graph.engine.persistence import StateFileError, unpack_instance
from s7graph.sequencer.state import GraphState
from s7graph.web.harness.persist import HOT_WAY_OUT, HotRestartRefused, open_state, refusal
from s7graph.web.harness.session import ChartSession
from tests.web.harness.test_restart_position import DRILL, Drill, _faulted, _steps, _times

DAY_NS = 86_400 * 10**9


def _row(path: Path) -> dict[str, Any]:
    with sqlite3.connect(path) as con:
        (blob,) = con.execute("SELECT data FROM instances WHERE number=1").fetchone()
    con.close()
    return unpack_instance(blob)


def _put_row(path: Path, data: dict[str, Any]) -> None:
    with sqlite3.connect(path) as con:
        con.execute(
            "UPDATE instances SET data=? WHERE number=1",
            (zlib.compress(msgspec.msgpack.encode(data)),),
        )
    con.close()


def _with_step_time(path: Path, t_ns: int) -> None:
    """The running step S2's T (and U) on disk set to ``t_ns``."""
    data = _row(path)
    st = GraphState.from_state(data["G7_STATE"])
    st.t_ns[1] = st.u_ns[1] = t_ns
    data["G7_STATE"] = st.to_state()
    _put_row(path, data)


def _session() -> ChartSession:
    return ChartSession.load(DRILL / "drill.s7g", DRILL / "symbols.txt", VirtualClock(10**12))


def _refused(path: Path, restart: str = "warm") -> StateFileError:
    session = _session()
    with pytest.raises(StateFileError) as info:
        open_state(path, session.cpu, restart=restart)
    return info.value


def _stopped(tmp_path: Path, restart: str = "hot") -> Drill:
    """The drill, S2 faulted, stopped by a STOP request and saved as a clean end is."""
    drill, _ = _faulted(tmp_path, restart)
    drill.cpu.stop("s7graph run ended")
    drill.store.save(drill.cpu, clean=True)
    drill.kill()
    return drill


def test_a_row_without_its_sequencer_state_is_refused_not_started_in_the_initial_step(
    tmp_path: Path,
) -> None:
    drill = _stopped(tmp_path)
    path = drill.store.path
    data = _row(path)
    del data["G7_STATE"]
    _put_row(path, data)
    error = _refused(path, "hot")
    assert error.problem == "malformed state of DB1: no G7_STATE (its sequencer state)"


def test_a_step_time_of_31_years_is_refused(tmp_path: Path) -> None:
    drill = _stopped(tmp_path)
    _with_step_time(drill.store.path, 10**18)
    problem = _refused(drill.store.path, "hot").problem
    assert problem.startswith("malformed state of DB1: step index 1: T = 31.7 years")


def test_a_step_waiting_longer_than_s7s_time_range_still_resumes_hot(tmp_path: Path) -> None:
    """S7's TIME ends at 24.8 days; the runtime counts on past it, so a sequencer that waited
    30 days in a step must come back."""
    drill = _stopped(tmp_path)
    _with_step_time(drill.store.path, 30 * DAY_NS)
    again = Drill(drill.store.path, drill.plant, restart="hot")
    assert again.cpu.last_restart == "hot" and again.state.t_ns[1] == 30 * DAY_NS


def test_a_clean_stop_of_a_warm_run_allows_a_manual_hot_restart(tmp_path: Path) -> None:
    """As the mode selector's STOP on S7-400: a warm run's clean end keeps the hot-restart
    image, and the next run may resume where the sequencer was."""
    drill = _stopped(tmp_path, "warm")
    on_disk = GraphState.from_state(_row(drill.store.path)["G7_STATE"])
    again = Drill(drill.store.path, drill.plant, restart="hot")
    assert again.cpu.last_restart == "hot" and again.cpu.mode is CpuMode.RUN
    assert _steps(again.state, again) == [2] and _times(again.state) == _times(on_disk)


def test_hot_after_an_unclean_end_of_a_warm_run_is_refused_not_turned_warm(
    tmp_path: Path,
) -> None:
    """A warm run keeps no hot-restart image while it runs: killed, it leaves none."""
    drill, _ = _faulted(tmp_path, "warm")
    drill.kill()
    error = _refused(drill.store.path, "hot")
    assert isinstance(error, HotRestartRefused)
    assert error.problem == (
        "cannot restart hot: the last run kept no hot-restart image (a run keeps one when "
        "started with --restart hot, or when it stops cleanly)"
    )
    line = f"s7graph: error: {drill.store.path}: {error.problem}; {HOT_WAY_OUT}"
    assert refusal(error) == line


def test_hot_after_a_stop_by_an_error_is_refused_naming_it(tmp_path: Path) -> None:
    """A block aborted by cycle monitoring is no STOP S7-400 resumes from; a warm restart is
    still possible."""
    drill, _ = _faulted(tmp_path, "hot")
    drill.cpu.abort("plant demo_plant.py")
    drill.store.save(drill.cpu, clean=True)
    drill.kill()
    error = _refused(drill.store.path, "hot")
    assert error.problem == (
        "cannot restart hot: STOP by an error (block aborted by cycle monitoring)"
    )
    again = Drill(drill.store.path, drill.plant, restart="warm")
    assert again.cpu.last_restart == "warm" and _steps(again.state, again) == [1]


def test_hot_after_a_killed_hot_run_resumes_as_after_a_power_cut(tmp_path: Path) -> None:
    drill, _ = _faulted(tmp_path, "hot")
    drill.kill()
    session = _session()
    opened = open_state(drill.store.path, session.cpu, restart="hot")
    assert opened.report is not None and not opened.report.clean
    session.cpu.start("hot")
    opened.store.close()
    assert session.cpu.last_restart == "hot"


def test_a_refused_hot_restart_leaves_the_state_file_as_it_was(tmp_path: Path) -> None:
    drill, _ = _faulted(tmp_path, "warm")
    drill.kill()
    path = drill.store.path
    before = _dump(path)
    _refused(path, "hot")
    assert _dump(path) == before


def _dump(path: Path) -> list[tuple[object, ...]]:
    with sqlite3.connect(path) as con:
        rows = [("meta", *r) for r in con.execute("SELECT * FROM meta ORDER BY key")]
        rows += [("diag", *r) for r in con.execute("SELECT * FROM diagnostics ORDER BY seq")]
        rows += [("inst", *r) for r in con.execute("SELECT * FROM instances")]
    con.close()
    return rows
