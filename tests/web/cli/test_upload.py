"""``s7graph upload``'s files (``web/cli/upload.py``): the chart under the stem of the
file name the CPU gives and ``.s7g`` — a name from the bus never leaves the folder — the
symbol table as ``symbols.txt``, each S7-SCL source under its own name. Against a running
CPU: ``tests/web/bus/test_online_change.py`` and ``test_online_change_blocks.py``."""

from __future__ import annotations

import pytest

from s7graph.web.bus.protocol import BlockSources, ChartSource
from s7graph.web.cli.upload import SYMBOLS_FILE, files_of, program_files


def _written(source: ChartSource) -> list[tuple[str, str]]:
    return [(name, text) for name, text, _ in files_of(source).files]


@pytest.mark.parametrize(
    ("file", "name"),
    [
        ("drill.s7g", "drill.s7g"),
        ("line 2.xml", "line 2.s7g"),  # an imported chart: its text is .s7g now
        ("../../etc/passwd", "passwd.s7g"),
        ("C:\\plant\\drill.s7g", "drill.s7g"),
        ("", "Seq_drill.s7g"),
        ("..", "Seq_drill.s7g"),
        ("a\x00b.s7g", "Seq_drill.s7g"),
        ("symbols.txt", "symbols.s7g"),
    ],
)
def test_the_chart_is_written_under_its_files_stem_in_the_folder(file: str, name: str) -> None:
    source = ChartSource(fb="Seq_drill", file=file, text="FUNCTION_BLOCK …")
    assert _written(source) == [(name, "FUNCTION_BLOCK …")]


def test_the_symbol_table_comes_along_when_the_chart_has_one() -> None:
    source = ChartSource(fb="F", file="f.s7g", text="chart", symbols='"Start" I0.0 BOOL\n')
    assert _written(source) == [("f.s7g", "chart"), (SYMBOLS_FILE, '"Start" I0.0 BOOL\n')]
    assert _written(ChartSource(fb="F", text="chart", symbols=" \n")) == [("F.s7g", "chart")]


def test_each_scl_source_is_written_under_its_own_name_and_the_rest_named_as_skipped() -> None:
    """The sources in the CPU's order after the chart and its symbols; a name that is no
    file name here, or one taken by a file before it, is not written; nor one the CPU left
    out of its answer — each gets a line."""
    source = ChartSource(
        fb="F",
        file="f.s7g",
        text="chart",
        symbols="syms",
        blocks={"b.scl": "B", "..": "X", "f.s7g": "Y", "sub/c.scl": "C", "symbols.txt": "Z"},
        left_out=["big.scl"],
    )
    upload = files_of(source)
    assert [(n, t) for n, t, _ in upload.files] == [
        ("f.s7g", "chart"),
        (SYMBOLS_FILE, "syms"),
        ("b.scl", "B"),
        ("c.scl", "C"),
    ]
    assert upload.skipped == [
        ("..", "not written: no file name here"),
        ("f.s7g", "not written: the name of a file written before it"),
        ("symbols.txt", "not written: the name of a file written before it"),
        ("big.scl", "not uploaded: too large for one bus message"),
    ]


def test_a_program_of_blocks_uploads_its_sources_by_name() -> None:
    """A CPU without a chart: its S7-SCL sources, as a chart's are, skipped alike."""
    blocks = BlockSources(files={"main.scl": "M", "lib/x.scl": "X"}, files_left_out=["y.scl"])
    upload = program_files(blocks)
    assert [(n, t) for n, t, _ in upload.files] == [("main.scl", "M"), ("x.scl", "X")]
    assert upload.skipped == [("y.scl", "not uploaded: too large for one bus message")]
