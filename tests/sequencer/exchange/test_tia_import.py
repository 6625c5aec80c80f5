"""What a real TIA Portal GRAPH export holds that the SimaticML import refused or placed wrongly
(docs/import-export.md): named constants, a step's time compared with operands TIA types from
the comparison, global tags without an address, which get marker addresses inside the
CPU's M area, and transitions nobody named."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from s7graph.sequencer.exchange import ImportFailed, export_chart, import_chart, import_file
from s7graph.sequencer.exchange.markers import M_BYTES, Markers, used_bytes
from s7graph.sequencer.text.format import format_chart
from s7graph.sequencer.text.walk import uncommented, unlocated
from tests.sequencer.exchange.helpers import codes, import_to, sim, synthetic


def test_a_global_constant_is_an_fb_variable_and_a_block_constant_its_value() -> None:
    """``Scope="GlobalConstant"`` (its value in the PLC's constants table, which a block
    export does not carry) no longer refuses the block: it is an FB variable of that name,
    typed by the comparison, reported for the user to give its value; a block constant
    (``LocalConstant``) is the value its interface gives."""
    result = import_file(synthetic("tia_global_constant.xml"))
    text = format_chart(result.chart)
    assert 'TRANSITION T1 FROM S1 TO S2 := "Start" AND strokes < MAX_STROKES;' in text
    assert "TRANSITION T2 FROM S2 TO S1 := S2.U > T#2S;" in text
    assert "  MAX_STROKES : INT;" in text
    assert ("I023", 209) in codes(result.problems)
    assert "constant MAX_STROKES is in the PLC's constants table" in " ".join(
        d.message for d in result.problems
    )


def test_a_named_constant_as_an_array_index_keeps_its_name() -> None:
    xml = synthetic("tia_global_constant.xml").read_text()
    xml = xml.replace(
        '<Component Name="Start" />',
        '<Component Name="Station" /><Component Name="OP"><Access Scope="GlobalConstant" '
        'UId="90"><Constant Name="C_OP10" /></Access></Component>',
    )
    assert '"Station.OP[C_OP10]"' in format_chart(import_chart(xml.encode(), "t.xml").chart)


def test_a_steps_time_compared_with_an_untyped_operand_compares_times(tmp_path: Path) -> None:
    """``Pressing.U > "PressTime"`` with no SrcType: the tag is a TIME (TIA compiles it so);
    ``Idle.T > 5000``: an untyped integer compared with a time is milliseconds; a DInt tag
    compared with a time is declared TIME (reported: TIA's milliseconds, the same 32
    bits). None of them refuses the block any more, and the chart runs."""
    result = import_file(synthetic("tia_time_compare.xml"))
    text = format_chart(result.chart)
    assert 'S2.U > "PressTime"' in text
    assert 'S1.T > T#5000MS AND "MaxIdle" < S1.T' in text
    types = {s.name: s.type for s in result.chart.symbols}
    assert types["PressTime"] == types["MaxIdle"] == "TIME"
    assert codes(result.problems) == [("I032", 7), ("I031", 224)]
    rc, chart = import_to(tmp_path, synthetic("tia_time_compare.xml"))
    assert rc == 1
    records = sim(
        tmp_path,
        chart,
        watch=[],
        cycles=80,
        cycle_ms=100,
        stimulus=[{"at_ms": 0, "set": {"Start": True, "MaxIdle": 0, "PressTime": 1500}}],
    )
    (t1, e1), (t2, e2) = [(r["t_ms"], e) for r in records for e in r["events"]][:2]
    assert (e1, e2) == (["S1", "S2"], ["S2", "S1"])
    assert 5000 < t1 <= 5100 and 1500 < t2 - t1 <= 1600


def test_unaddressed_tags_get_marker_addresses_inside_the_cpus_m_area(tmp_path: Path) -> None:
    """67 tags without an address (56 TIME, 11 BOOL): every allocated address lies in the
    CPU's 256 bytes of M (they went up to MD370 before, and the CPU stopped at the first
    write), away from the retentive MB0…MB15; the chart runs and writes them all."""
    result = import_file(synthetic("tia_many_tags.xml"))
    taken = [b for s in result.chart.symbols for b in used_bytes(s.address)]
    assert len(result.chart.symbols) == 67
    assert max(taken) < M_BYTES and min(taken) >= 16
    assert len(taken) == len(set(taken)) + 9  # 11 bits share 2 bytes
    assert import_to(tmp_path, synthetic("tia_many_tags.xml"))[0] == 1
    chart = tmp_path / "chart.s7g"
    records = sim(
        tmp_path,
        chart,
        watch=['"Wait56"', '"Lamp10"'],
        cycles=4,
        stimulus=[{"at_ms": 0, "set": {"Go": True}}],
    )
    assert records[-1]["values"] == {'"Wait56"': 56_000, '"Lamp10"': True}


def test_tags_that_do_not_fit_the_m_area_refuse_the_chart_where_they_are() -> None:
    """Four TIME tags more than M holds: an error at the first that does not fit, no chart
    (one the CPU could not run)."""
    xml = synthetic("tia_many_tags.xml").read_text()
    first = re.search(r"<Action [^>]*>\s*<Token Text='\"Wait1\" := T#1S' />", xml)
    assert first is not None
    more = "".join(
        first.group(0).replace('"Wait1" := T#1S', f'"Extra{i}" := T#1S') + "</Action>\n"
        for i in range(4)
    )
    xml = xml.replace(first.group(0), more + first.group(0), 1)
    with pytest.raises(ImportFailed) as info:
        import_chart(xml.encode(), "many.xml")
    [error] = [d for d in info.value.diagnostics if d.is_error]
    assert error.code == "I014" and "no room for tag" in error.message


def test_the_allocator_skips_bytes_in_use_and_aligns_words() -> None:
    alloc = Markers({150, 151, 153}, size=160)
    assert alloc.take("D") == "MD154"
    assert alloc.take("W") == "MW158"
    assert alloc.take("W") == "MW16"
    assert alloc.take("") == "M100.0"
    assert [alloc.take("") for _ in range(8)][-1] == "M101.0"


def test_a_static_string_keeps_the_length_tia_declared() -> None:
    """``String[8]`` is a ``STRING[8]`` variable, not one of 254 characters."""
    xml = (
        synthetic("tia_global_constant.xml")
        .read_text()
        .replace(
            '<Member Name="strokes" Datatype="Int">',
            '<Member Name="label" Datatype="String[8]"><StartValue>\'Drill\'</StartValue></Member>'
            '<Member Name="strokes" Datatype="Int">',
        )
    )
    text = format_chart(import_chart(xml.encode(), "t.xml").chart)
    assert "  label : STRING[8] := 'Drill';" in text


def _names(xml: str) -> list[tuple[str, str, str | None]]:
    """(element, Number, Name or None when it has none) of every step and transition."""
    out: list[tuple[str, str, str | None]] = []
    for tag, attrs in re.findall(r"<(Step|Transition) ([^>]*)>", xml):
        name = re.search(r'\bName="([^"]*)"', attrs)
        number = re.search(r'\bNumber="(\d+)"', attrs)
        assert number is not None
        out.append((tag, number[1], name[1] if name else None))
    return out


def test_a_transition_nobody_named_stays_unnamed_through_a_simaticml_round_trip() -> None:
    """TIA gives a transition nobody named its default name (``Trans1``); a file may also
    carry none. Both import as an unnamed transition, which the export writes with TIA's
    default again, while a name its author gave (``Back``) stays: importing the export
    gives the same chart, and the export names every step and transition as the file did."""
    source = synthetic("tia_unnamed_transitions.xml")
    first = import_file(source)
    names = [(t.number, t.name) for t in first.chart.all_transitions()]
    assert names == [(1, ""), (2, ""), (3, "Back")]
    xml = export_chart(first.chart, "simaticml")
    written = _names(source.read_text())
    assert ("Transition", "2", None) in written
    assert _names(xml) == [
        (tag, n, name if name is not None else f"Trans{n}") for tag, n, name in written
    ]
    back = import_chart(xml.encode(), "back.xml").chart
    assert uncommented(unlocated(back.sequences)) == uncommented(unlocated(first.chart.sequences))
