"""Function blocks in and around an imported chart (docs/import-export.md): the blocks Beremiz
draws in a chart's network run every call, as Beremiz runs them (an S action of the first
initial step: PERMANENT AFTER); R_TRIG, F_TRIG, SR and RS compute their IEC bodies; SEL on
BOOLs is a condition; and a chart that can never leave a step says so, and why."""

from __future__ import annotations

from pathlib import Path

from s7graph.sequencer.exchange import import_chart, import_file
from s7graph.sequencer.text.format import format_chart, format_row
from s7graph.sequencer.text.model import Chart
from s7graph.sequencer.text.walk import uncommented, unlocated
from tests.sequencer.exchange.helpers import codes, import_to, sim, synthetic

PERMANENT_CALLS = [
    "R_TRIG0_Q := START_BUTTON AND NOT R_TRIG0_M;",
    "R_TRIG0_M := START_BUTTON;",
    "CALL SFB 4, DB 100 (IN := S2.X, PT := T#300ms, Q => TON0_Q, ET => TON0_ET);",
]


def after(chart: Chart) -> list[str]:
    text = format_chart(chart)
    body = text.split("PERMANENT AFTER\n", 1)[1].split("END_PERMANENT", 1)[0]
    return [line.strip() for line in body.splitlines() if line.strip()]


def test_the_blocks_beremiz_draws_in_a_chart_are_called_every_call_in_permanent_after() -> None:
    """An R_TRIG and a TON in the SFC body feed the transitions: Beremiz calls them in the
    action COMPUTE_FUNCTION_BLOCKS, stored on the first initial step; the import calls them
    in PERMANENT AFTER, in that order, and the textual form Beremiz hands matiec gives the
    very same chart."""
    xml = import_file(synthetic("beremiz_chart_blocks.xml"))
    text = import_file(synthetic("beremiz_compute_blocks.st"))
    assert after(xml.chart) == PERMANENT_CALLS
    assert [d.code for d in xml.problems] == ["I031", "I031"]  # how R_TRIG0 and TON0 run
    assert uncommented(unlocated(xml.chart)) == uncommented(unlocated(text.chart))


def test_an_s_action_on_an_initial_step_nothing_resets_runs_every_call(tmp_path: Path) -> None:
    """``COMPUTE_FUNCTION_BLOCKS(S)`` on the initial step, never reset: the action is active
    from the first call on, for good — PERMANENT AFTER. The chart leaves Idle on the edge of
    START_BUTTON (R_TRIG0 computed after the call that sees it, read by the next) and comes
    back 300 ms later (TON0); the button still held does not start it again."""
    rc, chart = import_to(tmp_path, synthetic("beremiz_compute_blocks.st"))
    assert rc == 1
    records = sim(
        tmp_path,
        chart,
        watch=["MOTOR"],
        cycles=50,
        stimulus=[{"at_ms": 50, "set": {"START_BUTTON": True}}],
    )
    events = [(r["t_ms"], e) for r in records for e in r["events"]]
    assert events == [(60, ["S1", "S2"]), (370, ["S2", "S1"])]
    assert records[10]["values"]["MOTOR"] and not records[-1]["values"]["MOTOR"]


def test_an_s_action_that_a_step_resets_is_not_permanent() -> None:
    """Reset somewhere (``R``), the stored action has no GRAPH form: reported, not made
    permanent."""
    text = synthetic("beremiz_compute_blocks.st").read_text()
    text = text.replace("    MOTOR(N);", "    MOTOR(N);\n    COMPUTE_FUNCTION_BLOCKS(R);")
    result = import_chart(text.encode(), "c.st")
    assert "PERMANENT AFTER" not in format_chart(result.chart)
    assert ("I020", 17) in codes(result.problems)


def edge_program(body: str) -> bytes:
    return (
        "PROGRAM P\nVAR x : BOOL; a : BOOL; b : BOOL; go : BOOL;\n"
        " E1 : R_TRIG; E2 : F_TRIG; L1 : SR; L2 : RS; END_VAR\n"
        f"{body}\n"
        "INITIAL_STEP A: END_STEP\nSTEP B: END_STEP\n"
        "TRANSITION FROM A TO B := go; END_TRANSITION\n"
        "TRANSITION FROM B TO A := NOT go; END_TRANSITION\nEND_PROGRAM\n"
    ).encode()


def iec_reference(steps: list[dict[str, bool]]) -> list[dict[str, bool]]:
    """The outputs of R_TRIG, F_TRIG, SR, RS call by call, as matiec's library computes them
    (lib/edge_detection.txt, lib/bistable.txt; state starting FALSE)."""
    m1 = m2 = q1 = q2 = False
    out = []
    for v in steps:
        x, s, r = v["x"], v["a"], v["b"]
        e1, m1 = x and not m1, x
        e2, m2 = (not x) and not m2, not x
        q1 = s or (not r and q1)
        q2 = (not r) and (s or q2)
        out.append({"E1_Q": e1, "E2_Q": e2, "L1_Q1": q1, "L2_Q1": q2})
    return out


def test_r_trig_f_trig_sr_and_rs_compute_their_iec_bodies(tmp_path: Path) -> None:
    """Called in the POU body (PERMANENT BEFORE), the four blocks give matiec's outputs call
    by call — OB100's first call included, in which F_TRIG sees CLK FALSE and pulses."""
    result = import_file(synthetic("edge_latch_blocks.st"))
    chart = tmp_path / "p.s7g"
    chart.write_text(format_chart(result.chart))
    pattern = [(1, 0, 0), (1, 1, 0), (0, 1, 1), (0, 0, 1), (1, 0, 0), (0, 0, 0), (0, 1, 0)]
    pattern += [(1, 1, 1), (1, 0, 0), (0, 0, 0)]
    inputs = [{"x": bool(x), "a": bool(s), "b": bool(r)} for x, s, r in pattern]
    stimulus = [{"at_ms": 10 * i, "set": v} for i, v in enumerate(inputs)]
    watch = ["E1_Q", "E2_Q", "L1_Q1", "L2_Q1"]
    records = sim(tmp_path, chart, watch=watch, cycles=len(inputs), stimulus=stimulus)
    first = {"x": False, "a": False, "b": False}  # OB100's call, before the stimulus
    expected = iec_reference([first, *inputs])
    assert expected[0]["E2_Q"]  # the F_TRIG pulse of the first call
    assert [r["values"] for r in records] == expected[1:]


def test_codesys_spells_the_bistable_inputs_set1_reset_and_set_reset1() -> None:
    body = "L1(SET1 := a, RESET := b);\nL2(SET := a, RESET1 := b);"
    text = format_chart(import_chart(edge_program(body), "p.st").chart)
    assert "L1_Q1 := a OR NOT b AND L1_Q1;" in text
    assert "L2_Q1 := NOT b AND (a OR L2_Q1);" in text


def test_an_edge_detector_called_in_an_action_runs_while_its_step_is_active() -> None:
    """In an N action the call runs only while the step is: each assignment is gated by the
    step in PERMANENT AFTER (the instance keeps its state otherwise); an input that is an
    expression is read once, into an FB variable."""
    program = edge_program("").decode()
    program = program.replace("STEP B: END_STEP", "STEP B: DETECT(N); END_STEP")
    program = program.replace(
        "END_PROGRAM", "ACTION DETECT:\n E1(CLK := x AND a, Q => b);\nEND_ACTION\nEND_PROGRAM"
    )
    result = import_chart(program.encode(), "p.st")
    assert after(result.chart) == [
        "E1_CLK := S2.X AND x AND a OR NOT S2.X AND E1_CLK;",
        "E1_Q := S2.X AND E1_CLK AND NOT E1_M OR NOT S2.X AND E1_Q;",
        "E1_M := S2.X AND E1_CLK OR NOT S2.X AND E1_M;",
        "b := S2.X AND E1_Q OR NOT S2.X AND b;",
    ]


def test_sel_on_bools_is_a_condition_and_on_numbers_is_reported() -> None:
    """``SEL(G, IN0, IN1)`` on BOOLs is ``NOT G AND IN0 OR G AND IN1`` (IEC's 0 and 1 read
    as BOOLs there); a SEL of numbers has no GRAPH form: the row is left out, reported."""
    result = import_file(synthetic("sel_condition.st"))
    t1 = result.chart.all_transitions()[0]
    assert "NOT g AND a OR g AND TRUE" in format_chart(result.chart)
    assert t1.condition is not None
    assert [(d.code, d.loc.line) for d in result.problems] == [("I021", 7)]
    assert "SEL of INT has no GRAPH form" in result.problems[0].message


def test_sel_drawn_in_a_chart_network_is_the_same_condition() -> None:
    xml = synthetic("beremiz_chart_blocks.xml").read_text()
    sel = (
        '<block localId="20" width="60" height="80" typeName="SEL"><inputVariables>'
        '<variable formalParameter="G"><connectionPointIn><connection refLocalId="9"/>'
        '</connectionPointIn></variable><variable formalParameter="IN0"><connectionPointIn>'
        '<connection refLocalId="10" formalParameter="Q"/></connectionPointIn></variable>'
        '<variable formalParameter="IN1"><connectionPointIn><connection refLocalId="13" '
        'formalParameter="Q"/></connectionPointIn></variable></inputVariables><inOutVariables/>'
        '<outputVariables><variable formalParameter="OUT"><connectionPointOut/></variable>'
        "</outputVariables></block>"
    )
    xml = xml.replace("</SFC>", sel + "</SFC>").replace(
        '<connection refLocalId="10" formalParameter="Q"/></connectionPointIn>\n              '
        "</condition>",
        '<connection refLocalId="20" formalParameter="OUT"/></connectionPointIn>\n'
        "              </condition>",
    )
    chart = import_chart(xml.encode(), "sel.xml").chart
    t1 = chart.all_transitions()[0]
    assert "NOT START_BUTTON AND R_TRIG0_Q OR START_BUTTON AND TON0_Q" in format_chart(chart)
    assert t1.sources == (1,)


def test_a_chart_that_can_never_leave_its_initial_step_says_so_and_why() -> None:
    """Its only transition waits for the output of a TON nothing calls: the import says
    the chart cannot leave the initial step, which transition waits for what, and why."""
    text = (
        b"PROGRAM P\nVAR go : BOOL; T1 : TON; END_VAR\n"
        b"INITIAL_STEP Wait: END_STEP\nSTEP Go: END_STEP\n"
        b"TRANSITION FROM Wait TO Go := T1.Q AND go; END_TRANSITION\n"
        b"TRANSITION FROM Go TO Wait := NOT go; END_TRANSITION\nEND_PROGRAM\n"
    )
    result = import_chart(text, "p.st")
    assert codes(result.problems) == [("I022", 2), ("I025", 3)]
    stall = result.problems[1]
    assert 'cannot leave initial step S1 "Wait": T1 can never hold — ' in stall.message
    assert "T1_Q is T1.Q, and T1 : TON is never called" in stall.message


def test_an_input_the_caller_gives_is_never_a_stall() -> None:
    text = (
        b"FUNCTION_BLOCK F\nVAR_INPUT go : BOOL; END_VAR\n"
        b"INITIAL_STEP Wait: END_STEP\nSTEP Go: END_STEP\n"
        b"TRANSITION FROM Wait TO Go := go; END_TRANSITION\n"
        b"TRANSITION FROM Go TO Wait := NOT go; END_TRANSITION\nEND_FUNCTION_BLOCK\n"
    )
    assert import_chart(text, "f.st").problems == []


def test_rows_of_the_chart_blocks_file_read_back_the_same() -> None:
    """The MOTOR row of Run is the Boolean action N (no trace of the blocks in the rows)."""
    chart = import_file(synthetic("beremiz_chart_blocks.xml")).chart
    assert [format_row(r) for r in chart.all_steps()[1].actions] == ["N MOTOR;"]


def test_a_block_called_in_a_transition_body_is_reported_not_dropped_silently() -> None:
    """A named transition's FBD body calling an FB instance: a condition calls no block, so
    the call is not imported — said where it is."""
    xml = synthetic("beremiz_chart_blocks.xml").read_text()
    body = (
        '<transitions><transition name="Started"><body><FBD>'
        '<inVariable localId="1"><expression>START_BUTTON</expression></inVariable>'
        '<block localId="2" typeName="R_TRIG" instanceName="R_TRIG0"><inputVariables>'
        '<variable formalParameter="CLK"><connectionPointIn><connection refLocalId="1"/>'
        "</connectionPointIn></variable></inputVariables><inOutVariables/><outputVariables>"
        '<variable formalParameter="Q"><connectionPointOut/></variable></outputVariables>'
        '</block><outVariable localId="3"><connectionPointIn><connection refLocalId="2" '
        'formalParameter="Q"/></connectionPointIn><expression>Started</expression>'
        "</outVariable></FBD></body></transition></transitions>"
    )
    wired = (
        '<connectionPointIn><connection refLocalId="10" formalParameter="Q"/></connectionPointIn>'
    )
    assert wired in xml
    xml = xml.replace("</interface>", "</interface>" + body)
    xml = xml.replace(wired, '<reference name="Started"/>')
    result = import_chart(xml.encode(), "t.xml")
    called = [d.message for d in result.problems if d.code == "I022"]
    assert "transition Started: its FBD body calls R_TRIG0, which is not imported" in called[1]
    assert "R_TRIG0 : R_TRIG is not called by the chart" in called[0]
