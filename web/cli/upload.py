"""``s7graph upload --connect EP --cpu NAME [--fb FB] [--to DIR]``: the program back from
the CPU — STEP 7's "Upload from device". For a chart (``fb/<fb>/source``): the ``.s7g``
text the CPU compiled (a download from the page included), the symbol table it was
compiled with and the S7-SCL sources it runs beside the chart. Without ``--to`` the chart's
text goes to stdout; with it, the chart is written to ``DIR/<its file name>``
(``<FB>.s7g`` when the CPU knows none), the symbol table to ``DIR/symbols.txt`` and each
S7-SCL source under its own file name — what ``s7graph download DIR/<chart> --blocks
DIR/<source>`` takes back. A CPU that runs a program of S7-SCL blocks without a chart gives
its sources (``blocks``): one to stdout, or each into ``DIR``. No file is written over
without ``--force``. A read: no login.
"""

from __future__ import annotations

import functools
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path, PurePath
from typing import NamedTuple

from s7graph.web.bus.client import BusClient
from s7graph.web.bus.protocol import BlockSources, ChartSource
from s7graph.web.cli.net import NetOptions
from s7graph.web.cli.remote import ask, fb_to_read

__all__ = ["SYMBOLS_FILE", "Upload", "files_of", "program_files", "upload_command"]

SYMBOLS_FILE = "symbols.txt"
"""The name the symbol table is written under (the examples' own)."""


@dataclass(frozen=True, slots=True)
class _Refused:
    """Why there is no chart to upload (printed as the error line)."""

    reason: str


class Upload(NamedTuple):
    """What an upload writes — (name, text, what it is), the chart first — and what it
    does not: (the name the CPU gives, why)."""

    files: list[tuple[str, str, str]]
    skipped: list[tuple[str, str]]


def _file_name(name: str) -> str:
    """The last part of a file name from the bus ("" when none is usable): a name from the
    bus never leaves the folder."""
    last = PurePath(name.replace("\\", "/")).name
    return last if last not in ("", ".", "..") and last.isprintable() else ""


def _add_sources(
    files: list[tuple[str, str, str]],
    skipped: list[tuple[str, str]],
    sources: Mapping[str, str],
    left_out: Sequence[str],
    what: str,
) -> None:
    """Add each of ``sources`` to ``files`` under its own name, or a line to ``skipped``:
    its name is no file name here or one written before it, or the CPU left it out."""
    for name, text in sources.items():
        usable = _file_name(name)
        if usable and usable not in [f[0] for f in files]:
            files.append((usable, text, what))
        else:
            why = "the name of a file written before it" if usable else "no file name here"
            skipped.append((name, f"not written: {why}"))
    skipped += [(name, "not uploaded: too large for one bus message") for name in left_out]


def files_of(source: ChartSource) -> Upload:
    """The files an upload of ``source`` writes: the chart under the stem of the file name
    the CPU gives and ``.s7g``, or ``<FB>.s7g``; the symbol table, if the chart has one;
    each S7-SCL source under its own name — skipped, with a line saying why, when that
    name is no file name or taken, or when the CPU left the source out of its message."""
    usable = _file_name(source.file)
    files = [(f"{PurePath(usable).stem if usable else source.fb}.s7g", source.text, "chart")]
    if source.symbols.strip():
        files.append((SYMBOLS_FILE, source.symbols, "its symbol table"))
    skipped: list[tuple[str, str]] = []
    _add_sources(files, skipped, source.blocks, source.left_out, "an S7-SCL source it runs")
    return Upload(files, skipped)


def program_files(blocks: BlockSources) -> Upload:
    """The files an upload of a program of S7-SCL blocks writes: each source under its own
    name, skipped as :func:`files_of` skips them."""
    files: list[tuple[str, str, str]] = []
    skipped: list[tuple[str, str]] = []
    _add_sources(files, skipped, blocks.files, blocks.files_left_out, "an S7-SCL source")
    return Upload(files, skipped)


def _source(client: BusClient, fb: str | None) -> ChartSource | BlockSources | _Refused | None:
    """The source of ``fb`` (default: the CPU's first FB), or of the CPU's program of
    S7-SCL blocks when it runs no GRAPH FB; None when the CPU does not answer."""
    status = client.status()
    if status is None:
        return None
    if not status.fbs and fb is None:
        blocks = client.blocks()
        if blocks is None:
            return None
        if not blocks.files and not blocks.files_left_out:
            return _Refused("this CPU runs no GRAPH FB and no S7-SCL source: nothing to upload")
        return blocks
    name, why = fb_to_read(status, fb, without="this CPU runs no GRAPH FB: no chart to upload")
    if why:
        return _Refused(why)
    source = client.source(name)
    if source is None:
        return _Refused(f"FB {name} gave no source (the CPU did not answer in time)")
    return source


def upload_command(
    net: NetOptions, *, fb: str | None = None, to: Path | None = None, force: bool = False
) -> int:
    """Upload the chart ``fb`` (default: the CPU's first FB) runs, or the CPU's program of
    S7-SCL blocks: to stdout, or into the folder ``to``; 0, or 2 when the CPU does not
    answer, runs no such FB, a file exists (without ``force``) or cannot be written, or
    a program of several sources is asked for without ``to``."""
    source: ChartSource | BlockSources | _Refused | int = ask(
        net, functools.partial(_source, fb=fb)
    )
    if isinstance(source, int):
        return source
    if isinstance(source, _Refused):
        print(f"s7graph: error: {net.cpu}: {source.reason}", file=sys.stderr)
        return 2
    upload = files_of(source) if isinstance(source, ChartSource) else program_files(source)
    if to is None:
        return _to_stdout(net, upload)
    if to.exists() and not to.is_dir():
        print(f"s7graph: error: --to {to}: not a folder", file=sys.stderr)
        return 2
    files = [(to / name, text) for name, text, _ in upload.files]
    problem = _write(files, force=force)
    if problem:
        print(f"s7graph: error: {problem}", file=sys.stderr)
        return 2
    if isinstance(source, BlockSources):
        print(f"s7graph: the program of {net.cpu} (no GRAPH FB):")
    for (path, text), (_, _, what) in zip(files, upload.files, strict=True):
        lines = f"({len(text.splitlines())} lines)"
        if what == "chart" and isinstance(source, ChartSource):
            print(f"s7graph: {source.fb} version {source.version} of {net.cpu} → {path} {lines}")
        else:
            print(f"s7graph: {what} → {path} {lines}")
    for name, why in upload.skipped:
        print(f"s7graph: warning: S7-SCL source {name!r} {why}", file=sys.stderr)
    return 0


def _to_stdout(net: NetOptions, upload: Upload) -> int:
    """The chart's text, or a program's only source, to stdout, and a line on stderr
    naming the S7-SCL sources beside a chart; 2 for a program of several sources (or of
    none that came)."""
    sources = [name for name, _, what in upload.files if what.startswith("an S7-SCL")]
    sources += [name for name, _ in upload.skipped]
    chart = bool(upload.files) and upload.files[0][2] == "chart"
    if not upload.files or (not chart and len(sources) != 1):
        why = f"its program has S7-SCL sources {', '.join(sources)}: --to DIR writes them"
        print(f"s7graph: error: {net.cpu}: {why}", file=sys.stderr)
        return 2
    text = upload.files[0][1]
    sys.stdout.write(text if text.endswith("\n") else text + "\n")
    if chart and sources:
        names = ", ".join(sources)
        print(
            f"s7graph: the CPU runs S7-SCL sources beside it ({names}): --to DIR writes them",
            file=sys.stderr,
        )
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
