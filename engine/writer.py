"""The state file's writer: commits off the scan thread, and says when an effect is durable.

One of the three engine modules allowed a thread (with ``clock.py`` and ``runner.py``).
The scan thread hands each scan's :class:`~engine.persistence.Batch` to ``submit`` (None when
the scan changed nothing) and goes on at once; the writer thread commits it as one
transaction. When the disk is slower than the scans, the batches waiting are merged and
committed together, so a slow disk or a foreign lock costs memory for the rows that
changed, never scan time. A locked file is retried; any other error (disk full, I/O error)
is kept as ``error`` — the first one — and nothing more is written.

**Durable**: every batch carries the mark of the last scan it holds (the runner's scan
number). ``committed`` is the mark of the last scan whose state is on disk: every scan up to
it either changed nothing or was committed. ``next_mark()`` is the mark whose commit makes
*everything applied so far* durable — a command applied at the boundary after scan N acts,
and is audited, in scan N + 1. ``when_durable(mark, fn)`` calls ``fn(None)`` once that scan
is committed (at once if it already is) or ``fn(error)`` if writing failed; ``wait(mark,
timeout)`` blocks a caller (never the scan thread) until then.
"""

from __future__ import annotations

import contextlib
import threading
import time
from collections.abc import Callable

from s7graph.engine.persistence import Batch, StateStore, StateWriteError

__all__ = ["DurableCallback", "StoreWriter"]

DurableCallback = Callable[[str | None], None]
"""``fn(error)``: None once the scan is durable, else why it never will be."""

_BUSY_RETRY_S = 0.05


class StoreWriter:
    """Writes one ``StateStore`` in a thread of its own; ``close()`` flushes and ends it."""

    def __init__(self, store: StateStore) -> None:
        self.store = store
        self._cond = threading.Condition()
        store.use_lock(self._cond)
        store.deferred = True
        self._pending: Batch | None = None
        self._writing = False
        self._closed = False
        self._latest = 0
        self._waiters: list[tuple[int, DurableCallback]] = []
        self.committed = 0
        """Mark of the last scan whose state is on disk."""
        self.error: StateWriteError | None = None
        """The first write error; once set, nothing more is written."""
        self.commits = 0
        self.rows = 0
        self.busy_retries = 0
        self.max_commit_ns = 0
        self._thread = threading.Thread(target=self._loop, name="s7graph-writer", daemon=True)
        self._thread.start()

    # ---- the scan thread's side -------------------------------------------------------------

    def submit(self, batch: Batch | None, mark: int) -> None:
        """Hand over scan ``mark``'s changes (None: it changed nothing); never waits for
        the disk."""
        with self._cond:
            self._latest = max(self._latest, mark)
            if batch is not None:
                batch.upto = max(batch.upto, mark)
                if self._pending is None:
                    self._pending = batch
                else:
                    self._pending.merge(batch)
                self._cond.notify_all()
            elif self._pending is None and not self._writing and self.error is None:
                self.committed = self._latest  # nothing in flight: durable as it is
                if self._waiters:
                    self._cond.notify_all()

    # ---- durability ------------------------------------------------------------------------

    def next_mark(self) -> int:
        """The mark whose commit makes durable everything applied up to now."""
        with self._cond:
            return self._latest + 1

    def durable(self, mark: int) -> bool:
        return self.committed >= mark and self.error is None

    def when_durable(self, mark: int, fn: DurableCallback) -> None:
        """Call ``fn(None)`` once scan ``mark`` is committed (now, in this thread, if it is
        already), ``fn(error)`` if it never will be; later calls run in the writer thread."""
        with self._cond:
            error = self.error
            ready = error is not None or self.committed >= mark
            if not ready:
                self._waiters.append((mark, fn))
                self._cond.notify_all()
                return
        fn(str(error) if error is not None else None)

    def wait(self, mark: int, timeout: float | None = None) -> bool:
        """Block (not in the scan thread) until scan ``mark`` is durable; False on timeout or
        a write error."""
        with self._cond:
            self._cond.wait_for(lambda: self.committed >= mark or self.error is not None, timeout)
            return self.committed >= mark and self.error is None

    # ---- the writer thread -----------------------------------------------------------------

    def _loop(self) -> None:
        while True:
            with self._cond:
                while self._pending is None and not self._closed and not self._due():
                    self._cond.wait()
                if self.error is not None:
                    batch = None
                    self._pending = None
                else:
                    batch, self._pending = self._pending, None
                self._writing = batch is not None
                closing = self._closed
            error = self._commit(batch) if batch is not None else None
            with self._cond:
                self._writing = False
                if error is not None and error.busy and batch is not None and not closing:
                    if self._pending is not None:
                        batch.merge(self._pending)
                    self._pending = batch  # a foreign lock: keep the rows, try again
                    self.busy_retries += 1
                elif error is not None:
                    self.error = self.error or error
                elif batch is not None:
                    self.committed = batch.upto if self._pending is not None else self._latest
                elif self._pending is None and self.error is None:
                    self.committed = self._latest
                ready = self._take_ready()
                self._cond.notify_all()
                done = closing and self._pending is None
                busy = error is not None and error.busy and not closing
            self._call(ready)
            if done:
                return
            if busy:
                time.sleep(_BUSY_RETRY_S)

    def _commit(self, batch: Batch) -> StateWriteError | None:
        started = time.perf_counter_ns()
        try:
            self.store.write(batch)
        except StateWriteError as exc:
            return exc
        except Exception as exc:  # anything else from the disk is still a write failure
            return StateWriteError(self.store.path, f"{type(exc).__name__}: {exc}")
        self.max_commit_ns = max(self.max_commit_ns, time.perf_counter_ns() - started)
        self.commits += 1
        self.rows += batch.rows
        return None

    def _due(self) -> bool:
        return any(mark <= self.committed for mark, _ in self._waiters) or (
            bool(self._waiters) and self.error is not None
        )

    def _take_ready(self) -> list[tuple[DurableCallback, str | None]]:
        error = str(self.error) if self.error is not None else None
        ready = [(fn, error) for mark, fn in self._waiters if error or mark <= self.committed]
        if ready:
            self._waiters = [
                (m, f) for m, f in self._waiters if not (error or m <= self.committed)
            ]
        return ready

    @staticmethod
    def _call(ready: list[tuple[DurableCallback, str | None]]) -> None:
        for fn, error in ready:
            with contextlib.suppress(Exception):  # a callback's failure is its own
                fn(error)

    # ---- the end ---------------------------------------------------------------------------

    def flush(self, timeout: float | None = None) -> bool:
        """Wait until everything submitted is committed (or failed); True if committed."""
        with self._cond:
            latest = self._latest
        return self.wait(latest, timeout)

    def close(self, timeout: float | None = 10.0) -> None:
        """Commit what is pending and end the thread; waiters still waiting get an error."""
        with self._cond:
            self._closed = True
            self._cond.notify_all()
        self._thread.join(timeout)
        with self._cond:
            left, self._waiters = self._waiters, []
        self._call([(fn, "the state file was closed first") for _, fn in left])
        self.store.deferred = False
