"""``block_texts``: each block of the S7-SCL sources as written, from its first line to its
``END_`` line, in source order, with its file and line (what ``s7graph/<cpu>/blocks``
serves, docs/bus.md)."""

from __future__ import annotations

from pathlib import Path

from s7graph.web.harness.scl import block_texts, compile_sources

FIRST = """// a counter: not part of the block
FUNCTION_BLOCK FB17
VAR_INPUT go : BOOL; END_VAR
VAR n : DINT; END_VAR
  IF go THEN n := n + 1; END_IF;
END_FUNCTION_BLOCK

// between the blocks
function FC3 : INT
VAR_INPUT a : INT; END_VAR
  FC3 := a * 2;
end_function
DATA_BLOCK DB10 FB17
BEGIN
END_DATA_BLOCK
"""
SECOND = """ORGANIZATION_BLOCK OB1
  FB17.DB10(go := FC3(a := 1) > 0);
END_ORGANIZATION_BLOCK
"""


def test_each_block_is_its_lines_from_its_start_to_its_end_in_source_order(
    tmp_path: Path,
) -> None:
    first, second = tmp_path / "blocks.scl", tmp_path / "main.scl"
    first.write_text(FIRST, encoding="utf-8")
    second.write_text(SECOND, encoding="utf-8")
    texts = block_texts(compile_sources([first, second]))
    assert [(t.label, t.file, t.line) for t in texts] == [
        ("FB17", str(first), 2),
        ("FC3", str(first), 9),
        ("DB10", str(first), 13),
        ("OB1", str(second), 1),
    ]
    lines = FIRST.splitlines()
    assert texts[0].text == "\n".join(lines[1:6]) and texts[0].name == "FB17"
    assert texts[1].text == "\n".join(lines[8:12])  # end_function, in any case
    assert texts[2].text == "DATA_BLOCK DB10 FB17\nBEGIN\nEND_DATA_BLOCK"
    assert texts[3].text == SECOND.strip()
