"""The chart files of a running CPU's project directory: which ones an editor may open, and
writing one so that nothing acknowledged is lost.

The project directory is the folder of the chart the CPU was started with. A file is named
by a bare name inside it (``drill.s7g``, ``line1.xml``): no folder, no leading dot, no
control character — anything else is refused with a :class:`ProjectError` naming it.
:func:`write_chart` keeps the file it replaces as a numbered backup (``drill.s7g.~1~``,
``~2~`` …, as GNU ``cp --backup=numbered`` names them) and writes the new text through a
temporary file, flushed to the disk and renamed over the old one, so the file on disk is
always either the old chart or the new one, and the new one is durable when it returns.
"""

from __future__ import annotations

import contextlib
import os
import re
import shutil
import tempfile
from pathlib import Path

from s7graph.engine.errors import S7Error
from s7graph.engine.renew import sync
from s7graph.sequencer.exchange import importable_files

__all__ = [
    "CHART_CHOICE",
    "ProjectError",
    "backup_name",
    "chart_file",
    "project_file",
    "project_files",
    "restore_backup",
    "write_chart",
]

_NAME = re.compile(r"^[^/\\\x00-\x1f\x7f.][^/\\\x00-\x1f\x7f]{0,127}$")
CHART_CHOICE = "{file} » {chart}"
"""A line of an open refused because the file holds several charts: one chart to choose
(the editor offers each in its *Open file* list)."""
MAX_READ = 10_000_000  # bytes of a file Open reads (the import refuses beyond its limits)


class ProjectError(S7Error):
    """A file name outside the project directory, or a file that cannot be read or written."""


def project_file(directory: Path, name: str) -> Path:
    """The file ``name`` of ``directory``; refused unless ``name`` is a bare file name."""
    if not isinstance(name, str) or not _NAME.match(name) or name in (".", ".."):
        raise ProjectError(
            f"{str(name)[:60]!r} is not a file name of the project directory "
            "(a bare name: no folder, no leading dot)"
        )
    path = Path(directory) / name
    if path.resolve().parent != Path(directory).resolve():
        raise ProjectError(f"{name!r} leads out of the project directory")
    return path


def chart_file(file: str, pou: str | None, suffix: str) -> str:
    """The name of what an opened ``file`` becomes beside it (``suffix``: ``.s7g`` as the
    editor saves it, ``.scl`` for its SCL FCs): ``line1.s7g``, or ``line1_Crane.Hoist.s7g``
    for the chart ``pou`` of a file that holds several (its odd characters ``_``)."""
    stem = file.rsplit(".", 1)[0] if "." in file[1:] else file
    if pou:
        stem += "_" + re.sub(r"[^A-Za-z0-9_.-]", "_", pou)
    return f"{stem}{suffix}"


def project_files(directory: Path) -> list[tuple[str, str]]:
    """The charts and importable files of ``directory`` as (name, format), by name."""
    try:
        return [(p.name, fmt) for p, fmt in importable_files(Path(directory))]
    except OSError as exc:
        raise ProjectError(
            f"{directory}: cannot list the project directory: {exc.strerror}"
        ) from None


def backup_name(path: Path) -> Path:
    """The next free numbered backup of ``path``: ``name.~N~``, N one more than the highest."""
    taken = [
        int(m[1])
        for p in path.parent.glob(f"{glob_escape(path.name)}.~*~")
        if (m := re.fullmatch(re.escape(path.name) + r"\.~(\d+)~", p.name))
    ]
    return path.with_name(f"{path.name}.~{max(taken, default=0) + 1}~")


def glob_escape(name: str) -> str:
    return re.sub(r"([*?\[])", r"[\1]", name)


def _fsync_dir(directory: Path) -> None:
    with contextlib.suppress(OSError):  # not every file system lets a folder be opened
        sync(directory, folder=True)


def write_chart(path: Path, text: str) -> Path | None:
    """Write ``text`` to ``path`` durably, keeping the file it replaces as a numbered
    backup; returns the backup (None when there was no file)."""
    path = Path(path)
    backup = None
    try:
        if path.exists():
            backup = backup_name(path)
            shutil.copy2(path, backup)
            with open(backup, "rb+") as f:
                os.fsync(f.fileno())
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
        try:
            with os.fdopen(fd, "w", encoding="utf-8", newline="\n") as f:
                f.write(text)
                f.flush()
                os.fsync(f.fileno())
            os.replace(tmp, path)
        except BaseException:
            with contextlib.suppress(OSError):
                os.unlink(tmp)
            raise
        _fsync_dir(path.parent)
    except OSError as exc:
        raise ProjectError(f"{path}: cannot write the chart: {exc.strerror or exc}") from None
    return backup


def restore_backup(path: Path, backup: Path | None) -> None:
    """Put ``backup`` back as ``path`` (a write the CPU then did not take); without a
    backup there was no file before, so ``path`` goes."""
    try:
        if backup is None:
            Path(path).unlink(missing_ok=True)
        else:
            os.replace(backup, path)
        _fsync_dir(Path(path).parent)
    except OSError as exc:
        raise ProjectError(f"{path}: cannot restore {backup}: {exc.strerror or exc}") from None
