"""Every corpus file imports into a chart ``s7graph check`` accepts, and reports exactly
what it could not map, at its line in the file (docs/import-export.md). The corpus is read in place
(``../shared/corpus``); the tests skip when it is absent."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from s7graph.sequencer.exchange import export_chart, import_file
from s7graph.sequencer.text.format import format_chart, format_expr, format_row
from s7graph.sequencer.text.model import Chart
from s7graph.web.cli import main
from tests.sequencer.exchange.helpers import codes, corpus, import_to, imported

# file → (format, [(code, line) of every problem the import reports])
EXPECTED: dict[str, tuple[str, list[tuple[str, int]]]] = {
    "iec-text/ironplc_first_steps_counter_sfc.st": ("iec-text", [("I023", 12)]),
    "iec-text/matiec_annexF_gravel.txt": (
        "iec-text",
        [
            ("I022", 34),
            ("I031", 36),
            ("I031", 37),
            ("I031", 38),
            ("I022", 40),
            ("I021", 76),
            ("I021", 77),
            ("I031", 85),
            ("I021", 96),
            ("I021", 97),
            ("I024", 102),
        ],
    ),
    "iec-text/matiec_sfc.txt": ("iec-text", [("I023", 3), ("I023", 6), ("I024", 158)]),
    "plcopen/beremiz_first_steps.xml": (
        "plcopen",
        [
            ("I024", 20),
            ("I024", 72),
            ("I024", 451),
            ("I024", 494),
            ("I024", 910),
            ("I024", 963),
            ("I024", 1141),
        ],
    ),
    "plcopen/beremiz_test_svgui.xml": (
        "plcopen",
        [
            ("I023", 29),
            ("I023", 73),
            ("I024", 93),
            ("I024", 1157),
            ("I024", 1306),
            ("I024", 1557),
            ("I023", 1971),
            ("I023", 1976),
            ("I021", 1994),
            ("I020", 2678),
            ("I024", 2693),
        ],
    ),
    "plcopen/beremiz_traffic_light.xml": (
        "plcopen",
        [
            ("I031", 62),
            ("I031", 67),
            ("I031", 97),
            ("I031", 102),
            ("I031", 107),
            ("I031", 112),
            ("I031", 490),
            ("I031", 494),
            ("I024", 1214),
            ("I024", 1419),
        ],
    ),
    "plcopen/iec_checker_example.xml": (
        "plcopen",
        [
            ("I024", 26),
            ("I024", 260),
            ("I024", 400),
            ("I033", 496),
            ("I033", 496),
            ("I020", 799),
            ("I031", 802),
            ("I024", 809),
            ("I024", 868),
            ("I024", 895),
        ],
    ),
    "plcopen/matiec_SFC_TEST.xml": ("plcopen", [("I023", 40), ("I023", 53), ("I024", 783)]),
    "simaticml/GraphBranch2.xml": ("simaticml", []),
    "simaticml/GraphBranchAbortOption.xml": ("simaticml", []),
    "simaticml/GraphEnd.xml": ("simaticml", []),
    "simaticml/StepSequence.xml": ("simaticml", [("I032", 34)]),
}


def edges(chart: Chart) -> list[tuple[int, tuple[int, ...], tuple[int, ...]]]:
    """(number, FROM, TO) of every transition, in written (priority) order."""
    return [(t.number, t.sources, t.targets) for t in chart.all_transitions()]


def steps(chart: Chart) -> dict[str, int]:
    return {s.name: s.number for s in chart.all_steps()}


@pytest.mark.parametrize("relative", sorted(EXPECTED))
def test_corpus_file_imports_reporting_exactly_what_it_cannot_map(relative: str) -> None:
    fmt, expected = EXPECTED[relative]
    result = imported(relative)
    assert result.format == fmt
    assert codes(result.problems) == expected
    assert all(d.loc.file == str(corpus(relative)) for d in result.problems)


@pytest.mark.parametrize("relative", sorted(EXPECTED))
def test_imported_corpus_chart_passes_s7graph_check(relative: str, tmp_path: Path) -> None:
    rc, out = import_to(tmp_path, corpus(relative))
    assert rc == (1 if EXPECTED[relative][1] else 0)
    assert main(["check", str(out)]) in (0, 1)  # warnings (empty TIA transitions) at most


def test_matiec_sfc_test_keeps_its_four_way_alternative_and_three_way_branch() -> None:
    """The alternative out of STEP2 is written left to right (A1 x=80, A2 x=384, A3 x=659,
    D x=920 in the file): the GRAPH priority of a chart drawn without PRIORITY."""
    chart = imported("plcopen/matiec_SFC_TEST.xml").chart
    n = steps(chart)
    out_of_step2 = [t for t in chart.all_transitions() if t.sources == (n["STEP2"],)]
    assert [t.targets for t in out_of_step2] == [
        (n["A1"],),
        (n["A2"],),
        (n["A3"],),
        (n["D1"], n["D2"], n["D3"]),
    ]
    join = next(t for t in chart.all_transitions() if len(t.sources) == 3)
    assert join.sources == (n["E1"], n["E2"], n["E3"]) and join.targets == (n["GO"],)


def test_xml_and_textual_twins_of_sfc_test_give_the_same_chart_shape() -> None:
    xml = imported("plcopen/matiec_SFC_TEST.xml").chart
    text = imported("iec-text/matiec_sfc.txt").chart

    def shape(chart: Chart) -> set[tuple[tuple[str, ...], tuple[str, ...]]]:
        name = {s.number: s.name for s in chart.all_steps()}
        return {
            (tuple(name[s] for s in t.sources), tuple(name[s] for s in t.targets))
            for t in chart.all_transitions()
        }

    assert shape(xml) == shape(text)


def test_gravel_becomes_three_sequences_with_cross_chart_step_attributes() -> None:
    chart = imported("iec-text/matiec_annexF_gravel.txt").chart
    assert [[s.name for s in q.steps] for q in chart.sequences] == [
        ["START", "FILL_BIN", "LOAD_WAIT", "RUN_IN", "DUMP_BIN", "RUNOUT"],
        ["CONTROL_OFF", "CONTROL"],
        ["MONITOR"],
    ]
    t1 = chart.all_transitions()[0]
    assert t1.condition is not None
    assert format_expr(t1.condition) == "FILL_PB AND S8.X"  # CONTROL.X of the second chart


def test_svgui_two_charts_in_one_pou_are_two_sequences_with_a_join() -> None:
    chart = imported("plcopen/beremiz_test_svgui.xml").chart
    n = steps(chart)
    assert [q.steps[0].name for q in chart.sequences] == ["Start", "Start2"]
    assert (n["Start"],) in [t.sources for t in chart.all_transitions()]
    join = next(t for t in chart.all_transitions() if len(t.sources) == 2)
    assert join.sources == (n["WAIT1"], n["WAIT2"]) and join.targets == (n["TIMED_WAIT"],)


def test_tia_branch_export_keeps_numbers_names_alternatives_and_jumps() -> None:
    chart = imported("simaticml/GraphBranch2.xml").chart
    assert chart.name == "FB_SEQ_One" and chart.fb_number == 1234
    assert steps(chart) == {"Step 1": 1, "Step 21": 21, "Step 27": 27, "Step 32": 32, "Step 43": 43}
    assert edges(chart) == [
        (1, (1,), (21,)),
        (21, (21,), (27,)),
        (121, (21,), (32,)),
        (27, (27,), (32,)),
        (127, (27,), (43,)),
        (32, (32,), (43,)),
        (43, (43,), (1,)),
    ]
    assert chart.all_transitions()[2].name == "Abort Step (121)"
    assert all(t.condition is None for t in chart.all_transitions())  # coil on the rail


def test_tia_three_way_alternative_lists_its_paths_in_branch_order() -> None:
    chart = imported("simaticml/GraphBranchAbortOption.xml").chart
    assert [(t.number, t.targets) for t in chart.all_transitions() if t.sources == (21,)] == [
        (21, (27,)),
        (121, (32,)),
        (221, (43,)),
    ]


def test_tia_end_connection_is_a_branch_stop() -> None:
    chart = imported("simaticml/GraphEnd.xml").chart
    assert edges(chart)[-1] == (43, (43,), ())


def test_tia_v16_actions_and_lad_transition_are_rows_and_a_condition() -> None:
    chart = imported("simaticml/StepSequence.xml").chart
    s1 = chart.all_steps()[0]
    assert [format_row(r) for r in s1.actions] == [
        'N "StepData.Values.CurrentStep" := 1;',
        'S1 R "StepData.Values.CycleAbort";',
    ]
    text = format_chart(chart)
    assert (
        '"StepData.Values.CylcleState" = 1 AND "StepData.Values.StepMode" = 0 AND '
        '"StepData.Values.CurrentTime" > "StepData.Steps[1].WaitingTime" OR'
    ) in text
    assert edges(chart)[-1] == (2, (2,), ())
    assert chart.options.messages and chart.options.ack_required


def _element_names(xml: str) -> list[tuple[str, str, str]]:
    """(element, Number, Name) of every step and transition, sorted."""
    out = []
    for tag, attrs in re.findall(r"<(Step|Transition) ([^>]*)>", xml):
        number = re.search(r'\bNumber="(\d+)"', attrs)
        name = re.search(r'\bName="([^"]*)"', attrs)
        assert number is not None and name is not None, attrs
        out.append((tag, number[1], name[1]))
    return sorted(out)


@pytest.mark.parametrize(
    "name", ["GraphBranch2", "GraphBranchAbortOption", "GraphEnd", "StepSequence"]
)
def test_a_tia_export_exported_again_names_steps_and_transitions_as_tia_did(name: str) -> None:
    """Import, then export: every step and transition has the name TIA wrote —
    StepSequence's transitions, TIA's defaults ``Trans1`` and ``Trans2``, are unnamed in
    the chart and go out with those defaults again."""
    source = corpus(f"simaticml/{name}.xml")
    chart = import_file(source).chart
    assert _element_names(export_chart(chart, "simaticml")) == _element_names(
        source.read_text(encoding="utf-8")
    )
    if name == "StepSequence":
        assert [t.name for t in chart.all_transitions()] == ["", ""]
