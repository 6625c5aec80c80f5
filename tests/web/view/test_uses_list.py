"""A page's cross-reference list and the CPU's S7-SCL blocks (``web/view/uses_list.py``):
each block parsed where it stands in its file, a block that does not parse left out, a
use in a block labelled by its file and line and found again by its block's key."""

from __future__ import annotations

from s7graph.engine.errors import SourceLocation
from s7graph.sequencer.xref import Use
from s7graph.web.bus.protocol import BlockSource, BlockSources
from s7graph.web.view.uses_list import block_key, parsed_blocks, use_label

SOURCES = BlockSources(
    blocks=[
        BlockSource(
            label="FC5",
            file="plant.scl",
            line=7,
            text="FUNCTION FC 5 : VOID\nBEGIN\n  M1.0 := Q0.0;\nEND_FUNCTION\n",
        ),
        BlockSource(
            label="FC6",
            file="plant.scl",
            line=12,
            text="FUNCTION FC 6 : VOID\nBEGIN\n  M1.0 := ;\nEND_FUNCTION\n",
        ),
    ]
)


def test_each_block_is_parsed_at_its_line_and_a_broken_one_left_out() -> None:
    parsed = parsed_blocks(SOURCES)
    assert [u.name for s in parsed for u in s.units] == ["FC5"]
    assign = parsed[0].units[0].body[0]
    assert (assign.loc.file, assign.loc.line) == ("plant.scl", 9)
    assert parsed_blocks(None) == []


def test_a_use_in_a_block_names_its_file_and_is_found_by_its_blocks_key() -> None:
    use = Use("Q0.0", "FC 5", "read", SourceLocation("/srv/plant.scl", 9, 11))
    assert use_label(use) == "FC 5 · read · plant.scl:9"
    assert block_key("FC 5") == "FC5" and block_key('FB "Mixer"') == '"Mixer"'
    assert block_key('S2 "Fill" row 1 (S1 N)') is None
