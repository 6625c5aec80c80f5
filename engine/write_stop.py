"""A STOP because the state file could not be written, and the trace it leaves (docs/runtime.md,
"The state file"; docs/state-file.md, "When the state file cannot be written").

A write error of the state file (a full disk, an I/O error: ``engine/writer.py``) stops the
CPU as every STOP by an error does (``Cpu.stop_by_error``, ``EventId.STOP_STATE_WRITE``),
its reason in words (``stop_on_write_error``): ``the state file could not be written: disk
full (No space left on device), FILE``. The entry is in the diagnostic buffer and the CPU's
status at once, and the runner hands the reason to its ``on_stop`` at once (``s7graph run``:
one line on stderr). The file did not take that entry; at the end of the run
(``Runner.shutdown``) ``leave_trace`` tries once more, with nothing but the entries the file
lacks — a page or two, where the transaction that failed held a scan's state. If the file
takes them (the disk has room again), the next start reads the STOP back from the file and
says why the last run stopped (``engine.diag_events.last_error_stop``); if not, the stderr
line is the only trace, and the run says so.
"""

from __future__ import annotations

import errno
import os

from s7graph.engine.cpu import Cpu
from s7graph.engine.diagnostics import EventId
from s7graph.engine.errors import internal_error
from s7graph.engine.persistence import Batch, DiagRow, StateStore, StateWriteError, diag_row

__all__ = ["disk_full", "leave_trace", "stop_on_write_error", "stop_words"]

_FULL = (
    "SQLITE_FULL",
    "database or disk is full",
    os.strerror(errno.ENOSPC),
    os.strerror(errno.EDQUOT),
)
"""What a write error says when the disk (or the user's quota on it) is full: SQLite's
words, or the operating system's (``ENOSPC``, ``EDQUOT``)."""


def disk_full(problem: str) -> bool:
    """Whether a write error's ``problem`` says the disk is full."""
    return any(mark in problem for mark in _FULL)


def stop_words(error: StateWriteError) -> str:
    """Why the CPU went to STOP, in one line: ``the state file could not be written: disk full
    (…), FILE`` (without ``disk full`` for any other error)."""
    problem = error.problem.removesuffix(f": {error.path}")
    what = f"disk full ({problem})" if disk_full(problem) else problem
    return f"the state file could not be written: {what}, {error.path}"


def stop_on_write_error(cpu: Cpu, error: StateWriteError) -> str:
    """STOP ``cpu`` by ``error`` (an entry ``EventId.STOP_STATE_WRITE`` saying why; then only a
    warm restart); the reason in one line (``stop_words``)."""
    words = stop_words(error)
    cpu.stop_by_error(EventId.STOP_STATE_WRITE, "", words)
    return words


def _unsaved_rows(store: StateStore, cpu: Cpu) -> list[DiagRow]:
    """The rows of the diagnostic entries ``cpu`` holds and the file does not (entry number N
    is row N - 1, as ``StateStore.stage`` numbers them)."""
    entries = list(cpu.diagnostics)
    first = cpu.diagnostics.total - len(entries)  # the row of the oldest entry held
    saved = store.diagnostics_saved()
    return [diag_row(seq, e) for seq, e in enumerate(entries, first) if seq >= saved]


def leave_trace(store: StateStore, cpu: Cpu) -> str:
    """After a write error, at the end of the run (the store's writer closed): write the
    diagnostic entries the file lacks — the STOP among them — and the mode, as one small
    transaction; what came of it, in one line for the user."""
    batch = Batch(meta={"mode": str(cpu.mode), "clean": "0"}, diagnostics=_unsaved_rows(store, cpu))
    try:
        store.write(batch)
    except StateWriteError as exc:
        why = exc.problem
    except OSError as exc:
        why = exc.strerror or internal_error("while writing the STOP's entry", exc)
    except Exception as exc:  # a defect of ours: said in words, never the run's end
        why = internal_error("while writing the STOP's entry", exc)
    else:
        return f"the STOP is recorded in {store.path}: its next start says why the run stopped"
    return (
        f"the STOP could not be recorded in {store.path} either ({why}): its next start "
        "cannot say why the run stopped"
    )
