"""``s7graph upload --connect EP --cpu NAME [--fb FB] [--to DIR]``: the chart an FB runs,
back from the CPU — STEP 7's "Upload from device": the ``.s7g`` text the CPU compiled (a
download from the page included), the symbol table it was compiled with and the S7-SCL
sources it runs beside the chart (``fb/<fb>/source``). Without ``--to`` the chart's text
goes to stdout; with it, the chart is written to ``DIR/<its file name>`` (``<FB>.s7g``
when the CPU knows none), the symbol table to ``DIR/symbols.txt`` and each S7-SCL source
under its own file name — what ``s7graph download DIR/<chart> --blocks DIR/<source>``
takes back — none over an existing file unless ``--force``. A read: no login.
"""

from __future__ import annotations

import functools
import sys
from dataclasses import dataclass
from pathlib import Path, PurePath
from typing import NamedTuple

from s7graph.web.bus.client import BusClient
from s7graph.web.bus.protocol import ChartSource
from s7graph.web.cli.net import NetOptions
from s7graph.web.cli.remote import ask, fb_to_read

__all__ = ["SYMBOLS_FILE", "Upload", "files_of", "upload_command"]

SYMBOLS_FILE = "symbols.txt"
"""The name the symbol table is written under (the examples' own)."""


@dataclass(frozen=True, slots=True)
class _Refused:
    """Why there is no chart to upload (printed as the error line)."""

    reason: str


class Upload(NamedTuple):
    """What an upload writes — (name, text, what it is), the chart first — and, a line
    each, what it does not."""

    files: list[tuple[str, str, str]]
    skipped: list[str]


def _file_name(name: str) -> str:
    """The last part of a file name from the bus ("" when none is usable): a name from the
    bus never leaves the folder."""
    last = PurePath(name.replace("\\", "/")).name
    return last if last not in ("", ".", "..") and last.isprintable() else ""


def files_of(source: ChartSource) -> Upload:
    """The files an upload of ``source`` writes: the chart under the stem of the file name
    the CPU gives and ``.s7g``, or ``<FB>.s7g``; the symbol table, if the chart has one;
    each S7-SCL source under its own name — skipped, with a line saying why, when that
    name is no file name or taken, or when the CPU left the source out of its message."""
    usable = _file_name(source.file)
    files = [(f"{PurePath(usable).stem if usable else source.fb}.s7g", source.text, "chart")]
    if source.symbols.strip():
        files.append((SYMBOLS_FILE, source.symbols, "its symbol table"))
    skipped: list[str] = []
    for name, text in source.blocks.items():
        usable = _file_name(name)
        if usable and usable not in [f[0] for f in files]:
            files.append((usable, text, "an S7-SCL source it runs"))
        else:
            why = "the name of a file written before it" if usable else "no file name here"
            skipped.append(f"S7-SCL source {name!r} not written: {why}")
    for name in source.left_out:
        skipped.append(f"S7-SCL source {name!r} not uploaded: too large for one bus message")
    return Upload(files, skipped)


def _source(client: BusClient, fb: str | None) -> ChartSource | _Refused | None:
    """The source of ``fb`` (default: the CPU's first FB); None when the CPU does not
    answer."""
    status = client.status()
    if status is None:
        return None
    without = "this CPU runs no GRAPH FB (a program of blocks): no chart to upload"
    name, why = fb_to_read(status, fb, without=without)
    if why:
        return _Refused(why)
    source = client.source(name)
    if source is None:
        return _Refused(f"FB {name} gave no source (the CPU did not answer in time)")
    return source


def upload_command(
    net: NetOptions, *, fb: str | None = None, to: Path | None = None, force: bool = False
) -> int:
    """Upload the chart ``fb`` (default: the CPU's first FB) runs: to stdout, or into the
    folder ``to``; 0, or 2 when the CPU does not answer, runs no such FB, or a file
    exists (without ``force``) or cannot be written."""
    source: ChartSource | _Refused | int = ask(net, functools.partial(_source, fb=fb))
    if isinstance(source, int):
        return source
    if isinstance(source, _Refused):
        print(f"s7graph: error: {net.cpu}: {source.reason}", file=sys.stderr)
        return 2
    upload = files_of(source)
    if to is None:
        sys.stdout.write(source.text if source.text.endswith("\n") else source.text + "\n")
        if source.blocks or source.left_out:
            names = ", ".join([*source.blocks, *source.left_out])
            print(
                f"s7graph: the CPU runs S7-SCL sources beside it ({names}): --to DIR writes them",
                file=sys.stderr,
            )
        return 0
    files = [(to / name, text) for name, text, _ in upload.files]
    problem = _write(files, force=force)
    if problem:
        print(f"s7graph: error: {problem}", file=sys.stderr)
        return 2
    for (path, text), (_, _, what) in zip(files, upload.files, strict=True):
        lines = f"({len(text.splitlines())} lines)"
        if what == "chart":
            print(f"s7graph: {source.fb} version {source.version} of {net.cpu} → {path} {lines}")
        else:
            print(f"s7graph: {what} → {path} {lines}")
    for line in upload.skipped:
        print(f"s7graph: warning: {line}", file=sys.stderr)
    return 0


def _write(files: list[tuple[Path, str]], *, force: bool) -> str:
    """Write ``files``; why not ("" when written): one exists (without ``force``), or the
    folder or a file cannot be written."""
    there = [str(path) for path, _ in files if path.exists()]
    if there and not force:
        return f"{', '.join(there)} exists (--force writes over it)"
    try:
        for path, text in files:
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(text, encoding="utf-8")
    except OSError as exc:
        return f"cannot write {exc.filename or files[0][0].parent}: {exc.strerror or exc}"
    return ""
