"""``carry_over`` (sequencer/change/carry.py): the one function taking a GRAPH FB's state to a
changed chart — by step number, transitions by number, variables by name — pure, with a
report of what it could not keep; and the chart fingerprint it is chosen by."""

from __future__ import annotations

from pathlib import Path

from s7graph.sequencer.change.carry import ChartShape, carry_over, fingerprint
from s7graph.sequencer.compiled import CompiledChart
from s7graph.sequencer.cycle import new_state
from s7graph.web.harness.session import load_chart
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
