"""Source text on disk: UTF-8, and where a bad byte is (charts, symbol tables, stimuli).

``decode_utf8`` turns bytes into text or raises :class:`NotUtf8` naming the file, the line
and the column of the first byte that is not UTF-8 — a located error like any other.
"""

from __future__ import annotations

from pathlib import Path

from s7graph.engine.errors import S7Error, SourceLocation

__all__ = ["NotUtf8", "decode_utf8", "is_unicode", "read_utf8"]


class NotUtf8(S7Error):
    """Bytes that are not UTF-8; ``where`` is the place of the first bad byte."""


def decode_utf8(data: bytes, file: str = "<input>", *, bom: bool = True) -> str:
    """``data`` as text (a leading BOM dropped when ``bom``); ``NotUtf8`` at the bad byte."""
    try:
        return data.decode("utf-8-sig" if bom else "utf-8")
    except UnicodeDecodeError as exc:
        before = data[: exc.start]
        line = before.count(b"\n") + 1
        start = before.rfind(b"\n") + 1
        col = len(before[start:].decode("utf-8", errors="replace")) + 1
        bad = data[exc.start : exc.start + 1].hex()
        where = SourceLocation(file, line, col)
        raise NotUtf8(f"not UTF-8: byte 0x{bad} ({exc.reason})", where) from None


def read_utf8(path: str | Path) -> str:
    """The text of the file at ``path`` (OSError if it cannot be read, ``NotUtf8``)."""
    return decode_utf8(Path(path).read_bytes(), str(path))


def is_unicode(text: str) -> bool:
    """Whether ``text`` can be written as UTF-8: no lone surrogate, which is what Python
    makes of command-line bytes that were not UTF-8."""
    try:
        text.encode("utf-8")
    except UnicodeEncodeError:
        return False
    return True
