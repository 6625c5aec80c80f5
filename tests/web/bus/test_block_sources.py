"""``s7graph/<cpu>/blocks`` on a real bus: the S7-SCL blocks the CPU runs, read when asked
(after a reload, the new ones); file names without their folder; one message stays under
the bus's limit, the blocks that do not fit only named (docs/bus.md, "Keys"). The same
sources whole, file by file, in the room the blocks leave and on the chart's ``source`` key
(``source_files``)."""

from __future__ import annotations

from pathlib import Path

from s7graph.web.bus.block_sources import (
    MAX_TEXT_BYTES,
    block_sources,
    serve_blocks,
    source_files,
)
from s7graph.web.bus.client import BusClient
from s7graph.web.bus.cpu_side import CpuSide
from s7graph.web.bus.protocol import (
    MAX_MESSAGE_BYTES,
    BlockSources,
    ChartSource,
    decode,
    encode,
)
from s7graph.web.bus.session import open_session
from s7graph.web.harness.scl import SclSources, compile_sources, compile_texts

SOURCE = """FUNCTION FC{n} : INT
VAR_INPUT a : INT; END_VAR
  FC{n} := a + {n};{pad}
END_FUNCTION
"""


def _compiled(tmp_path: Path, name: str, *numbers: int, pad: int = 0) -> SclSources:
    return compile_sources([_source(tmp_path, name, numbers, pad)])


def _source(tmp_path: Path, name: str, numbers: tuple[int, ...], pad: int = 0) -> Path:
    """``src/<name>`` holding an FC of ``SOURCE`` for each of ``numbers`` (each ``pad``
    characters of comment longer)."""
    path = tmp_path / "src" / name
    path.parent.mkdir(exist_ok=True)
    text = "".join(SOURCE.format(n=n, pad=" // " + "x" * pad if pad else "") for n in numbers)
    path.write_text(text, encoding="utf-8")
    return path


def test_a_client_reads_the_blocks_the_cpu_runs_now(tmp_path: Path) -> None:
    running: list[SclSources | None] = [None]
    side = CpuSide({}, cpu="cpu1")
    try:
        serve_blocks(side.publisher, lambda: running[0])
        with open_session(connect=[side.endpoint]) as session:
            client = BusClient(session, "cpu1")
            assert client.blocks() == BlockSources()  # no S7-SCL blocks: an empty list
            running[0] = _compiled(tmp_path, "a.scl", 1, 2)
            first = client.blocks()
            assert first is not None
            assert [(b.label, b.file, b.line) for b in first.blocks] == [
                ("FC1", "a.scl", 1),
                ("FC2", "a.scl", 5),
            ]
            assert first.blocks[1].text.splitlines()[2] == "  FC2 := a + 2;"
            whole = (tmp_path / "src" / "a.scl").read_text(encoding="utf-8")
            assert first.files == {"a.scl": whole} and first.files_left_out == []
            running[0] = _compiled(tmp_path, "b.scl", 7)  # an online change brought others
            again = client.blocks()
            assert again is not None and [b.label for b in again.blocks] == ["FC7"]
            client.close()
    finally:
        side.close()


def test_blocks_past_the_message_limit_are_only_named(tmp_path: Path) -> None:
    pad = MAX_TEXT_BYTES // 3  # two sources: one may hold at most 1,000,000 characters
    paths = [_source(tmp_path, f"big{k}.scl", (2 * k - 1, 2 * k), pad) for k in (1, 2)]
    message = block_sources(compile_sources(paths))
    assert [b.label for b in message.blocks] == ["FC1", "FC2"]
    assert message.left_out == ["FC3", "FC4"]
    assert message.files == {} and message.files_left_out == ["big1.scl", "big2.scl"]
    data = encode(message)
    assert len(data) < MAX_MESSAGE_BYTES and decode(data, BlockSources) == message


def test_whole_sources_for_the_chart_go_by_file_name_and_past_the_limit_only_named(
    tmp_path: Path,
) -> None:
    """Each source whole under its file's name (no folder), in order; from the first that
    would not fit beside the chart's own text, only named — the message stays readable."""
    assert source_files(None) == ({}, [])
    small, other = SOURCE.format(n=1, pad=""), SOURCE.format(n=3, pad="")
    big = SOURCE.format(n=2, pad=" // " + "x" * (MAX_TEXT_BYTES // 2))
    texts = [("/plant/a.scl", small), ("/plant/b.scl", big), ("/plant/c.scl", other)]
    sources = compile_texts(texts)
    assert source_files(sources) == ({"a.scl": small, "b.scl": big, "c.scl": other}, [])
    chart = "x" * (MAX_TEXT_BYTES // 2)
    files, left_out = source_files(sources, room=MAX_TEXT_BYTES - len(chart))
    assert (files, left_out) == ({"a.scl": small}, ["b.scl", "c.scl"])
    message = ChartSource(fb="F", text=chart, blocks=files, left_out=left_out)
    data = encode(message)
    assert len(data) < MAX_MESSAGE_BYTES and decode(data, ChartSource) == message
