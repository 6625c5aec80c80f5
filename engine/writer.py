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

**Encoded in the idle part of the cycle.** A batch staged with ``defer``
(``StateStore.stage``) still holds its instance DBs unencoded — for large charts most of
the staging's work. ``submit(batch, mark, until=t)`` leaves them to a second thread, the
*encoder* (``encoder_id``; never held up by a commit or a checkpoint of the file), which
encodes them one at a time while the scan thread idles, up to ``t`` (``time.monotonic``,
the runner's next scan less a margin), and hands them on to the commit. ``finish()``,
called by the scan thread before its next scan, makes sure no scan changes a state that is
still being read and no row holds a later scan's state: a staging the encoder has not
finished is *carried* — what it has encoded stays, under the next scan's staging, which
stages every instance DB again, and nothing of it is committed (or counted durable) on
its own — so the scan starts on time; the next one in a row is not carried but finished
by the scan thread (waiting for the one in hand), so the file is never more than two
scans behind. The interpreter's lock is still shared; what moves is when the work
is done: in the scan thread's sleep, not between its scan and its deadline. The runner
puts the encoder on the processor it keeps for the scan (``engine/cores.py``), idle then.
"""

from __future__ import annotations

import contextlib
import threading
import time
from collections.abc import Callable

from s7graph.engine.errors import internal_error
from s7graph.engine.persistence import Batch, StateStore, StateWriteError

__all__ = ["DurableCallback", "StoreWriter"]

DurableCallback = Callable[[str | None], None]
"""``fn(error)``: None once the scan is durable, else why it never will be."""

_BUSY_RETRY_S = 0.05
_MARGIN_FACTOR = 2
"""The encoder starts on an instance DB only when twice the longest recent one
(``encode_ns``) fits before ``until``: the scan thread should not have to wait for it."""
_FADE = 16
"""``encode_ns`` loses a sixteenth at every staging: one slow encoding fades."""


class StoreWriter:
    """Writes one ``StateStore`` in a thread of its own (and encodes deferred stagings in
    another); ``close()`` flushes and ends them."""

    def __init__(self, store: StateStore) -> None:
        self.store = store
        lock = threading.Lock()
        self._cond = threading.Condition(lock)
        self._wake_encoder = threading.Condition(lock)
        """Notified when there is something to encode, or the end (not every commit)."""
        store.use_lock(self._cond)
        store.deferred = True
        self._pending: Batch | None = None
        self._staging: Batch | None = None
        """The batch whose instance DBs are still being encoded (``submit`` with
        ``until``)."""
        self._until = 0.0
        self._encoding = threading.Lock()  # held while one instance DB is encoded
        self.encode_ns = 0
        """The longest recent encoding of one instance DB, in the encoder's processor time
        (a wait for the interpreter's lock or a processor is not the encoding's): each
        one's, or the last value less ``1/_FADE`` at every staging."""
        self.encoded_here = 0
        """Instance DBs encoded by the encoder thread (the rest: by the scan thread)."""
        self.encoded_late = 0
        """Instance DBs the scan thread had to encode itself before its scan."""
        self._carried: Batch | None = None
        """A staging not encoded by its next scan, waiting for that scan's (``finish``)."""
        self._carrying = False  # the last staging was carried over
        self.carried = 0
        """Stagings carried over to the next scan's."""
        self._writing = False
        self._closed = False
        self._latest = 0
        self._waiters: list[tuple[int, DurableCallback]] = []
        self.committed = 0
        """Mark of the last scan whose state is on disk."""
        self.error: StateWriteError | None = None
        """The first write error; once set, nothing more is written."""
        self._renewing: str | None = None
        """Why the file must be built anew (deleted, replaced, damaged: ``engine/renew.py``);
        the rows wait for a whole staging (``wants_full``) to build it with."""
        self.wants_full = False
        """The next staging must be whole (``stage(full=True)``): the file is built anew."""
        self._renewals: list[str] = []
        self.left: Batch | None = None
        """The rows it could not write when it closed while the file was to be built anew:
        the store's last ``save`` builds it with them (``Runner.shutdown``)."""
        self.commits = 0
        self.rows = 0
        self.busy_retries = 0
        self.max_commit_ns = 0
        self._thread = threading.Thread(target=self._loop, name="s7graph-writer", daemon=True)
        self._thread.start()
        self._encoder = threading.Thread(
            target=self._encode_loop, name="s7graph-encoder", daemon=True
        )
        self._encoder.start()

    @property
    def encoder_id(self) -> int | None:
        """The encoder thread's native id (for pinning it: ``engine/cores.py``)."""
        return self._encoder.native_id

    # ---- the scan thread's side -------------------------------------------------------------

    def submit(self, batch: Batch | None, mark: int, *, until: float | None = None) -> None:
        """Hand over scan ``mark``'s changes (None: it changed nothing); never waits for
        the disk. A batch with instance DBs still to encode (``stage(defer=True)``) is
        encoded by the encoder thread up to ``until`` (``time.monotonic``; None: not
        there), the rest by ``finish()``, which must come before the next ``submit``."""
        if batch is not None and batch.full:
            with self._cond:
                carried, self._carried = self._carried, None
                if carried is not None:  # its rows, under the whole staging
                    carried.unencoded = []
                    carried.merge(batch)
                    batch = carried
                self.wants_full = False
        if batch is not None and batch.unencoded:
            with self._cond:
                if self._staging is not None:
                    raise RuntimeError("submit before finish: a batch is still being encoded")
                self._latest = max(self._latest, mark)
                batch.upto = max(batch.upto, mark)
                if self._carried is not None:  # what it encoded, under this staging
                    self._carried.unencoded = []  # this one stages every instance DB
                    self._carried.merge(batch)
                    batch, self._carried = self._carried, None
                self._staging = batch
                self._until = -1.0 if until is None else until
                self.encode_ns -= self.encode_ns // _FADE
                self._wake_encoder.notify()
            return
        with self._cond:
            self._latest = max(self._latest, mark)
            if batch is not None:
                batch.upto = max(batch.upto, mark)
                if self._pending is None:
                    self._pending = batch
                else:
                    self._pending.merge(batch)
                self._cond.notify_all()
            elif self._idle():
                self.committed = self._latest  # nothing in flight: durable as it is
                if self._waiters:
                    self._cond.notify_all()

    def finish(self, *, carry: bool = True) -> int:
        """Call before the next scan: the batch being encoded is done, or carried over to
        the next scan's staging (``carry``, unless the last one was), or else encoded to the
        end in the calling (scan) thread, after the instance DB in hand; how many the
        calling thread encoded. ``carry=False``: no scan follows, so nothing is carried
        and what was carried is encoded now."""
        if not carry:
            with self._cond:
                if self._staging is None and self._carried is not None:
                    self._staging, self._carried = self._carried, None  # no scan since
        staging = self._staging
        if staging is None:
            self._carrying = False
            return 0
        with self._encoding:
            if self._staging is not staging:
                self._carrying = False
                return 0  # the encoder was done meanwhile
            if self.error is not None:
                staging.unencoded.clear()  # nothing more is written
            elif carry and staging.unencoded and not self._carrying:
                with self._cond:
                    self._staging, self._carried = None, staging
                    self._carrying = True
                    self.carried += 1
                return 0
            self._carrying = False
            left = len(staging.unencoded)
            while self._encode_next(staging):
                pass
            self.encoded_late += left
            self._staged(staging)
        return left

    def _staged(self, batch: Batch) -> None:
        """``batch`` is encoded (``_encoding`` held): on to the commit."""
        with self._cond:
            self._staging = None
            if not batch:
                if self._idle():
                    self.committed = self._latest
            elif self._pending is None:
                self._pending = batch
            else:
                self._pending.merge(batch)
            self._cond.notify_all()

    def _in_flight(self) -> bool:
        """A batch waiting for its commit, being encoded or carried (``_cond`` held)."""
        return not (self._pending is None and self._staging is None and self._carried is None)

    def _idle(self) -> bool:
        """Nothing in flight (``_cond`` held): what was submitted is durable as it is."""
        return not self._in_flight() and not self._writing and self.error is None

    def _encode_one(self, staging: Batch) -> None:
        """Encode the next instance DB of ``staging`` in the encoder thread, if it is still
        the one being encoded."""
        with self._encoding:
            if self._staging is not staging or not staging.unencoded:
                return
            started = time.thread_time_ns()
            left = self._encode_next(staging)
            self.encode_ns = max(self.encode_ns, time.thread_time_ns() - started)
            self.encoded_here += 1
            if not left:
                self._staged(staging)

    def _encode_next(self, staging: Batch) -> bool:
        """``StateStore.encode_next``; a failure is a write error (nothing more is written),
        never an exception in the scan thread or the end of this one."""
        try:
            return self.store.encode_next(staging)
        except Exception as exc:
            staging.unencoded.clear()
            problem = f"cannot encode the state: {internal_error('while encoding it', exc)}"
            with self._cond:
                self.error = self.error or StateWriteError(self.store.path, problem)
            return False

    def _may_encode(self) -> bool:
        """Whether the encoder may start on the next instance DB now (``_cond`` held): in
        time, or the writer closing (no scan follows)."""
        margin = _MARGIN_FACTOR * self.encode_ns / 1e9
        return (
            self._staging is not None
            and self.error is None
            and (self._closed or time.monotonic() + margin < self._until)
        )

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

    # ---- the encoder and writer threads -----------------------------------------------------

    def _encode_loop(self) -> None:
        while True:
            with self._cond:
                while not self._may_encode():
                    if self._ending():
                        return
                    if self._staging is not None and self._until > time.monotonic():
                        self._wake_encoder.wait(max(0.0, self._until - time.monotonic()))
                    else:
                        self._wake_encoder.wait()
                staging = self._staging
            if staging is not None:
                self._encode_one(staging)

    def _ending(self) -> bool:
        """Closed, with nothing left to encode (``_cond`` held)."""
        return self._closed and (self._staging is None or self.error is not None)

    def _writable(self) -> bool:
        """A batch waiting that can be written now (``_cond`` held): while the file is to be
        built anew, only one holding a whole staging."""
        return self._pending is not None and (self._renewing is None or self._pending.full)

    def take_renewals(self) -> list[str]:
        """What happened each time the file was built anew since the last call, in words
        (called every scan: nothing to take is seen without the lock)."""
        if not self._renewals:
            return []
        with self._cond:
            taken, self._renewals = self._renewals, []
        return taken

    def _loop(self) -> None:
        while True:
            with self._cond:
                while not self._writable() and not self._ending() and not self._due():
                    self._cond.wait()
                if self.error is not None:
                    batch = None
                    self._pending = None
                elif self._writable() or self._ending():
                    batch, self._pending = self._pending, None
                else:
                    batch = None
                self._writing = batch is not None
                closing = self._closed
                renewing = self._renewing
            error = self._write(batch, renewing) if batch is not None else None
            with self._cond:
                self._writing = False
                if error is not None and error.busy and batch is not None and not closing:
                    if self._pending is not None:
                        batch.merge(self._pending)
                    self._pending = batch  # a foreign lock: keep the rows, try again
                    self.busy_retries += 1
                elif error is not None and error.renew and batch is not None and not closing:
                    if error.committed:  # its rows are in the old file: copied from there
                        batch = Batch(upto=batch.upto)
                    if self._pending is not None:
                        batch.merge(self._pending)
                    self._pending = batch  # kept for the new file, with a whole staging
                    self._renewing = error.problem
                    self.wants_full = True
                elif error is not None:
                    if error.renew and batch is not None:  # for the store's last save
                        self.left = Batch(upto=batch.upto) if error.committed else batch
                    self.error = self.error or error
                elif batch is not None:
                    if renewing is not None and batch.full:
                        self._renewing = None
                    later = self._in_flight()
                    self.committed = max(self.committed, batch.upto if later else self._latest)
                elif self._idle():
                    self.committed = self._latest
                ready = self._take_ready()
                self._cond.notify_all()
                done = self._ending() and self._pending is None
                busy = error is not None and error.busy and not closing
            self._call(ready)
            if done:
                return
            if busy:
                time.sleep(_BUSY_RETRY_S)

    def _write(self, batch: Batch, renewing: str | None) -> StateWriteError | None:
        """Commit ``batch``; or, while the file is to be built anew and ``batch`` holds a
        whole staging, build it (``StateStore.renew``)."""
        if renewing is None:
            return self._commit(batch)
        if not batch.full:  # closing before a whole staging came: it is the store's now
            return StateWriteError(self.store.path, renewing, renew=True)
        try:
            note = self.store.renew(batch, renewing)
        except StateWriteError as exc:
            return exc
        except Exception as exc:  # anything else from the disk is still a write failure
            return StateWriteError(self.store.path, f"{renewing}: {exc}")
        with self._cond:
            self._renewals.append(note)
        return None

    def _commit(self, batch: Batch) -> StateWriteError | None:
        started = time.perf_counter_ns()
        try:
            self.store.write(batch)
        except StateWriteError as exc:
            return exc
        except Exception as exc:  # anything else from the disk is still a write failure
            return StateWriteError(self.store.path, _disk_words(exc))
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
            self._waiters = [(m, f) for m, f in self._waiters if not (error or m <= self.committed)]
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
            self._wake_encoder.notify()
        self._thread.join(timeout)
        self._encoder.join(timeout)
        with self._cond:
            left, self._waiters = self._waiters, []
        self._call([(fn, "the state file was closed first") for _, fn in left])
        self.store.deferred = False


def _disk_words(exc: Exception) -> str:
    """A write failure the store did not name, in words: an OS error's own (``File too
    large``), else an internal error of the writer with its message."""
    if isinstance(exc, OSError) and exc.strerror:
        return f"{exc.strerror}{f': {exc.filename}' if exc.filename else ''}"
    return internal_error("while writing it", exc)
