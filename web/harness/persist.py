"""What a chart or program run keeps in its state file, and how the file is opened.

``open_state`` opens the state file of a run and restores the CPU from it: a file it cannot
trust is refused (``StateFileError``: the CLI prints one line naming the file and the
problem and exits 2), never taken for a fresh start; ``fresh`` keeps an existing file as
``FILE.old-N`` and starts anew. ``persist_messages`` adds the CPU's message list to it.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from s7graph.engine.cpu import Cpu
from s7graph.engine.diagnostics import EventId
from s7graph.engine.persistence import LoadReport, StateFileError, StateStore
from s7graph.sfb.alarms import message_list

__all__ = ["OpenedState", "keep_aside", "open_state", "persist_messages", "refusal"]


def persist_messages(store: StateStore, cpu: Cpu) -> None:
    """Save the CPU's message list (``sfb.alarms``) with the state; call before ``load``.
    Its change log is not part of it: every change is in the store's alarm log already."""
    messages = message_list(cpu)
    cached: list[Any] = [-1, None]  # (changes, snapshot): the same object while unchanged

    def snapshot() -> object:
        if cached[0] != messages.changes:
            cached[:] = [messages.changes, messages.snapshot(with_log=False)]
        return cached[1]

    store.add_part("messages", snapshot, messages.restore)


class OpenedState:
    """An open state file: the store, what ``load`` found (None: nothing yet), and where
    ``--fresh`` put the file it found."""

    def __init__(self, store: StateStore, report: LoadReport | None, kept: Path | None) -> None:
        self.store = store
        self.report = report
        self.kept = kept

    def describe(self, restart: str) -> str:
        """How the run starts, for its first line on stderr."""
        if self.report is None:
            aside = f"; the old file is kept as {self.kept}" if self.kept else ""
            return f"fresh start, state in {self.store.path}{aside}"
        how = "" if self.report.clean else " after an unclean stop"
        return f"{restart} restart from {self.store.path}{how}"


def keep_aside(path: Path) -> Path | None:
    """Rename ``path`` (and its ``-wal``/``-shm`` companions) to ``path.old-N``, the first
    free N; None when there is no file."""
    if not path.exists():
        return None
    n = 1
    while Path(f"{path}.old-{n}").exists():
        n += 1
    target = Path(f"{path}.old-{n}")
    path.rename(target)
    for suffix in ("-wal", "-shm"):
        companion = Path(f"{path}{suffix}")
        if companion.exists():
            companion.rename(Path(f"{target}{suffix}"))
    return target


def open_state(path: Path, cpu: Cpu, *, fresh: bool = False, hot: bool = False) -> OpenedState:
    """Open ``path`` and restore ``cpu`` (STOP) from it, with its message list; the notes
    of a carried-over state go to the diagnostic buffer. ``hot``: the run restarts hot, so
    the store keeps the hot restart image too. ``StateFileError`` when the file cannot be
    trusted (the store is closed again)."""
    kept = keep_aside(path) if fresh else None
    store = StateStore(path, hot=hot)
    try:
        persist_messages(store, cpu)
        report = store.load(cpu)
    except BaseException:
        store.close()
        raise
    if report is not None:
        now = cpu.clock.now_ns()
        for note in report.notes:
            cpu.diagnostics.record(now, EventId.STATE_CARRIED_OVER, "", note)
    return OpenedState(store, report, kept)


def refusal(exc: StateFileError) -> str:
    """The one line of a refused state file, with the way out."""
    return (
        f"s7graph: error: {exc.path}: {exc.problem}; start anew with --fresh "
        f"(keeps this file as {exc.path}.old-N)"
    )
