"""``s7graph upload --connect EP --cpu NAME [--fb FB] [--to DIR]``: the chart an FB runs,
back from the CPU — STEP 7's "Upload from device": the ``.s7g`` text the CPU compiled (a
download from the page included) and the symbol table it was compiled with
(``fb/<fb>/source``). Without ``--to`` the chart's text goes to stdout; with it, the chart
is written to ``DIR/<its file name>`` (``<FB>.s7g`` when the CPU knows none) and the symbol
table to ``DIR/symbols.txt``, neither over an existing file unless ``--force``. A read: no
login. The CPU's S7-SCL blocks are not uploaded: it keeps each block's own lines, not the
source files they came from (their types, the text between blocks); the page shows them.
"""

from __future__ import annotations

import functools
import sys
from dataclasses import dataclass
from pathlib import Path, PurePath

from s7graph.web.bus.client import BusClient
from s7graph.web.bus.protocol import ChartSource
from s7graph.web.cli.net import NetOptions
from s7graph.web.cli.remote import ask, fb_to_read

__all__ = ["SYMBOLS_FILE", "files_of", "upload_command"]

SYMBOLS_FILE = "symbols.txt"
"""The name the symbol table is written under (the examples' own)."""


@dataclass(frozen=True, slots=True)
class _Refused:
    """Why there is no chart to upload (printed as the error line)."""

    reason: str


def files_of(source: ChartSource) -> list[tuple[str, str]]:
    """The files an upload of ``source`` writes, as (name, text): the chart under the stem
    of the file name the CPU gives and ``.s7g`` — only the name's last part, so a name from
    the bus never leaves the folder — or ``<FB>.s7g``; then the symbol table, if the chart
    has one."""
    stem = PurePath(source.file.replace("\\", "/")).stem
    usable = stem not in ("", ".", "..") and stem.isprintable()
    name = f"{stem if usable else source.fb}.s7g"
    files = [(name, source.text)]
    if source.symbols.strip():
        files.append((SYMBOLS_FILE, source.symbols))
    return files


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
    if to is None:
        sys.stdout.write(source.text if source.text.endswith("\n") else source.text + "\n")
        return 0
    files = [(to / name, text) for name, text in files_of(source)]
    problem = _write(files, force=force)
    if problem:
        print(f"s7graph: error: {problem}", file=sys.stderr)
        return 2
    lines = len(source.text.splitlines())
    wrote = f"{source.fb} version {source.version} of {net.cpu}"
    print(f"s7graph: {wrote} → {files[0][0]} ({lines} lines)")
    if len(files) > 1:
        print(f"s7graph: its symbol table → {files[1][0]}")
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
