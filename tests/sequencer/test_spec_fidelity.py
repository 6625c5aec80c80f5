"""S7-GRAPH behaviours a new user checks first, through ``s7graph sim`` and the virtual clock:
block options as the defaults of their pins, timers and counters as contacts, every
activation of a step raising S1 (whichever sequencer activates it, and an initial step whose
transition already holds), ``N C`` assignments under the interlock, SQ_ISOFF.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from s7graph.engine.clock import VirtualClock
from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.compile import compile_chart
from s7graph.sequencer.params import markdown_table
from s7graph.sequencer.text.parse import parse_chart
from s7graph.web.harness.session import ChartSession
from tests.sequencer.helpers import Chart, chart, enter, seq, sim_trace, source, two_steps

# ---------------------------------------------------------------- block options → pins

SKIPPING = seq("""
  INITIAL_STEP S1 "a": END_STEP
  STEP S2 "b": N Q0.2; END_STEP
  STEP S3 "c": END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.0;
  TRANSITION T2 FROM S2 TO S3 := I0.1;
  TRANSITION T3 FROM S3 TO S1 := FALSE;
""")
BOTH_HOLD = [{"at_ms": 10, "set": {"I0.0": True, "I0.1": True}}]


def test_block_option_skip_steps_is_the_default_of_en_sskip(tmp_path: Path) -> None:
    """S7-GRAPH block setting "Skip steps" with the run-time pin EN_SSKIP (STEP7 comprehensive guide
    vol. 2, ch. 14, STEP7 comprehensive guide vol. 2, ch. 14): with the USER set and EN_SSKIP
    unwired, SKIP_STEPS := TRUE skips S2."""
    text = source(SKIPPING, header="SKIP_STEPS := TRUE;", params="USER")
    rc, lines = sim_trace(tmp_path, text, BOTH_HOLD, cycles=3, watch="EN_SSKIP,SSKIP_ENABLED,Q0.2")
    assert rc == 0
    assert lines[0]["values"] == {"EN_SSKIP": True, "SSKIP_ENABLED": True, "Q0.2": False}
    assert lines[1]["events"] == [["S1", "S2"], ["S2", "S3"]] and lines[1]["active"] == ["S3"]
    assert lines[1]["values"]["Q0.2"] is False  # S2 never active: its N row never ran


def test_a_stimulus_on_en_sskip_wins_over_the_option(tmp_path: Path) -> None:
    """The pin's initial value is the option; a value written to the pin wins from then on
    (docs/semantics.md, "Block options")."""
    text = source(SKIPPING, header="SKIP_STEPS := TRUE;", params="USER")
    stim = [{"at_ms": 0, "set": {"EN_SSKIP": False}}, *BOTH_HOLD]
    rc, lines = sim_trace(tmp_path, text, stim, cycles=3, watch="SSKIP_ENABLED,Q0.2")
    assert rc == 0 and lines[0]["values"]["SSKIP_ENABLED"] is False
    assert lines[1]["active"] == ["S2"] and lines[1]["values"]["Q0.2"] is True
    assert lines[2]["active"] == ["S3"]


SUPERVISED = seq("""
  INITIAL_STEP S1 "a": END_STEP
  STEP S2 "b": SUPERVISION := I0.5; END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.0;
  TRANSITION T2 FROM S2 TO S1 := FALSE;
""")
FAULT_COMES_AND_GOES = [
    {"at_ms": 10, "set": {"I0.0": True}},
    {"at_ms": 30, "set": {"I0.5": True}},
    {"at_ms": 50, "set": {"I0.5": False}},
]


def test_block_option_ack_required_false_is_the_default_of_en_ackreq(tmp_path: Path) -> None:
    """S7-GRAPH block setting "Acknowledge errors" with the pin EN_ACKREQ (manual 7-25):
    with ACK_REQUIRED := FALSE and EN_ACKREQ unwired a fault clears with its cause."""
    text = source(SUPERVISED, header="ACK_REQUIRED := FALSE;", params="USER")
    rc, lines = sim_trace(
        tmp_path, text, FAULT_COMES_AND_GOES, cycles=7, watch="EN_ACKREQ,ACKREQ_ENABLED,FAULT"
    )
    assert rc == 0
    assert lines[0]["values"] == {"EN_ACKREQ": False, "ACKREQ_ENABLED": False, "FAULT": False}
    assert [line["values"]["FAULT"] for line in lines] == [False] * 3 + [True] * 2 + [False] * 2


def test_a_stimulus_on_en_ackreq_wins_over_the_option(tmp_path: Path) -> None:
    """EN_ACKREQ set by a stimulus overrides ACK_REQUIRED := FALSE: the fault stays latched."""
    text = source(SUPERVISED, header="ACK_REQUIRED := FALSE;", params="USER")
    stim = [{"at_ms": 0, "set": {"EN_ACKREQ": True}}, *FAULT_COMES_AND_GOES]
    rc, lines = sim_trace(tmp_path, text, stim, cycles=7, watch="ACKREQ_ENABLED,FAULT")
    assert rc == 0 and lines[-1]["values"] == {"ACKREQ_ENABLED": True, "FAULT": True}


@pytest.mark.parametrize("options", ["SKIP_STEPS := TRUE; ACK_REQUIRED := FALSE;", ""])
def test_the_instance_db_starts_with_every_option_in_its_pins(options: str) -> None:
    """Every option ↔ pin pair (sequencer/params.py OPTION_DEFAULTS): before the first
    call the instance DB holds the options in EN_SSKIP/EN_ACKREQ and SSKIP_ENABLED/
    ACKREQ_ENABLED; without options they hold the options' defaults."""
    text = source(SKIPPING, header=options, params="USER")
    cc = compile_chart(parse_chart(text, "options.s7g"))
    session = ChartSession(cc, SymbolTable(), VirtualClock())
    values = {
        n: session.get(n) for n in ("EN_SSKIP", "EN_ACKREQ", "SSKIP_ENABLED", "ACKREQ_ENABLED")
    }
    skip, ack = bool(options), not options
    assert values == {
        "EN_SSKIP": skip,
        "EN_ACKREQ": ack,
        "SSKIP_ENABLED": skip,
        "ACKREQ_ENABLED": ack,
    }


def test_the_pin_table_names_the_option_as_the_default() -> None:
    """The pin table of docs/semantics.md (params.markdown_table) says "option …" for those pins."""
    table = markdown_table()
    assert "| option SKIP_STEPS (FALSE) | Skip steps |" in table
    assert "| option ACK_REQUIRED (TRUE) | Faults must be acknowledged |" in table


# ---------------------------------------------------------------- timers and counters


def test_a_tl_timer_contact_keeps_the_step_while_the_timer_runs(tmp_path: Path) -> None:
    """STEP7 comprehensive guide vol. 2, ch. 14: TL T0 started when Step1 is left; Step2 sets Q0.0
    and stays active while the timer runs (``NOT T0``), then resets Q0.0 on leaving."""
    text = """FUNCTION_BLOCK "Tl"
  PARAMETERS := STANDARD;
SEQUENCE 1 "s"
  INITIAL_STEP S1 "Step1": S0 TL T0, S5T#800MS; END_STEP
  STEP S2 "Step2": S1 S Q0.0; S0 R Q0.0; END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.0;
  TRANSITION T2 FROM S2 TO S1 := NOT T0;
END_SEQUENCE
END_FUNCTION_BLOCK
"""
    stim = [{"at_ms": 10, "set": {"I0.0": True}}, {"at_ms": 20, "set": {"I0.0": False}}]
    rc, lines = sim_trace(tmp_path, text, stim, cycles=95, watch="Q0.0,T0")
    assert rc == 0
    assert lines[1]["active"] == ["S2"] and lines[1]["values"] == {"Q0.0": True, "T0": True}
    assert all(line["active"] == ["S2"] for line in lines[1:81])
    assert lines[81]["events"] == [["S2", "S1"]]  # 800 ms after the start at t = 10 ms
    assert lines[81]["values"] == {"Q0.0": False, "T0": False}


CELL_CONDITIONS = ["T5", "NOT T0", "C1 AND I0.0", "Z1 OR T5", '"Tmr"', 'NOT "Cnt"']


@pytest.mark.parametrize("where", ["transition", "interlock", "supervision", "permanent"])
@pytest.mark.parametrize("cond", CELL_CONDITIONS)
def test_timer_and_counter_status_bits_are_contacts_in_every_kind_of_condition(
    where: str, cond: str
) -> None:
    """El-Shahat's S7-300/400 course: a timer or counter is used "at the same address as a BOOL
    state"; in S7-GRAPH conditions that is the status bit — in transitions, interlocks, supervisions
    and permanent instructions (absolute, German ``Z``, or a symbol)."""
    il = f"INTERLOCK := {cond};" if where == "interlock" else ""
    sv = f"SUPERVISION := {cond};" if where == "supervision" else ""
    t2 = cond if where == "transition" else "FALSE"
    perm = f"PERMANENT BEFORE M9.0 := {cond}; END_PERMANENT" if where == "permanent" else ""
    header = f'SYMBOLS "Tmr" : T6 : TIMER; "Cnt" : C2 : COUNTER; END_SYMBOLS\n{perm}'
    run = chart(
        seq(f"""
      INITIAL_STEP S1 "a": END_STEP
      STEP S2 "b": {il} {sv} N Q1.0; END_STEP
      TRANSITION T1 FROM S1 TO S2 := I0.2;
      TRANSITION T2 FROM S2 TO S1 := {t2};
    """),
        header=header,
    )
    run.call()
    assert run.active == [1]


def test_counter_and_timer_contacts_follow_their_cells() -> None:
    """The status bit of a counter is "count > 0" (El-Shahat's S7-300/400 course), read live in an
    interlock (C rows), a transition and a permanent coil."""
    run = chart(
        seq("""
      INITIAL_STEP S1 "a": S1 CS C1, C#2; END_STEP
      STEP S2 "b": INTERLOCK := C1; N C Q1.0; S1 CD C1; END_STEP
      STEP S3 "c": S1 CD C1; END_STEP
      TRANSITION T1 FROM S1 TO S2 := C1 AND I0.0;
      TRANSITION T2 FROM S2 TO S3 := I0.1;
      TRANSITION T3 FROM S3 TO S2 := NOT C1;
    """),
        header="PERMANENT AFTER M9.0 := NOT C1; END_PERMANENT",
    )
    run.call()
    run.set(I0_0=True).call()  # C1 = 2: T1 switches; S2 counts down to 1
    assert run.active == [2] and run.get("Q1.0") is True and run.get("M9.0") is False
    run.set(I0_1=True).call()  # S3 counts down to 0: C1 off
    assert run.active == [3] and run.get("M9.0") is True
    run.set(I0_1=False).call()  # NOT C1: back to S2, whose interlock C1 is lost
    assert run.active == [2] and run.get("Q1.0") is False and run.st.il_err[run.idx(2)]


def test_a_counter_in_a_comparison_or_an_assignment_reads_its_count() -> None:
    """El-Shahat's S7-300/400 course: a counter is also "the value of the current count" — where a
    number is expected (a comparison, arithmetic, an assignment to an INT) it reads as ``L C n``."""
    run = chart(
        seq("""
      INITIAL_STEP S1 "a": S1 CS C1, C#2; S1 CU C1; END_STEP
      STEP S2 "b": S1 N n := C1 * 10 + C1; END_STEP
      TRANSITION T1 FROM S1 TO S2 := C1 >= 3 AND C1 < MW0;
      TRANSITION T2 FROM S2 TO S1 := FALSE;
    """),
        header="VAR n : INT := 0; END_VAR",
    )
    run.set(MW0=3).call(2)
    assert run.active == [1]  # C1 = 3 is not < 3
    run.set(MW0=4).call()
    assert run.active == [2] and run.st.vars["n"] == 33


def test_a_timer_in_a_comparison_reads_its_remaining_time_in_time_base_units() -> None:
    """``L T n`` loads the remaining time in units of its time base (S5T#2S: 200 × 10 ms),
    so ``T4 > 150`` holds for the first half second of a 2 s timer."""
    run = chart(
        seq("""
      INITIAL_STEP S1 "a": S1 TD T4, S5T#2S; END_STEP
      STEP S2 "b": S1 N v := T4; END_STEP
      TRANSITION T1 FROM S1 TO S2 := T4 > 150;
      TRANSITION T2 FROM S2 TO S1 := FALSE;
    """),
        header="VAR v : INT := 0; END_VAR",
    )
    run.call(2)
    assert run.active == [2] and run.st.vars["v"] == 200  # no time base tick without a CPU


def test_a_timer_cannot_be_compared_with_a_time(tmp_path: Path, capsys) -> None:
    """Its value is a count of time-base units, not a TIME: ``T4 > T#2S`` is a type error
    (E030) naming the timer."""
    text = source(
        seq("""
      INITIAL_STEP S1 "a": END_STEP
      TRANSITION T1 FROM S1 TO S1 := T4 > T#2S;
    """)
    )
    rc, _ = sim_trace(tmp_path, text, [], cycles=1)
    assert rc == 2 and "error[E030]: cannot compare INT with TIME" in capsys.readouterr().err


# ---------------------------------------------------------------- every activation raises S1

TWO_SEQUENCERS = """
SEQUENCE 1 "first"
  INITIAL_STEP S1 "idle": END_STEP
  STEP S9 "target": {il} S1 N n := n + 1; N Q0.1; END_STEP
  TRANSITION T1 FROM S1 TO S1 := FALSE;
  TRANSITION T9 FROM S9 TO S1 := I0.1;
END_SEQUENCE
SEQUENCE 2 "second"
  INITIAL_STEP S5 "wait": {src_il} END_STEP
  STEP S6 "on": {src_il} S1 ON S9; END_STEP
  TRANSITION T5 FROM S5 TO {to} := I0.0;
  TRANSITION T6 FROM S6 TO S5 := FALSE;
END_SEQUENCE
"""


@pytest.mark.parametrize("how", ["jump", "on"])
@pytest.mark.parametrize("path", ["fast", "general"])
def test_a_step_activated_from_a_later_sequencer_runs_its_s1_rows_once(
    tmp_path: Path, how: str, path: str
) -> None:
    """S7-GRAPH manual 6-2, 6-4: a jump to a step of another sequencer of the FB, or an
    ``ON Sx``, activates it like any activation: its S1 rows run once, in that call, and its
    N rows from then on. Plain steps take the fast path, steps with an interlock the general
    one."""
    il = "INTERLOCK := TRUE;" if path == "general" else ""
    body = TWO_SEQUENCERS.format(il=il, src_il=il, to="S9" if how == "jump" else "S6")
    text = source(body, header="VAR n : INT := 0; END_VAR")
    stim = [{"at_ms": 10, "set": {"I0.0": True}}, {"at_ms": 20, "set": {"I0.0": False}}]
    rc, lines = sim_trace(tmp_path, text, stim, cycles=5, watch="n,Q0.1,S9.X")
    assert rc == 0
    assert lines[0]["values"] == {"n": 0, "Q0.1": False, "S9.X": False}
    assert lines[1]["values"] == {"n": 1, "Q0.1": True, "S9.X": True}
    assert lines[-1]["values"] == {"n": 1, "Q0.1": True, "S9.X": True}


CODESYS_ACTIVATIONS = {
    "jump into a later sequencer": seq("""
      INITIAL_STEP S1 "a": END_STEP
      TRANSITION T1 FROM S1 TO S9 := I0.0;
    """)
    + seq(
        """
      INITIAL_STEP S5 "w": END_STEP
      STEP S9 "t": S1 N n := n + 1; END_STEP
      TRANSITION T9 FROM S9 TO S5 := FALSE;
    """,
        2,
    ),
    "ON in its own sequencer": seq("""
      INITIAL_STEP S1 "a": END_STEP
      STEP S2 "b": S1 ON S9; END_STEP
      STEP S9 "t": S1 N n := n + 1; END_STEP
      TRANSITION T1 FROM S1 TO S2 := I0.0;
    """),
    "S_ON in MAN": seq("""
      INITIAL_STEP S1 "a": END_STEP
      STEP S9 "t": S1 N n := n + 1; END_STEP
      TRANSITION T1 FROM S1 TO S9 := FALSE;
    """),
}


@pytest.mark.parametrize("how", CODESYS_ACTIVATIONS)
def test_the_codesys_order_runs_the_s1_rows_of_an_activation_once(how: str) -> None:
    """``ORDER := CODESYS`` (new steps act in the next call) must not run S1 rows twice: a
    step whose rows already ran in its activation call is not carried to the next one."""
    c = Chart(CODESYS_ACTIVATIONS[how], header="VAR n : INT := 0; END_VAR\nORDER := CODESYS;")
    c.call()
    if how == "S_ON in MAN":
        c.set(SW_MAN=True, S_SEL=9)
        c.call()
        c.set(S_ON=True)
    else:
        c.set(I0_0=True)
    c.call(4)
    assert "S9" in c.active and c.rt.st.vars["n"] == 1


# ---------------------------------------------------------------- the initial step

COUNTER_EXAMPLE = """FUNCTION_BLOCK "Counter"
  PARAMETERS := STANDARD;{options}
VAR n : INT := 0; preset : INT := 0; END_VAR
SEQUENCE 1 "s"
  INITIAL_STEP S1 "Step1": S1 CS C1, C#26; S1 N preset := C1; N n := n + 1; N Q0.1; END_STEP
  STEP S2 "Step2": S0 CU C1; END_STEP
  TRANSITION T1 FROM S1 TO S2 := ;
  TRANSITION T2 FROM S2 TO S2 := I0.0;
END_SEQUENCE
END_FUNCTION_BLOCK
"""


@pytest.mark.parametrize("options", ["", " SKIP_STEPS := TRUE;"])
def test_an_initial_step_whose_transition_holds_runs_its_rows_once_before_it_switches(
    tmp_path: Path, options: str
) -> None:
    """STEP7 comprehensive guide vol. 2, ch. 14 (the counter example): as soon as Step1 is active C1
    is set to 26, then the sequence goes on to Step2 (STEP7 comprehensive guide vol. 2, ch. 14: a
    step is active for at least one cycle). The startup call (OB100, INIT_SQ) activates Step1 and
    runs its S1 and N rows; the next call switches. An INIT_SQ edge later does the same again; skip
    steps never passes an initialized step."""
    text = COUNTER_EXAMPLE.format(options=options)
    stim = [{"at_ms": 30, "set": {"INIT_SQ": True}}, {"at_ms": 50, "set": {"INIT_SQ": False}}]
    rc, lines = sim_trace(tmp_path, text, stim, cycles=6, watch="n,preset,C1,Q0.1")
    assert rc == 0
    assert lines[0]["events"] == [["S1", "S2"]] and lines[0]["active"] == ["S2"]
    assert lines[0]["values"] == {"n": 1, "preset": 26, "C1": True, "Q0.1": False}
    assert lines[3]["active"] == ["S1"] and lines[3]["values"]["Q0.1"] is True
    assert lines[4]["events"] == [["S1", "S2"]] and lines[4]["values"]["n"] == 2


def test_the_first_call_of_a_bare_runtime_holds_the_initial_step_too() -> None:
    """The first call initializes like an INIT_SQ edge (the same rule without a CPU)."""
    c = Chart(
        seq("""
      INITIAL_STEP S1 "a": N Q0.0; END_STEP
      STEP S2 "b": END_STEP
      TRANSITION T1 FROM S1 TO S2 := TRUE;
    """)
    )
    c.call()
    assert c.active == ["S1"] and c.q("Q0.0") and c.fired == []
    c.call()
    assert c.active == ["S2"] and not c.q("Q0.0") and c.fired == ["T1"]


# ---------------------------------------------------------------- N C assignments


def test_an_n_c_assignment_does_not_run_while_the_interlock_is_lost() -> None:
    """S7-GRAPH manual 14-8, STEP7 comprehensive guide vol. 2, ch. 14: ``N[C] A := B`` — like every
    row marked C, an assignment marked C runs only while the interlock holds (an event one too)."""
    run = two_steps(
        "N C n := n + 1; S1 N C m := m + 1;",
        interlock="I0.5",
        header="VAR n : INT := 0; m : INT := 0; END_VAR",
    )
    run.set(I0_5=True)
    enter(run)
    assert run.st.vars == {"n": 1, "m": 1}
    run.call(2)
    assert run.st.vars == {"n": 3, "m": 1}
    run.set(I0_5=False).call(3)
    assert run.st.vars == {"n": 3, "m": 1}
    run.set(I0_5=True).call()
    assert run.st.vars == {"n": 4, "m": 1}


# ---------------------------------------------------------------- SQ_ISOFF


def test_sq_isoff_means_no_step_active_from_off_sq_until_init_sq(tmp_path: Path) -> None:
    """SQ_ISOFF "sequencer is off (no step active)": TRUE after an OFF_SQ pulse, and it
    stays TRUE once OFF_SQ is released, until INIT_SQ activates the initial steps."""
    text = source(SKIPPING, params="USER")
    stim = [
        {"at_ms": 20, "set": {"OFF_SQ": True}},
        {"at_ms": 30, "set": {"OFF_SQ": False}},
        {"at_ms": 60, "set": {"INIT_SQ": True}},
    ]
    rc, lines = sim_trace(tmp_path, text, stim, cycles=8, watch="SQ_ISOFF")
    assert rc == 0
    assert [line["values"]["SQ_ISOFF"] for line in lines] == [False] * 2 + [True] * 4 + [False] * 2
    assert lines[5]["active"] == [] and lines[6]["active"] == ["S1"]


def test_sq_isoff_goes_false_when_s_on_activates_a_step() -> None:
    """In MAN, S_ON on the step shown in S_NO switches the sequencer on again."""
    run = chart(SKIPPING, params="USER")
    run.call()
    run.pulse("OFF_SQ")
    assert run.active == [] and run.out("SQ_ISOFF") is True
    run.set(SW_MAN=True, S_SEL=2).call()
    run.pulse("S_ON")
    assert run.active == [2] and run.out("SQ_ISOFF") is False
