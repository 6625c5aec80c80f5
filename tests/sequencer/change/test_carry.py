"""``carry_over`` (sequencer/change/carry.py): the one function taking a GRAPH FB's state to a
changed chart — by step number, transitions by number, variables by name — pure, with a
report of what it could not keep; and the chart fingerprint it is chosen by."""

from __future__ import annotations

from pathlib import Path

from s7graph.sequencer.change.carry import ChartShape, carry_over, fingerprint
from s7graph.sequencer.compiled import CompiledChart
from s7graph.sequencer.cycle import new_state
from s7graph.web.harness.session import compile_text, load_chart
from tests.paths import EXAMPLES

DRILL = EXAMPLES / "drill"


def _drill(tmp_path: Path, *edits: tuple[str, str]) -> CompiledChart:
    text = (DRILL / "drill.s7g").read_text(encoding="utf-8")
    for old, new in edits:
        assert old in text
        text = text.replace(old, new)
    path = tmp_path / f"drill{len(list(tmp_path.iterdir()))}.s7g"
    path.write_text(text, encoding="utf-8")
    return load_chart(path, DRILL / "symbols.txt")[0]


def test_the_fingerprint_names_what_the_chart_does_not_how_it_is_written(tmp_path: Path) -> None:
    same = _drill(tmp_path, ('STEP S2 "Clamp"', 'STEP   S2   "Clamp"'), ("(*", "(* moved"))
    other = _drill(tmp_path, ("S5.T >= dwell", "S5.T > dwell"))
    assert fingerprint(same) == fingerprint(_drill(tmp_path))
    assert fingerprint(other) != fingerprint(same)


def test_active_steps_keep_their_times_and_what_is_gone_is_reported(tmp_path: Path) -> None:
    old = _drill(tmp_path)
    new = _drill(
        tmp_path,
        (
            'STEP S3 "Coolant" "No coolant pressure":\n    SUPERVISION := S3.U > T#2S;\n'
            '    S1 S "Cool_pump_on";\n  END_STEP\n',
            "",
        ),
        ('"Clamped, coolant" FROM S2 TO S3', '"Clamped, coolant" FROM S2 TO S4'),
        ('TRANSITION T4 "Coolant flows" FROM S3 TO S4 := "Cool_press_ok";\n', ""),
        ("pieces : INT := 0;", "pieces : DINT := 0;  spare : BOOL := TRUE;"),
    )
    st = new_state(old)
    for i, t_ms in ((2, 700), (3, 1200)):  # S3 and S4, a simultaneous pair for the test
        st.x[i] = True
        st.active.append(i)
        st.t_ns[i] = t_ms * 1_000_000
        st.u_ns[i] = (t_ms - 100) * 1_000_000
    st.sv_err[2] = True
    st.vars.update(pieces=7, dwell=900)
    before = st.to_state()
    carried, report = carry_over(ChartShape.of(old), st, new)
    assert st.to_state() == before  # pure
    assert report.kept == [4] and report.gone == [3] and report.faults_gone == [3]
    k = new.step_index[4]
    assert carried.active == [k] and carried.x[k]
    assert (carried.step_t_ms(k), carried.step_u_ms(k)) == (1200, 1100)
    assert carried.vars == {"pieces": 0, "dwell": 900, "spare": True}
    assert report.vars_reset == ["pieces"] and report.vars_new == ["spare"]
    lines = report.lines()
    assert lines[0] == "chart changed; carried over by step number: active steps kept: S4"
    assert "active steps gone (no longer active): S3" in lines


def test_a_latched_fault_whose_supervision_a_download_removes_has_no_cause_left(
    tmp_path: Path,
) -> None:
    """S3's supervision fault stays latched — it still waits for its acknowledgement — but
    with the supervision gone nothing holds its cause: an acknowledgement releases it (a
    kept cause made ``ack`` refuse it for good: "the cause persists")."""
    old = _drill(tmp_path)
    new = _drill(tmp_path, ("    SUPERVISION := S3.U > T#2S;\n", ""))
    i = old.step_index[3]
    st = new_state(old)
    st.x[i] = True
    st.active.append(i)
    st.sv_cond[i] = st.sv_err[i] = True
    carried, _ = carry_over(ChartShape.of(old), st, new)
    k = new.step_index[3]
    assert carried.sv_err[k] and not carried.sv_cond[k]
    kept, _ = carry_over(ChartShape.of(old), st, _drill(tmp_path, ("T#2S", "T#3S")))
    assert kept.sv_cond[k] and kept.sv_err[k]  # a supervision still there keeps its cause


ONE = """FUNCTION_BLOCK "Two" FB 1 DB 1
VAR
  n : INT := 3;
END_VAR
SEQUENCE 1
  INITIAL_STEP S1:
  END_STEP
  STEP S2:
  END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.0;
  TRANSITION T2 FROM S2 TO S1 := I0.1;
END_SEQUENCE
END_FUNCTION_BLOCK
"""
SECOND = """SEQUENCE 2
  INITIAL_STEP S20:
  END_STEP
  STEP S21:
  END_STEP
  TRANSITION T20 FROM S20 TO S21 := I0.2;
  TRANSITION T21 FROM S21 TO S20 := I0.3;
END_SEQUENCE
"""


def test_a_new_sequencer_starts_in_its_initial_steps_and_a_changed_type_says_its_restart() -> None:
    """The one rule of a download and a restart with a changed chart: a sequencer the old
    version did not have starts in its initial steps (times from 0) — the other sequencers
    go on — also from a state file saved before the shape kept the sequencers' numbers;
    a variable whose type changed restarts at its initial value, the line saying so."""
    old = compile_text(ONE, "one.s7g")[0]
    new = compile_text(
        ONE.replace("n : INT := 3;", "n : REAL := 2.5;").replace(
            "END_SEQUENCE\n", "END_SEQUENCE\n" + SECOND
        ),
        "two.s7g",
    )[0]
    st = new_state(old)
    i = old.step_index[2]
    st.x[i] = True
    st.active.append(i)
    st.t_ns[i] = 900_000_000
    st.last_ns = 5_000_000_000
    st.vars["n"] = 7
    saved = ChartShape.of(old).to_json()
    older = {k: v for k, v in saved.items() if k != "sequences"}  # a state file of before
    for shape in (ChartShape.from_json(saved), ChartShape.from_json(older)):
        carried, report = carry_over(shape, st, new)
        s2, s20 = new.step_index[2], new.step_index[20]
        assert sorted(carried.active) == sorted([s2, s20])
        assert carried.step_t_ms(s2) == 900 and carried.step_t_ms(s20) == 0
        assert carried.act_ns[s20] == st.last_ns and not carried.x[new.step_index[21]]
        assert carried.vars["n"] == 2.5
        lines = report.lines()
        assert "new sequencer 2: its initial step S20 becomes active" in lines
        assert "variable n: INT → REAL, restarts at its initial value 2.5" in lines
    moved = new_state(old)  # S2, active, moved into the new sequencer: it goes on from S2
    moved.x[i] = True
    moved.active.append(i)
    into = compile_text(
        ONE.replace("  STEP S2:\n  END_STEP\n", "")
        .replace("FROM S1 TO S2", "FROM S1 TO S1")
        .replace("  TRANSITION T2 FROM S2 TO S1 := I0.1;\n", "")
        .replace("END_SEQUENCE\n", "END_SEQUENCE\n" + SECOND.replace("S21", "S2")),
        "moved.s7g",
    )[0]
    carried, report = carry_over(ChartShape.of(old), moved, into)
    assert carried.active == [into.step_index[2]]
    assert "new sequencer 2: active step S2 goes on in it; its initial steps stay inactive" in (
        report.lines()
    )
