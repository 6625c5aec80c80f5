"""``s7graph upload``'s files (``web/cli/upload.py``): the chart under the stem of the
file name the CPU gives and ``.s7g`` — a name from the bus never leaves the folder — and
the symbol table as ``symbols.txt``. Against a running CPU: ``tests/web/bus/
test_online_change.py``."""

from __future__ import annotations

import pytest

from s7graph.web.bus.protocol import ChartSource
from s7graph.web.cli.upload import SYMBOLS_FILE, files_of


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
    assert files_of(source) == [(name, "FUNCTION_BLOCK …")]


def test_the_symbol_table_comes_along_when_the_chart_has_one() -> None:
    source = ChartSource(fb="F", file="f.s7g", text="chart", symbols='"Start" I0.0 BOOL\n')
    assert files_of(source) == [("f.s7g", "chart"), (SYMBOLS_FILE, '"Start" I0.0 BOOL\n')]
    assert files_of(ChartSource(fb="F", text="chart", symbols=" \n")) == [("F.s7g", "chart")]
