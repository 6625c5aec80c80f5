"""The S7-SCL blocks a CPU runs, as source, on the bus (``s7graph/<cpu>/blocks``).

A chart run with ``--blocks`` and a program of S7-SCL blocks serve the text of every block
of their sources (:class:`BlockSources`), so a view shows the FB or FC a step's ``CALL``
row calls as it was written: read-only, as the engineering station opens a block of the
CPU ("Opening a block online", in the STEP 7 programming manual). Each block is its own
lines (``web.harness.scl.block_texts``), in source order; file names go without their
directory. One message stays under the bus's limit: the blocks after the first that
would not fit are only named (``left_out``).

The same message, and the chart's source (``fb/<fb>/source``), carry the sources whole,
file by file (:func:`source_files`), for ``s7graph upload``: what a download's ``blocks``
replace, or a program of blocks as it was loaded.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import PurePath

from s7graph.web.bus.protocol import MAX_MESSAGE_BYTES, BlockSource, BlockSources, encode
from s7graph.web.bus.publisher import BusPublisher
from s7graph.web.harness.scl import SclSources, block_texts

__all__ = ["MAX_TEXT_BYTES", "block_sources", "serve_blocks", "source_files"]

MAX_TEXT_BYTES = MAX_MESSAGE_BYTES * 3 // 4
"""The texts one message carries at most (UTF-8; JSON escapes take some of the rest)."""


def _size(text: str) -> int:
    """About what ``text`` takes in a JSON message (escaped line breaks, its name)."""
    return len(text.encode()) + 2 * text.count("\n") + 300


def block_sources(sources: SclSources | None) -> BlockSources:
    """The message of ``sources`` (None: no S7-SCL blocks, an empty list): each block's
    text, then — in the room the blocks leave — each source whole (:func:`source_files`)."""
    if sources is None:
        return BlockSources()
    blocks: list[BlockSource] = []
    left_out: list[str] = []
    room = MAX_TEXT_BYTES
    for b in block_texts(sources):
        if left_out or _size(b.text) > room:
            left_out.append(b.label)
            continue
        room -= _size(b.text)
        blocks.append(
            BlockSource(
                label=b.label,
                name=b.name[:256],
                file=PurePath(b.file).name[:256],
                line=b.line,
                text=b.text,
            )
        )
    files, files_left_out = source_files(sources, room=room)
    return BlockSources(
        blocks=blocks, left_out=left_out, files=files, files_left_out=files_left_out
    )


def source_files(
    sources: SclSources | None, *, room: int = MAX_TEXT_BYTES
) -> tuple[dict[str, str], list[str]]:
    """The S7-SCL sources of ``sources`` whole, by file name (no directory), in order, as
    far as they fit in ``room`` bytes of a message; and the names of the others (the first
    that does not fit, all after it, and a second source of a name already taken)."""
    files: dict[str, str] = {}
    left_out: list[str] = []
    if sources is None:
        return files, left_out
    for file, text in zip(sources.files, sources.texts, strict=False):
        name = PurePath(file).name[:256]
        if left_out or _size(text) > room or name in files:
            left_out.append(name)
            continue
        room -= _size(text)
        files[name] = text
    return files, left_out


def serve_blocks(publisher: BusPublisher, read: Callable[[], SclSources | None]) -> None:
    """Serve ``blocks`` on ``publisher``'s bus: the message of the sources ``read()`` gives
    at the query (those the CPU runs now), encoded once per sources."""
    made: list[tuple[object, bytes]] = []

    def answer() -> bytes:
        sources = read()
        if not made or made[0][0] is not sources:
            made[:] = [(sources, encode(block_sources(sources)))]
        return made[0][1]

    publisher.serve("blocks", answer)
