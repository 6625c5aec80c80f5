"""A network is read in time as long as it is drawn: a LAD parallel branch opened after
contacts reads what flows to its opening once (``before AND (b1 OR b2)``), so nested
branches never double the condition per level; a loop of wires is an error at its place,
and an FBD whose outputs feed several inputs level after level is refused once it would be
over 20,000 elements written out — never an import that does not end."""

from __future__ import annotations

import re

import pytest

from s7graph.sequencer.exchange import export_chart, import_chart
from s7graph.sequencer.exchange.problems import ImportFailed
from s7graph.sequencer.exchange.xmltree import MAX_WIRE_DEPTH
from s7graph.sequencer.text.format import format_expr
from s7graph.sequencer.text.parse import parse_chart
from tests.sequencer.exchange.helpers import corpus

CHART = """FUNCTION_BLOCK "T" FB 3
SEQUENCE 1 "Main"
  INITIAL_STEP S1:
  END_STEP
  STEP S2:
  END_STEP
  TRANSITION T1 FROM S1 TO S2 := {cond};
  TRANSITION T2 FROM S2 TO S1;
END_SEQUENCE
END_FUNCTION_BLOCK
"""


def test_nested_parallel_branches_read_back_as_long_as_written() -> None:
    cond = " AND ".join(f"(I{k}.0 OR I{k}.1)" for k in range(24))
    xml = export_chart(parse_chart(CHART.format(cond=cond), "t.s7g"), "simaticml")
    read = import_chart(xml.encode(), "t.xml").chart.sequences[0].transitions[0].condition
    assert read is not None
    text = format_expr(read)
    assert len(text) < 2 * len(cond)  # 2 ** 24 copies of the first branch, before
    assert sorted(set(re.findall(r"I\d+\.\d", text))) == sorted(set(re.findall(r"I\d+\.\d", cond)))


def test_a_loop_of_wires_is_an_error_at_its_place() -> None:
    xml = export_chart(parse_chart(CHART.format(cond="I0.0 AND I0.1"), "t.s7g"), "simaticml")
    contact = re.search(r'<Part Name="Contact" UId="(\d+)"', xml)
    assert contact is not None
    uid = contact.group(1)
    loop = f'<Wire UId="99"><NameCon UId="{uid}" Name="out" /><NameCon UId="{uid}" Name="in" />'
    at = xml.index("</Wires>", contact.end())  # the contact's own network
    xml = xml[:at] + loop + "</Wire>" + xml[at:]
    with pytest.raises(ImportFailed) as failed:
        import_chart(xml.encode(), "t.xml")
    said = [d.message for d in failed.value.diagnostics if d.is_error]
    assert any("a loop of wires" in m for m in said), said


def _or_chain(levels: int, block: str = "OR", pins: tuple[str, ...] = ("IN1", "IN2")) -> str:
    """An FBD body: SWITCH_BUTTON into an OR fed twice, each OR into the next twice (or
    into another ``block`` by its ``pins``)."""
    blocks = []
    for k in range(levels):
        src = 43 if k == 0 else 1000 + k - 1
        ins = "".join(
            f'<variable formalParameter="{n}"><connectionPointIn>'
            f'<connection refLocalId="{src}"/></connectionPointIn></variable>'
            for n in pins
        )
        blocks.append(
            f'<block localId="{1000 + k}" typeName="{block}"><position x="0" y="0"/>'
            f"<inputVariables>{ins}</inputVariables><inOutVariables/><outputVariables>"
            '<variable formalParameter="OUT"><connectionPointOut/></variable>'
            "</outputVariables></block>"
        )
    return (
        '<FBD><inVariable localId="43"><position x="0" y="0"/><connectionPointOut/>'
        "<expression>SWITCH_BUTTON</expression></inVariable>"
        + "".join(blocks)
        + (
            f'<outVariable localId="44"><position x="0" y="0"/><connectionPointIn>'
            f'<connection refLocalId="{1000 + levels - 1}" formalParameter="OUT"/>'
            "</connectionPointIn><expression>STOP</expression></outVariable></FBD>"
        )
    )


def _with_stop_body(
    levels: int, block: str = "OR", pins: tuple[str, ...] = ("IN1", "IN2")
) -> bytes:
    text = corpus("plcopen/beremiz_traffic_light.xml").read_text(encoding="utf-8")
    start = text.index('<transition name="STOP">')
    body = text.index("<FBD>", start)
    end = text.index("</FBD>", body) + len("</FBD>")
    return (text[:body] + _or_chain(levels, block, pins) + text[end:]).encode()


def test_an_fbd_whose_outputs_fan_out_is_read_or_refused_at_once() -> None:
    small = import_chart(_with_stop_body(4), "t.xml").chart
    assert "SWITCH_BUTTON" in format_expr(
        next(
            t for t in small.all_transitions() if "SWITCH_BUTTON" in format_expr(t.condition)
        ).condition  # type: ignore[arg-type]
    )
    with pytest.raises(ImportFailed) as failed:
        import_chart(_with_stop_body(40), "t.xml")  # 2 ** 40 elements written out
    said = [d.message for d in failed.value.diagnostics if d.is_error]
    assert any("over 20,000 elements" in m for m in said), said


@pytest.mark.parametrize(("nots", "refused"), [(MAX_WIRE_DEPTH - 2, False), (150, True)])
def test_an_fbd_value_through_more_elements_than_an_import_reads_is_refused_as_in_lad(
    nots: int, refused: bool
) -> None:
    """NOT after NOT in a PLCopen FBD: the same limit and the same words as for a TIA LAD
    network (test_unreadable_input), at the element past it."""
    data = _with_stop_body(nots, "NOT", ("IN",))
    if not refused:
        stop = import_chart(data, "t.xml").chart.all_transitions()
        assert any("SWITCH_BUTTON" in format_expr(t.condition) for t in stop if t.condition)
        return
    with pytest.raises(ImportFailed) as failed:
        import_chart(data, "t.xml")
    said = [d for d in failed.value.diagnostics if d.is_error]
    words = (
        f"a value that flows through more than {MAX_WIRE_DEPTH} elements one after "
        f"another (an import reads at most {MAX_WIRE_DEPTH})"
    )
    assert len(said) == 1 and words in said[0].message, said
    line = data.decode().splitlines()[said[0].loc.line - 1]
    assert f'<block localId="{1000 + nots - MAX_WIRE_DEPTH - 1}"' in line, line


@pytest.mark.parametrize(
    "cond",
    [
        "a AND (b OR c)",
        "NOT a AND (b OR NOT c) AND S1.T >= T#2S",
        "a AND b AND (c OR d AND e) AND (a OR e)",
        "(a OR b) AND c AND (d OR e)",
    ],
)
def test_contacts_before_a_parallel_branch_are_read_once_before_the_or(cond: str) -> None:
    """LAD draws ``a AND (b OR c)`` as contact a, then a branch of b and c: read back, the
    contacts every branch passes stay before the OR, not copied into each branch."""
    text = CHART.replace(
        "FB 3", "FB 3\nVAR a : BOOL; b : BOOL; c : BOOL; d : BOOL; e : BOOL; END_VAR"
    ).format(cond=cond)
    chart = parse_chart(text, "t.s7g")
    xml = export_chart(chart, "simaticml")
    read = import_chart(xml.encode(), "t.xml").chart.sequences[0].transitions[0].condition
    assert read is not None
    assert format_expr(read) == format_expr(chart.sequences[0].transitions[0].condition)
