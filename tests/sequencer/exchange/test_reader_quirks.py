"""What other tools write that the readers took wrongly (docs/import-export.md): ``:= 1`` as a
condition, an action time given by a TIME variable, a POU the grammar cannot read beside a
chart, and charts drawn in actions (TwinCAT, CODESYS)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from s7graph.sequencer.exchange import ImportFailed, import_chart, import_file
from s7graph.sequencer.text.format import format_chart, format_row
from s7graph.sequencer.text.walk import unlocated
from tests.sequencer.exchange.helpers import codes, corpus, import_to, sim, synthetic
from tests.sequencer.exchange.test_iec_mapping import CODESYS


def test_one_and_zero_are_bool_literals_in_a_condition(tmp_path: Path) -> None:
    """``:= 1`` holds (IEC's 1 is a BOOL literal too), also as an operand of NOT, AND, OR,
    XOR: the chart runs round, one call a step."""
    rc, chart = import_to(tmp_path, synthetic("literal_condition.st"))
    assert rc == 0
    text = chart.read_text()
    assert "TRANSITION T1 FROM S1 TO S2 := TRUE;" in text
    assert "TRANSITION T2 FROM S2 TO S1 := NOT halt AND TRUE;" in text
    records = sim(tmp_path, chart, watch=["n"], cycles=6)
    assert [r["active"] for r in records] == [["S2"], ["S1"], ["S2"], ["S1"], ["S2"], ["S1"]]
    assert records[-1]["values"]["n"] == 3


def test_a_wired_literal_one_holds_in_plcopen_too() -> None:
    xml = CODESYS.replace(b"<expression>go</expression>", b"<expression>1</expression>")
    chart = import_chart(xml, "seq.xml").chart
    assert chart.all_transitions()[0].condition is not None
    assert "TRANSITION T1 FROM S1 TO S2 := TRUE;" in format_chart(chart)


def test_an_action_time_given_by_a_time_variable_is_the_rows_time(tmp_path: Path) -> None:
    """``horn(L, dt)``: dt is the action time, not an indicator variable; ``lamp(D, dt,
    shown)``: shown is the indicator (reported: GRAPH rows have none). The horn sounds for
    dt from the alarm, the lamp lights after it."""
    result = import_file(synthetic("time_variable_action.st"))
    rows = [format_row(r) for r in result.chart.all_steps()[1].actions]
    assert rows == ["L horn, dt;", "D lamp, dt;"]
    assert codes(result.problems) == [("I020", 18)]
    assert "indicator variable shown" in result.problems[0].message
    assert import_to(tmp_path, synthetic("time_variable_action.st"))[0] == 1
    chart = tmp_path / "chart.s7g"
    records = sim(
        tmp_path,
        chart,
        watch=["horn", "lamp"],
        cycles=40,
        stimulus=[{"at_ms": 100, "set": {"alarm": True}}],
    )
    horn = [r["t_ms"] for r in records if r["values"]["horn"]]
    lamp = [r["t_ms"] for r in records if r["values"]["lamp"]]
    assert horn[0] == 100 and horn[-1] - horn[0] < 200
    assert lamp[0] - horn[0] >= 200


def test_an_action_time_that_is_no_time_is_reported() -> None:
    text = synthetic("time_variable_action.st").read_text().replace("dt : TIME", "dt : INT")
    text = text.replace(" := T#200ms", "")
    result = import_chart(text.encode(), "h.st")
    assert [format_row(r) for r in result.chart.all_steps()[1].actions] == []
    assert ("I020", 17) in codes(result.problems)
    assert "action time dt is a INT, not a TIME" in result.problems[0].message


def test_a_pou_the_grammar_cannot_read_does_not_keep_the_chart_beside_it_out() -> None:
    """An IL function and a TYPE block beside two charts: each is reported where it starts,
    and ``--pou`` reaches either chart."""
    source = synthetic("il_beside_chart.st")
    for pou, first in (("Blink", "Off"), ("Count", "Idle")):
        result = import_file(source, pou=pou)
        assert result.chart.all_steps()[0].name == first
        assert codes(result.problems) == [("I024", 3), ("I024", 12)]
    assert "FUNCTION AddOne does not parse as ST or textual SFC at line 7" in (
        result.problems[0].message
    )
    with pytest.raises(ImportFailed) as info:
        import_file(source)
    assert "holds 2 charts (Blink, Count)" in info.value.diagnostics[-1].message


def test_a_chart_that_does_not_parse_is_still_an_error_where_it_is() -> None:
    text = synthetic("il_beside_chart.st").read_text().replace("lamp(N);", "lamp(N)")
    with pytest.raises(ImportFailed) as info:
        import_chart(text.encode(), "il.st", pou="Blink")
    assert [(d.code, d.loc.line) for d in info.value.diagnostics if d.is_error] == [("I001", 26)]


def test_charts_in_actions_are_charts_of_their_own() -> None:
    """TwinCAT draws charts in a POU's actions: each is a chart ``POU.action``, with the
    POU's variables; ``--pou`` names it in full or by the action's name; the POU's own
    body (which calls them) is reported."""
    source = synthetic("twincat_action_charts.xml")
    for pou in ("Crane.Hoist", "Hoist"):
        result = import_file(source, pou=pou)
        chart = result.chart
        assert chart.name == "Crane.Hoist"
        assert [s.name for s in chart.all_steps()] == ["HoistIdle", "Lifting"]
        assert [format_row(r) for r in chart.all_steps()[1].actions] == ["N hoist;"]
        assert codes(result.problems) == [("I024", 16)]
        assert "charts of its actions are, each on its own (Crane.Hoist, Crane.Travel)" in (
            result.problems[0].message
        )
    assert import_file(source, pou="Travel").chart.all_steps()[0].name == "Parked"
    with pytest.raises(ImportFailed) as info:
        import_file(source, pou="Crane")
    assert "2 charts of Crane in the file" in info.value.diagnostics[-1].message


@pytest.mark.parametrize(
    "relative",
    [
        "plcopen/beremiz_traffic_light.xml",  # initialStep, negated (a NOT on a wire)
        "plcopen/iec_checker_example.xml",
        "simaticml/GraphBranch2.xml",  # Init
        "simaticml/StepSequence.xml",
    ],
)
def test_an_xsd_boolean_written_1_or_0_reads_as_true_or_false(relative: str) -> None:
    """Both schemas declare their flags ``xsd:boolean``, whose ``1`` and ``0`` are ``true``
    and ``false`` (a hand edit, another tool's writer): the same chart, the same problems."""
    words = corpus(relative).read_bytes()
    digits = re.sub(rb'(initialStep|negated|Init|constant)="true"', rb'\1="1"', words)
    digits = re.sub(rb'(initialStep|negated|Init|constant)="false"', rb'\1=" 0 "', digits)
    assert digits != words
    a, b = import_chart(words, "f.xml"), import_chart(digits, "f.xml")
    assert unlocated(a.chart) == unlocated(b.chart)
    assert codes(a.problems) == codes(b.problems)


def test_nested_comments_and_pragmas_read_as_blanks() -> None:
    """IEC 61131-3 ed.3 nests comments (``(* a (* b *) c *)``, ``/* */`` too) and leaves
    pragmas (``{attribute 'x'}``, as CODESYS writes them) to the reader: the same chart, its
    problems on the same lines and columns; a string holding ``(*`` stays a string."""
    plain = corpus("iec-text/matiec_sfc.txt").read_text(encoding="utf-8")
    dressed = re.sub(
        r"\bEND_STEP\b", "(* Schritt (* verschachtelt *) *) {attribute 'hide'} END_STEP", plain
    )
    dressed = dressed.replace("TRANSITION FROM", "/* a /* b */ */ TRANSITION FROM", 1)
    a, b = import_chart(plain.encode(), "f.st"), import_chart(dressed.encode(), "f.st")
    assert unlocated(a.chart) == unlocated(b.chart)
    assert [(d.code, d.loc.line) for d in a.problems] == [(d.code, d.loc.line) for d in b.problems]
    commented = CODESYS.replace(
        b"n := n + 1;", b"(* z\xc3\xa4hlen (* {x} *) *) n := n + 1; {attribute 'y'}"
    ).replace(b"<expression>NOT go</expression>", b"<expression>NOT /* /* */ */ go</expression>")
    assert unlocated(import_chart(commented, "s.xml").chart) == unlocated(
        import_chart(CODESYS, "s.xml").chart
    )
