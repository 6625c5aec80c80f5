"""What a chart or program run keeps in its state file, and how the file is opened.

``open_state`` opens the state file of a run and restores the CPU from it: a file it cannot
trust is refused (``StateFileError``: the CLI prints one line naming the file and the
problem and exits 2), never taken for a fresh start; ``fresh`` keeps an existing file as
``FILE.old-N`` and starts anew. A hot restart the saved state does not allow is refused the
same way (``HotRestartRefused``), never turned into a warm one; so is a file that is
another program's (``program``: ``engine/state_identity.py``). ``default_state`` chooses a
run's file without ``--state``: one of its own beside a chart or program of the same name,
never another file beside it, but a file a renamed source left there is named.
``persist_messages`` adds the CPU's message list to it.
"""

from __future__ import annotations

import shlex
from pathlib import Path
from typing import Any

from s7graph.engine.cpu import Cpu
from s7graph.engine.diagnostics import EventId
from s7graph.engine.persistence import (
    LoadReport,
    StateFileError,
    StateStore,
    foreign_state,
    not_in_use,
    state_beside,
)
from s7graph.engine.renew import set_aside
from s7graph.engine.state_identity import Program
from s7graph.sfb.alarms import message_list

__all__ = [
    "HotRestartRefused",
    "OpenedState",
    "default_state",
    "hot_refusal",
    "keep_aside",
    "open_state",
    "persist_messages",
    "refusal",
]

HOT_WAY_OUT = (
    "restart warm with --restart warm (each sequencer starts in its initial steps; where it "
    "was goes to the diagnostic buffer)"
)
_BLOCKERS = {
    "program download": "the program changed since the state was saved (a download)",
    "no hot restart image saved": "the last run kept no hot-restart image (a run keeps one "
    "when started with --restart hot, or when it stops cleanly)",
    "memory reset": "a memory reset since",
    "stack overflow": "the last run stopped on a block stack overflow",
    "aborted warm restart": "the last warm restart was aborted",
}


class HotRestartRefused(StateFileError):
    """``--restart hot`` that the saved state does not allow: why, and to restart warm."""

    def __init__(self, path: Path, why: str) -> None:
        super().__init__(path, f"cannot restart hot: {why}", way_out=HOT_WAY_OUT)


def hot_refusal(cpu: Cpu) -> str | None:
    """Why ``cpu``, restored from a state file, cannot restart hot (None: it can): its hot
    restart blockers in words, or its parameters."""
    if not cpu.hot_restart_enabled:
        return "the CPU is not parametrised for hot restarts (hot_restart_enabled off)"
    if not cpu.hot_blockers:
        return None
    return "; ".join(_BLOCKERS.get(b, b) for b in sorted(cpu.hot_blockers))


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
        private = (
            "; others could read it: made its owner's alone (mode 600)"
            if self.store.made_private
            else ""
        )
        if self.report is None:
            aside = f"; the old file is kept as {self.kept}" if self.kept else ""
            return f"fresh start, state in {self.store.path}{aside}{private}"
        how = "" if self.report.clean else " after an unclean stop"
        return f"{restart} restart from {self.store.path}{how}{private}"


def keep_aside(path: Path) -> Path | None:
    """Rename ``path`` (and its ``-wal``/``-shm`` companions: also a ``-wal`` whose file is
    gone) to ``path.old-N``, the first free N; the first file so kept (``path.old-N``, or
    ``path.old-N-wal`` when only a write-ahead log was there), None when there is none."""
    if not path.exists() and not Path(f"{path}-wal").exists():
        return None
    return set_aside(path, "old")[0]


def open_state(
    path: Path,
    cpu: Cpu,
    *,
    fresh: bool = False,
    hot: bool = False,
    restart: str | None = None,
    program: Program | None = None,
) -> OpenedState:
    """Open ``path`` and restore ``cpu`` (STOP) from it, with its message list; the notes
    of a carried-over state go to the diagnostic buffer. ``hot``: the run restarts hot, so
    the store keeps the hot restart image too. ``restart``: the startup the run makes (implies
    ``hot`` when hot); a saved state that allows no hot restart is refused
    (``HotRestartRefused``). ``StateFileError`` when the file cannot be trusted (the store is
    closed again, the file as it was: it is opened for writing only once it is taken).
    ``program``: the program the run is of; a file that is another's is refused, one taken
    records it (``engine/state_identity.py``)."""
    if fresh:
        not_in_use(path)  # a running CPU's file is never moved aside under it
    kept = keep_aside(path) if fresh else None
    store = StateStore(path, hot=hot or restart == "hot", program=program)
    try:
        persist_messages(store, cpu)
        report = store.load(cpu)
        why = hot_refusal(cpu) if restart == "hot" and report is not None else None
        if why is not None:
            raise HotRestartRefused(store.path, why)
        store.open_writing()  # only now: a file refused is left as it was, byte for byte
    except BaseException:
        store.close()
        raise
    if report is not None:
        now = cpu.clock.now_ns()
        for note in report.notes:
            cpu.diagnostics.record(now, EventId.STATE_CARRIED_OVER, "", note)
    return OpenedState(store, report, kept)


def default_state(source: Path, cpu: Cpu) -> tuple[Path, str | None]:
    """The state file of a run of ``source`` without ``--state``, and a note when the file
    of the other name is another program's, or when the run starts fresh though a state
    file beside ``source`` is this program's (docs/state-file.md, "Whose state it is"); the
    note goes to ``cpu``'s diagnostic buffer too.

    A chart's is ``NAME.state.sqlite``, an S7-SCL or Python program's
    ``NAME.scl.state.sqlite`` / ``NAME.py.state.sqlite`` (a chart and a program of one name
    side by side each keep their own); the other name (a chart's ``NAME.s7g.state.sqlite``,
    a program's ``NAME.state.sqlite``, as before) is taken when it is there and this
    program's, or older and not known to be another's, and the own name is not. A file
    another program's is passed over, said so, for a free name: never taken, never moved.
    Nor is any other file beside ``source`` taken, but one the program would carry over
    given it with ``--state`` (a renamed source's, ``state_beside``) is named in the note."""
    program = Program.of(source)
    plain = source.with_suffix(".state.sqlite")
    suffixed = source.with_name(f"{source.name}.state.sqlite")
    names = [plain, suffixed] if program.kind == "chart" else [suffixed, plain]
    others: list[str] = []
    for path in names:
        if _there(path):
            why = foreign_state(path, program, cpu)
            if why is None:
                return path, None
            others.append(f"{path.name} is passed over ({why})")
    for path in names:
        if not _there(path):
            if others:
                others.append(f"the state of {program} is kept in {path.name}")
            found = _beside(source, program, cpu, names)
            if found:
                others.append(found)
            note = "; ".join(others) if others else None
            if note is not None:
                now = cpu.clock.now_ns()
                cpu.diagnostics.record(now, EventId.STATE_NOT_TAKEN, "", note)
            return path, note
    return names[0], None  # both another's: refused, saying whose


def _beside(source: Path, program: Program, cpu: Cpu, names: list[Path]) -> str | None:
    """The files beside ``source`` (``*.state.sqlite``, but ``names``) that hold this
    program's state (``state_beside``: each read-only, never locked or changed), in words:
    which, and how to carry one over; None when there is none. A program without instance
    DBs has none: nothing in a file tells it apart."""
    if not cpu.instance_dbs:
        return None
    found = [
        (path, whose)
        for path in sorted(source.parent.glob("*.state.sqlite"))
        if path not in names and (whose := state_beside(path, program, cpu)) is not None
    ]
    if not found:
        return None
    run = f"run {program.source} with --state"
    if len(found) == 1:
        path, whose = found[0]
        return (
            f"{path.name} beside it holds {whose}, whose instance DBs are {program}'s (a "
            f"renamed source?): not taken without --state; to carry it over, {run} "
            f"{shlex.quote(str(path))}"
        )
    files = ", ".join(f"{path.name} ({whose})" for path, whose in found)
    return (
        f"{files} beside it hold states whose instance DBs are {program}'s (a renamed "
        f"source?): none taken without --state; to carry one over, {run} FILE"
    )


def _there(path: Path) -> bool:
    """Whether a state file is at ``path``, or what is left of one (its ``-wal``, a file
    being built anew)."""
    return any(Path(f"{path}{tail}").exists() for tail in ("", "-wal", ".renew"))


def refusal(exc: StateFileError) -> str:
    """The one line of a refused state file, with the way out (by default ``--fresh``)."""
    way_out = exc.way_out or f"start anew with --fresh (keeps this file as {exc.path}.old-N)"
    return f"s7graph: error: {exc.path}: {exc.problem}; {way_out}"
