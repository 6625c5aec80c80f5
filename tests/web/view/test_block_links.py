"""Which blocks a step's ``CALL`` rows call, a program's list of its blocks, and finding
and showing their source (``web.view.block_links``; the pages' buttons:
test_block_links_browser.py, test_program_blocks_browser.py)."""

from __future__ import annotations

from s7graph.web.bus.protocol import ActionInfo, BlockSource, BlockSources, ChartLayout, StepInfo
from s7graph.web.view.block_links import called_blocks, find_block, listed_blocks, source_html
from s7graph.web.view.program_view import blocks_html


def _layout(*operands: tuple[str, str]) -> ChartLayout:
    rows = [ActionInfo(qualifier=q, operand=o) for q, o in operands]
    return ChartLayout(
        fb="Seq", steps=[StepInfo(number=1, actions=rows)], transitions=[], sequences=[]
    )


def test_a_steps_call_rows_name_each_block_once_in_row_order() -> None:
    layout = _layout(
        ("N", "Motor_on"),
        ("CALL", "FB 17, DB 10 (go := TRUE)"),
        ("CALL", "fc3 (a := 2)"),
        ("CALL", "FB 17, DB 11"),
        ("CALL", '"Counter", "Inst" (go := TRUE)'),
        ("N", "FB 20"),
    )
    assert called_blocks(layout, 1) == [
        ("FB17", "FB 17"),
        ("FC3", "FC 3"),
        ('"Counter"', '"Counter"'),
    ]
    assert called_blocks(layout, 2) == []  # no such step


def test_a_block_is_found_by_its_label_or_its_name_and_shown_escaped() -> None:
    fb = BlockSource(label="FB5", name="Counter", file="b.scl", line=3, text="x := a < b;")
    sources = BlockSources(blocks=[BlockSource(label="FC3"), fb])
    assert find_block(sources, "FB5") is fb and find_block(sources, '"counter"') is fb
    assert find_block(sources, "FB6") is None and find_block(sources, '"Other"') is None
    shown = source_html(fb)
    assert "x := a &lt; b;" in shown and "FB5 Counter" in shown and "b.scl, line 3" in shown


def test_a_programs_list_names_every_block_in_source_order_the_left_out_last() -> None:
    sources = BlockSources(
        blocks=[
            BlockSource(label="FB10", name="Counter"),
            BlockSource(label="DB20", name="DB20"),
            BlockSource(label="OB1"),
        ],
        left_out=["FC300"],
    )
    assert listed_blocks(sources) == [
        ("FB10", 'FB 10 "Counter"'),
        ("DB20", "DB 20"),
        ("OB1", "OB 1"),
        ("FC300", "FC 300"),
    ]
    assert "4 blocks" in blocks_html(sources)
    assert "no S7-SCL blocks" in blocks_html(BlockSources())  # a Python program
    assert "does not answer" in blocks_html(None)
