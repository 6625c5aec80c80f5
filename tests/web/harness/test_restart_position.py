"""A restart that keeps the position (sequencer/fb.py, sequencer/change/carry.py, web/harness/
persist.py): the drill demo in one CPU on the virtual clock with its state file, as
``s7graph run`` keeps it; "killed" after the last commit, restarted from the file.

hot (OB101) resumes active steps, T and U, latched faults and pending messages exactly as
persisted; warm (OB100) writes the position to the diagnostic buffer, then initializes;
no restart acknowledges a message; a changed chart is carried over by step number."""

from __future__ import annotations

import json
import sqlite3
import zlib
from pathlib import Path
from typing import Any

import pytest

from s7graph.engine.clock import VirtualClock
from s7graph.engine.diagnostics import EventId
from s7graph.engine.modes import CpuMode
from s7graph.engine.persistence import FORMAT, StateFileError, unpack_instance
from s7graph.sequencer.state import GraphState
from s7graph.sfb.alarms import MessageState, message_list
from s7graph.web.harness.persist import OpenedState, open_state
from s7graph.web.harness.plant import LoadedPlant, load_plant
from s7graph.web.harness.session import ChartSession
from tests.paths import ROOT

DRILL = ROOT / "examples" / "drill"
SV2 = "Seq_drill/DB1/S2/SV"


def demo_plant(**attrs: object) -> LoadedPlant:
    """The demo plant; ``IDLE_MS=300, SLOW_EVERY=1``: every piece faults S2 at once."""
    plant = load_plant(DRILL / "demo_plant.py")
    for name, value in attrs.items():
        setattr(plant.plant, name, value)
    return plant


class Drill:
    """The drill demo in a CPU with its state file; the plant (the machine) outlives it."""

    def __init__(
        self, state: Path, plant: LoadedPlant, *, restart: str = "warm", chart: Path | None = None
    ) -> None:
        self.clock = VirtualClock(10**12)  # another run's clock: far from the last one's
        self.session = ChartSession.load(
            chart or DRILL / "drill.s7g", DRILL / "symbols.txt", self.clock
        )
        self.cpu = self.session.cpu
        self.plant = plant
        self.opened: OpenedState = open_state(state, self.cpu, hot=restart == "hot")
        self.store = self.opened.store
        self.record = self.cpu.start(restart)
        self.store.log_alarms(self.record.alarms, 0)
        self.store.save(self.cpu, clean=False)
        self.writes = 0

    @property
    def state(self) -> GraphState:
        return self.session.graph.state

    def run(self, ms: int) -> None:
        for _ in range(ms // 10):
            record = self.cpu.scan()
            self.plant.cycle(self.session, self.clock.now_ns() // 1_000_000, 10)
            self.store.log_alarms(record.alarms, 0)
            batch = self.store.stage(self.cpu)
            if batch is not None:
                self.store.write(batch)
                self.writes += 1
            self.clock.advance(10)

    def until(self, what: Any, limit_ms: int = 60_000) -> None:
        for _ in range(limit_ms // 10):
            if what(self):
                return
            self.run(10)
        raise AssertionError("never happened")

    def kill(self) -> None:
        """SIGKILL after the last commit: nothing more is written."""
        self.store.close()

    def persisted(self) -> GraphState:
        data = self.store.instance_state(1)
        assert data is not None
        return GraphState.from_state(data["G7_STATE"])  # type: ignore[arg-type]


def _steps(st: GraphState, drill: Drill) -> list[int]:
    return sorted(drill.session.cc.step_numbers[i] for i in st.active)


def _times(st: GraphState) -> list[tuple[int, int, bool]]:
    return [(st.t_ns[i], st.u_ns[i], st.sv_err[i]) for i in range(st.n_steps)]


def _faulted(tmp_path: Path, restart: str = "warm") -> tuple[Drill, LoadedPlant]:
    plant = demo_plant(IDLE_MS=300, SLOW_EVERY=1)
    drill = Drill(tmp_path / "drill.sqlite", plant, restart=restart)
    drill.until(lambda d: any(d.state.sv_err))
    drill.run(1230)
    return drill, plant


def test_a_staged_row_holds_its_scans_state_not_a_later_ones(tmp_path: Path) -> None:
    """Staging encodes the sequencer's lists where they are, without copying them: the row
    written later, after more scans switched steps, still holds the staged scan's state
    (its call counter and clock time of the last call too)."""
    drill = Drill(tmp_path / "drill.sqlite", demo_plant())
    drill.run(3000)
    staged = drill.state.to_state()
    batch = drill.store.stage(drill.cpu, full=True)
    assert batch is not None
    for _ in range(400):  # on, unstaged, until the sequencer moved on
        drill.cpu.scan()
        drill.plant.cycle(drill.session, drill.clock.now_ns() // 1_000_000, 10)
        drill.clock.advance(10)
    assert drill.state.active != staged["active"] and drill.state.calls != staged["calls"]
    drill.store.write(batch)
    row = drill.store.instance_state(1)["G7_STATE"]  # type: ignore[index]
    assert GraphState.from_state(row) == GraphState.from_state(staged)


@pytest.mark.parametrize("restart", ["warm", "hot"])
def test_quiet_scans_write_nothing_but_a_time_mark_every_half_second(
    tmp_path: Path, restart: str
) -> None:
    """S2 held by its fault: 200 scans, T runs, nothing else changes — 4 writes of the
    instance row, so a restart loses at most 500 ms of a running step time."""
    drill, _ = _faulted(tmp_path, restart)
    before = drill.writes
    drill.run(2000)
    assert drill.writes == before + 4
    lag = drill.state.step_t_ms(1) - drill.persisted().step_t_ms(1)
    assert 0 <= lag <= 500
    assert drill.persisted().step_u_ms(1) == drill.state.step_u_ms(1)  # frozen by the fault


def test_hot_restart_resumes_steps_times_faults_and_messages_as_persisted(tmp_path: Path) -> None:
    drill, plant = _faulted(tmp_path, "hot")
    drill.run(700)
    on_disk = drill.persisted()
    messages = message_list(drill.cpu).entries()
    drill.kill()

    again = Drill(tmp_path / "drill.sqlite", plant, restart="hot")
    assert again.cpu.last_restart == "hot" and again.cpu.mode is CpuMode.RUN
    assert _steps(again.state, again) == [2]
    assert again.session.get("Clamp_workp")  # set by S2's S1 action, kept by the hot restart
    assert _times(again.state) == _times(on_disk)  # T, U and the latch as last persisted
    assert message_list(again.cpu).entries() == messages  # incoming, unacknowledged
    (msg,) = messages
    assert msg.msg_id == SV2 and msg.state is MessageState.INCOMING and not msg.acked
    resumed = [e for e in again.cpu.diagnostics if e.event_id == EventId.SEQUENCER_POSITION]
    assert "hot restart resumes Seq_drill/DB1, in S2 'Clamp'" in resumed[-1].message
    assert "supervision fault" in resumed[-1].message
    t_before, u_before = again.state.t_ns[1], again.state.u_ns[1]
    again.run(500)  # the time goes on from there, U frozen by the fault
    assert again.state.t_ns[1] == t_before + 490_000_000
    assert again.state.u_ns[1] == u_before
    assert _steps(again.state, again) == [2] and again.state.sv_err[1]


def test_hot_restart_in_the_scan_a_step_began_runs_its_s1_action_once(tmp_path: Path) -> None:
    """Killed right after the scan that entered S5 "Dwell" (``S1 N pieces := pieces + 1``):
    that scan's event bits are on disk, and the first call after the restart clears them
    as it would have without the kill — the piece is counted once, not in every call."""
    plant = demo_plant()
    drill = Drill(tmp_path / "drill.sqlite", plant, restart="hot")
    drill.until(lambda d: d.state.x[4])
    assert drill.session.graph.state.vars["pieces"] == 1
    assert drill.persisted().ev[4]  # the S1 event of the last call, as persisted
    drill.kill()

    again = Drill(tmp_path / "drill.sqlite", plant, restart="hot")
    assert _steps(again.state, again) == [5]
    again.run(300)  # still dwelling (500 ms)
    assert _steps(again.state, again) == [5]
    assert again.state.vars["pieces"] == 1 and not again.state.ev[4]


def test_warm_restart_writes_the_position_first_and_acknowledges_nothing(tmp_path: Path) -> None:
    drill, plant = _faulted(tmp_path)
    drill.kill()

    again = Drill(tmp_path / "drill.sqlite", plant)
    assert _steps(again.state, again) == [1]  # initialized
    entries = list(again.cpu.diagnostics)
    ids = [e.event_id for e in entries]
    at = ids.index(EventId.SEQUENCER_POSITION)
    assert at < ids.index(EventId.STOP_TO_STARTUP, at)  # written before the restart acts
    assert entries[at].message.startswith("warm restart initializes Seq_drill/DB1, in S2")
    assert "supervision fault" in entries[at].message
    (msg,) = message_list(again.cpu).entries()
    assert msg.msg_id == SV2 and msg.state is MessageState.OUTGOING and not msg.acked
    assert msg.reason == "warm restart (OB100)"
    rows = again.store.alarms()
    assert [r["state"] for r in rows] == ["incoming", "outgoing"]
    assert rows[-1]["reason"] == "warm restart (OB100)"
    again.kill()
    third = Drill(tmp_path / "drill.sqlite", plant)  # and again: still listed, still waiting
    (still,) = [m for m in message_list(third.cpu).entries() if m.event_id == msg.event_id]
    assert still.state is MessageState.OUTGOING and not still.acked


def test_cold_restart_leaves_the_pending_message_listed_with_its_reason(tmp_path: Path) -> None:
    drill, plant = _faulted(tmp_path)
    drill.kill()
    again = Drill(tmp_path / "drill.sqlite", plant, restart="cold")
    assert _steps(again.state, again) == [1] and again.cpu.last_restart == "cold"
    (msg,) = message_list(again.cpu).entries()
    assert msg.state is MessageState.OUTGOING and not msg.acked
    assert msg.reason == "cold restart (OB102)"


@pytest.mark.parametrize(("restart", "kept"), [("warm", True), ("hot", True), ("cold", False)])
def test_level_overrides_survive_a_warm_or_hot_restart_and_a_cold_one_clears_them(
    tmp_path: Path, restart: str, kept: bool
) -> None:
    """An engineer switched supervisions and interlocks off (``en_sv``/``en_il`` hold EN_SV
    and EN_IL at 0): the overrides live in the instance DB, so a restart from the state file
    keeps them — but a cold restart, which resets every instance DB."""
    plant = demo_plant(IDLE_MS=300, SLOW_EVERY=1)  # every piece would fault S2 at once
    drill = Drill(tmp_path / "drill.sqlite", plant, restart="hot")
    drill.session.graph.set_level("EN_SV", False)
    drill.session.graph.set_level("EN_IL", False)
    drill.run(100)
    assert drill.persisted().levels == {"EN_SV": False, "EN_IL": False}
    drill.kill()

    again = Drill(tmp_path / "drill.sqlite", plant, restart=restart)
    assert again.cpu.last_restart == restart
    expected = {"EN_SV": False, "EN_IL": False} if kept else {}
    assert again.session.graph.levels == expected
    again.run(3000)  # S2 would fault after its supervision time
    assert again.state.sv_enabled is not kept and again.state.il_enabled is not kept
    assert any(again.state.sv_err) is not kept
    again.session.graph.set_level("EN_SV", None)  # the pin decides again, and that is kept
    again.run(20)
    assert again.persisted().levels == ({"EN_IL": False} if kept else {})


def _edited(tmp_path: Path, *pairs: tuple[str, str]) -> Path:
    text = (DRILL / "drill.s7g").read_text(encoding="utf-8")
    for old, new in pairs:
        assert old in text
        text = text.replace(old, new)
    path = tmp_path / "drill.s7g"
    path.write_text(text, encoding="utf-8")
    return path


def _in_s4(tmp_path: Path) -> tuple[Drill, LoadedPlant]:
    plant = demo_plant(IDLE_MS=300)
    drill = Drill(tmp_path / "drill.sqlite", plant, restart="hot")
    drill.until(lambda d: _steps(d.state, d) == [4])
    drill.run(600)
    return drill, plant


def test_a_changed_chart_carries_the_active_step_over_with_its_times(tmp_path: Path) -> None:
    drill, plant = _in_s4(tmp_path)
    on_disk = drill.persisted()
    drill.kill()
    chart = _edited(
        tmp_path,
        ('STEP S4 "Lower":', 'STEP S4 "Lower slowly":'),
        ("dwell : TIME := T#500MS;", "dwell : TIME := T#500MS;  spare : INT := 7;"),
    )
    again = Drill(tmp_path / "drill.sqlite", plant, restart="hot", chart=chart)
    report = again.opened.report
    assert report is not None and report.changed == [1]
    assert any("active steps kept: S4" in n for n in report.notes)
    assert any("new variables, at their initial values: spare" in n for n in report.notes)
    assert again.cpu.last_restart == "warm"  # a changed program: hot restart refused
    carried = [e for e in again.cpu.diagnostics if e.event_id == EventId.STATE_CARRIED_OVER]
    assert carried and "S4" in carried[0].message
    position = [e for e in again.cpu.diagnostics if e.event_id == EventId.SEQUENCER_POSITION]
    assert f"in S4 'Lower slowly' T={on_disk.step_t_ms(3)} ms" in position[-1].message


def test_a_chart_that_lost_the_active_step_reports_it_and_runs_on(tmp_path: Path) -> None:
    drill, plant = _in_s4(tmp_path)
    drill.kill()
    chart = _edited(
        tmp_path,
        ('STEP S4 "Lower":\n    N "Lower_drill";\n  END_STEP\n', ""),
        ('"Clamped, dry" FROM S2 TO S4', '"Clamped, dry" FROM S2 TO S5'),
        ('"Coolant flows" FROM S3 TO S4', '"Coolant flows" FROM S3 TO S5'),
        ('TRANSITION T5 "Down" FROM S4 TO S5 := "Drill_down";\n', ""),
    )
    again = Drill(tmp_path / "drill.sqlite", plant, restart="hot", chart=chart)
    report = again.opened.report
    assert report is not None
    assert any("active steps gone (no longer active): S4" in n for n in report.notes)
    again.run(200)  # no IndexError, no silent STOP
    assert again.cpu.mode is CpuMode.RUN


def test_the_state_of_another_chart_is_refused(tmp_path: Path) -> None:
    drill, plant = _in_s4(tmp_path)
    drill.kill()
    chart = _edited(tmp_path, ('FUNCTION_BLOCK "Seq_drill"', 'FUNCTION_BLOCK "Seq_mill"'))
    with pytest.raises(StateFileError) as info:
        Drill(tmp_path / "drill.sqlite", plant, chart=chart)
    assert info.value.problem == "DB1 holds an instance of FB1 'Seq_drill', not of FB1 'Seq_mill'"


@pytest.mark.parametrize(
    ("field", "value", "fragment"),
    [
        ("x", [True], "'x' does not hold 7 entries"),
        ("active", [9], "'active' is [9]"),
        ("mode", "TURBO", "unknown mode 'TURBO'"),
        ("t_since", "soon", "'t_since' does not hold 7 entries"),
    ],
)
def test_a_malformed_sequencer_state_is_refused(
    tmp_path: Path, field: str, value: object, fragment: str
) -> None:
    drill, plant = _in_s4(tmp_path)
    drill.kill()
    path = tmp_path / "drill.sqlite"
    with sqlite3.connect(path) as con:
        (blob,) = con.execute("SELECT data FROM instances WHERE number=1").fetchone()
        data = unpack_instance(blob)
        data["G7_STATE"][field] = value
        con.execute(
            "UPDATE instances SET data=? WHERE number=1",
            (zlib.compress(json.dumps(data).encode()),),
        )
    con.close()
    with pytest.raises(StateFileError) as info:
        Drill(path, plant)
    assert "malformed state of DB1" in info.value.problem and fragment in info.value.problem


def test_a_file_of_format_4_with_every_list_in_full_resumes_under_hot(tmp_path: Path) -> None:
    """State file format 4 kept every list of the sequencer in full: such a file is read,
    resumes the position, and is marked with the current format."""
    drill, plant = _faulted(tmp_path, "hot")
    on_disk = drill.persisted()
    drill.kill()
    path = tmp_path / "drill.sqlite"
    with sqlite3.connect(path) as con:
        (blob,) = con.execute("SELECT data FROM instances WHERE number=1").fetchone()
        data = unpack_instance(blob)
        data["G7_STATE"] = on_disk.to_state()
        compact = on_disk.state_view()
        assert any(isinstance(compact[k], dict) for k in ("il_err", "crit_flt", "t_since"))
        assert all(
            isinstance(v, list)
            for k, v in data["G7_STATE"].items()
            if k in compact and isinstance(compact[k], dict) and "fill" in compact[k]
        )
        con.execute(
            "UPDATE instances SET data=? WHERE number=1",
            (zlib.compress(json.dumps(data).encode()),),
        )
        con.execute("UPDATE meta SET value='s7graph-state 4' WHERE key='format'")
    con.close()
    again = Drill(path, plant, restart="hot")
    assert _steps(again.state, again) == [2] and _times(again.state) == _times(on_disk)
    with sqlite3.connect(path) as con:
        (mark,) = con.execute("SELECT value FROM meta WHERE key='format'").fetchone()
    con.close()
    assert mark == FORMAT
