"""Real-time pacing on the system clock, with a monitor that aborts a scan that hangs
(docs/architecture.md, "Processes and threads"; docs/runtime.md, "When a scan hangs or fails").

One of the three engine modules allowed threads and sleeping (with ``clock.py`` and
``writer.py``). :class:`Runner` calls ``cpu.scan()`` every ``cycle_ms`` (a minimum cycle
time: a late scan starts the next one at once), hands each ``ScanRecord`` to ``on_record``,
logs the scan's message events and, after the scan boundary's commands, hands the state's
changes to the store's writer (``engine/writer.py``: the instance DBs encoded in the idle
part of the cycle, committed off the scan thread; what the writer has not encoded by the
next scan is carried under that scan's staging, or encoded by the scan thread before it),
and keeps statistics of the scan execution time and of overruns.

**Cycle monitoring of the real thing.** The CPU judges a cycle's length only once it is
over; a block, a plant or an action in an endless loop would never end it. A monitor
thread watches the scan thread while it runs a section marked ``abortable`` (the scan; the
chart runner marks the plant): still running at twice the maximum cycle time, it raises
``ScanAborted`` into it — by a signal when the scan thread is the main thread (it also
interrupts a sleep), else by ``PyThreadState_SetAsyncExc`` — and again every maximum cycle
time while it is swallowed. The CPU goes to STOP with a time-error entry naming the block
(``Cpu.abort``).

**Priority.** A scan must not wait for the processor behind a browser or a build on the
same machine: while the loop runs, the scan thread is scheduled real-time (``SCHED_FIFO``
at ``rt_priority``, its monitor one above, so that it can still abort a scan that never
ends) when the system allows it — root, ``CAP_SYS_NICE`` or an rtprio limit — and at the
normal priority otherwise (``realtime`` says which). The process's other threads (the
bus, the writer) run real-time too, ``HELPERS_BELOW`` lower: each takes the interpreter's
lock at times, and one that holds it must not wait for the processor while the scan waits
for the lock. They run ``SCHED_RR``, taking turns with every thread of their priority:
the helpers of all the CPUs on a machine share the processors the scans leave, and under
``SCHED_FIFO`` one of them busy for seconds (any CPU's) kept the others — a writer
confirming a download — from running at all. Processes they start (the view) are reset to
the normal policy; the loop ends with every thread back at the normal policy. The process
and the view it starts keep small pages (:func:`keep_small_pages`): the kernel merging huge
pages held scans up.
While the loop runs the interpreter hands its lock to a thread that asks for it after
0.5 ms (``engine.switching``) instead of its usual 5 ms: a CPU that scans back to back
(OB1 free-cycling, as an S7 CPU does without a minimum cycle time) still leaves its bus
thread and its writer their share — S7's "cycle load from communication" — where the
outbox put one message per 5 ms and dropped the rest; and a scan waking while a helper
holds the lock waits for it at most that long.
With ``core`` (``engine/cores.py``) the scan thread runs on that processor and the
process's other threads on the rest while the loop runs — but the writer's encoder, which
works only while the scan thread sleeps (``engine/writer.py``) and runs below it; all of
them get every processor back when it ends.

**The garbage collector** (:class:`IdleGc`) runs in the idle part of the cycle, never in
the middle of a scan: when the loop starts, what the startup loaded is frozen (``gc.freeze``:
never traversed again) and automatic collections are turned off; after each cycle's work,
when the next cycle is not due for a while, the generations that are due are collected.

**Where the time went** (``profile``, ``engine/profile.py``): each cycle is stamped at the
end of each phase of the loop (what was left of the last staging to encode, scan, alarm
log, ``on_record``, staging, collector, the wait and the late start of the next scan), with
the scan thread's processor time and its time waiting for a processor; the longest cycle
and the last long ones (over the cycle time + 2 ms) are kept with their breakdowns, for
``status`` and ``s7graph status``.

**Stopping.** ``request_stop`` (the CLI's SIGTERM and Ctrl-C handlers) ends the loop after
the current scan. If the scan thread does not come back within ``grace_s`` — code that
swallows every abort — the monitor commits the state as of the last finished scan with a
diagnostic entry saying so, and ends the process with exit status 3 (``EXIT_HUNG``).
"""

from __future__ import annotations

import contextlib
import ctypes
import gc
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from types import FrameType

from s7graph.engine.cores import allowed_cpus, machine_claims, pin, rest_of, scan_core
from s7graph.engine.cpu import Cpu
from s7graph.engine.diag_events import stop_cause
from s7graph.engine.diagnostics import EventId
from s7graph.engine.errors import ScanAborted, generated_place
from s7graph.engine.marks import EXIT_HUNG, GRACE_S, ScanMarks
from s7graph.engine.modes import CpuMode, ModeRequest
from s7graph.engine.persistence import Batch, StateStore, StateWriteError
from s7graph.engine.profile import CycleProfile, OpenCycle
from s7graph.engine.record import DiagEntry, ScanRecord
from s7graph.engine.restart import RestartType, error_blocker
from s7graph.engine.switching import switching
from s7graph.engine.watchdog import COMM_LOAD_PCT, CycleStatistics
from s7graph.engine.write_stop import leave_trace, stop_on_write_error
from s7graph.engine.writer import DurableCallback, StoreWriter

__all__ = [
    "COMM_LOAD_PCT",
    "RT_PRIORITY",
    "IdleGc",
    "Runner",
    "keep_core",
    "keep_small_pages",
    "refused_startup",
    "set_realtime",
    "stop_reason",
]

_ABORT_SIGNAL = signal.SIGUSR2
_CYCLE_STOPS = frozenset({EventId.STOP_OB80_MISSING, EventId.STOP_CYCLE_TIME})
RT_PRIORITY = 40
"""The scan thread's ``SCHED_FIFO`` priority (1-98) when the system allows real-time."""
ENCODE_MARGIN_S = 0.0005
"""How long before the next scan falls due the writer stops encoding the instance DBs of the
last staging (``engine/writer.py``; it also keeps twice its longest recent encoding clear):
what is left then is carried over to the next staging, or encoded by the scan thread."""


HELPERS_BELOW = 10
"""How far below the scan thread the process's other threads run real-time."""


def set_realtime(priority: int | None, tid: int = 0, *, turns: bool = False) -> bool:
    """Schedule thread ``tid`` (a native id; 0: the calling thread) ``SCHED_FIFO`` at
    ``priority`` (reset in processes it forks), or back to the normal policy with None;
    False when the system refuses (or the thread is gone). ``turns``: ``SCHED_RR``
    instead — threads of the same priority take turns, a time slice each, where under
    ``SCHED_FIFO`` one that does not block keeps the processor from the others."""
    try:
        if priority is None:
            os.sched_setscheduler(tid, os.SCHED_OTHER, os.sched_param(0))
        else:
            policy = (os.SCHED_RR if turns else os.SCHED_FIFO) | os.SCHED_RESET_ON_FORK
            os.sched_setscheduler(tid, policy, os.sched_param(priority))
    except (OSError, AttributeError):  # no permission, gone, or not Linux
        return False
    return True


def realtime_allowed(priority: int) -> bool:
    """Whether the system lets a thread of this process run ``SCHED_FIFO`` at
    ``priority`` (tried on a thread of its own, which then ends)."""
    allowed: list[bool] = []
    probe = threading.Thread(target=lambda: allowed.append(set_realtime(priority)))
    probe.start()
    probe.join()
    return bool(allowed and allowed[0])


def core_for(choice: str | int | None, rt_priority: int | None) -> int | None:
    """The processor to keep for a scan at ``rt_priority`` (None: normal scheduling) for the
    ``--core`` ``choice`` (``engine.cores.scan_core``; ``auto`` keeps one only where the
    system grants the priority, and one no other CPU of the machine keeps), claimed for this
    process (``engine.cores.machine_claims``); ValueError for a choice that cannot be."""
    realtime = rt_priority is not None and (
        choice not in (None, "auto") or realtime_allowed(rt_priority)
    )
    return scan_core(choice, realtime=realtime, claims=machine_claims())


PR_SET_THP_DISABLE = 41
"""``prctl`` option (Linux ``<linux/prctl.h>``)."""


def keep_small_pages() -> bool:
    """Keep this process's memory out of transparent huge pages (``prctl(PR_SET_THP_DISABLE)``,
    inherited by the processes it starts after); False where the system has no such call.

    The kernel's ``khugepaged`` merges small pages into huge ones in the background (numpy
    asks for them for its large arrays: the view's), holding the process's memory-map lock,
    and on a kernel that is not fully preemptible a merge keeps its processor: measured
    (``perf sched``, 200 sequencers under a command flood) a scan blocked 5.7 ms on that
    lock, and scans woken on time that waited up to 5.6 ms for the processor the merge held.
    Other processes' merges can still do that: a real-time machine turns them off
    (``transparent_hugepage=never``)."""
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        return int(libc.prctl(PR_SET_THP_DISABLE, 1, 0, 0, 0)) == 0
    except (OSError, AttributeError):
        return False


def _threads() -> list[int]:
    """The native ids of this process's threads (Linux), else none."""
    try:
        return [int(t) for t in os.listdir("/proc/self/task")]
    except OSError:
        return []


PIN_ROUNDS = 8
"""How often :func:`keep_core` lists the threads to pin until none is new."""


def _other_threads() -> list[int]:
    """The native ids of this process's threads but the calling one (Linux), else none."""
    me = threading.get_native_id()
    return [tid for tid in _threads() if tid != me]


def keep_core(core: int, everywhere: set[int]) -> bool:
    """The calling (scan) thread on ``core``, the process's other threads off it. A
    thread inherits its starter's processors, so one started by a thread not pinned yet
    is listed again until none is new (at most ``PIN_ROUNDS`` lists)."""
    rest = rest_of(core, everywhere)
    done: set[int] = set()
    for _ in range(PIN_ROUNDS):
        new = [tid for tid in _other_threads() if tid not in done]
        if not new:
            break
        for tid in new:
            pin(rest, tid)
        done.update(new)
    return pin({core})


class IdleGc:
    """Garbage collection in the idle part of the cycle.

    ``start()`` collects once, freezes what is there (the loaded program, the bus, the
    view: ``gc.freeze``) and turns automatic collections off; ``idle(slack_s)``, called
    when a cycle's work is done and the next is due in ``slack_s``, collects the youngest
    generation due — only when the slack is at least ``min_idle_s`` and twice that
    generation's longest collection so far, unless the garbage has piled up ``OVERDUE``
    times past the threshold (a CPU that never idles must not grow without bound);
    ``stop()`` gives the collector back as it was. Process-wide: nested starts count."""

    OVERDUE = 20
    _users = 0
    _was_enabled = True
    _lock = threading.Lock()

    def __init__(self, *, min_idle_s: float = 0.002) -> None:
        self.min_idle_s = min_idle_s
        self.collections = [0, 0, 0]
        self.longest_ns = [0, 0, 0]
        self.started = False

    def start(self) -> None:
        with IdleGc._lock:
            if IdleGc._users == 0:
                IdleGc._was_enabled = gc.isenabled()
                gc.collect()
                gc.freeze()
                gc.disable()
            IdleGc._users += 1
        self.started = True

    def stop(self) -> None:
        if not self.started:
            return
        self.started = False
        with IdleGc._lock:
            IdleGc._users -= 1
            if IdleGc._users == 0:
                gc.unfreeze()
                if IdleGc._was_enabled:
                    gc.enable()

    def idle(self, slack_s: float) -> bool:
        """Collect what is due if there is time for it; whether it collected."""
        counts = gc.get_count()
        thresholds = gc.get_threshold()
        if counts[0] < thresholds[0]:
            return False
        generation = 0
        while generation < 2 and counts[generation + 1] >= thresholds[generation + 1]:
            generation += 1
        overdue = counts[0] >= thresholds[0] * self.OVERDUE
        while generation > 0 and slack_s * 1e9 < 2 * self.longest_ns[generation]:
            generation -= 1  # a younger one fits
        if not overdue and (
            slack_s < self.min_idle_s or slack_s * 1e9 < 2 * self.longest_ns[generation]
        ):
            return False
        started = time.perf_counter_ns()
        gc.collect(generation)
        took = time.perf_counter_ns() - started
        self.collections[generation] += 1
        self.longest_ns[generation] = max(self.longest_ns[generation], took)
        return True


class Runner:
    """Paces one CPU in real time until ``duration_s`` has passed or ``stop()`` is called.

    ``end_on_stop``: end the loop when the CPU goes to STOP by itself (a block error, a
    time error, an abort); ``stopped`` then holds the reason. A write error of the state
    file always ends it (``write_error``), with the CPU in STOP. ``comm_load_pct``: the
    share of the cycle the edge's commands may take at a boundary (``comm_budget_ns``).
    ``core``: the processor the scan thread keeps while the loop runs (``engine.cores``;
    None: it and every other thread run anywhere)."""

    def __init__(
        self,
        cpu: Cpu,
        *,
        cycle_ms: float = 10.0,
        store: StateStore | None = None,
        on_record: Callable[[ScanRecord], None] | None = None,
        end_on_stop: bool = False,
        grace_s: float = GRACE_S,
        on_stop: Callable[[str], object] | None = None,
        idle_gc: bool = True,
        rt_priority: int | None = RT_PRIORITY,
        comm_load_pct: float = COMM_LOAD_PCT,
        core: int | None = None,
        marks: ScanMarks | None = None,
    ) -> None:
        if cycle_ms <= 0:
            raise ValueError("cycle time must be positive")
        if not 1 <= comm_load_pct <= 100:
            raise ValueError("the communication load must be 1-100 % of the cycle")
        if rt_priority is not None and not 1 <= rt_priority <= 98:
            raise ValueError("real-time priority must be 1..98 (None: normal scheduling)")
        self.cpu = cpu
        self.cycle_s = cycle_ms / 1000.0
        self.store = store
        self.on_record = on_record
        self.end_on_stop = end_on_stop
        self.on_stop = on_stop
        """Called with the reason (one line) when the CPU goes to STOP by itself."""
        self.on_note: Callable[[str], object] | None = None
        """Called (in the scan thread) with what the user should know that is not a STOP:
        the state file was written anew (``engine/renew.py``)."""
        self.grace_s = grace_s
        self.exec_stats = CycleStatistics()
        """Wall time spent inside ``scan()`` (ns)."""
        self.overruns = 0
        """Cycles whose work took the whole set cycle time (the next started at once)."""
        self.profile = CycleProfile(int(self.cycle_s * 1e9))
        """Where each cycle's time went, and the cycles that ran long (``engine.profile``)."""
        self.scans = 0
        self.aborts = 0
        self.writer: StoreWriter | None = None
        self.stopped = ""
        """Why the CPU went to STOP by itself while running (one line), else empty."""
        self.write_error: StateWriteError | None = None
        self.trace = ""
        """After a write error: whether the STOP's entry reached the file at the end, in words."""
        self.rt_priority = rt_priority
        self.comm_load_pct = comm_load_pct
        self.comm_budget_ns = int(self.cycle_s * 1e9 * comm_load_pct / 100)
        """What one scan boundary may spend on commands (``COMM_LOAD_PCT``)."""
        self.realtime = False
        """Whether the scan thread runs real-time (while ``run`` runs)."""
        self.core = core
        self.pinned = False
        """Whether the scan thread runs on ``core`` alone (while ``run`` runs)."""
        self.gc: IdleGc | None = IdleGc() if idle_gc else None
        """The collector in the idle part of the cycle (``idle_gc``), while ``run`` runs."""
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._lock = threading.Lock()
        self._section: str | None = None
        self._cycle_start = 0.0
        self._armed = False
        self._last_abort = 0.0
        self._scan_tid: int | None = None
        self._signal_abort = False
        self._stop_at: float | None = None
        self._monitor: threading.Thread | None = None
        self._done = threading.Event()
        self._exit: Callable[[int], object] = os._exit
        self.marks = marks
        """Each cycle, section and block marked for the supervisor (``engine.marks``)."""
        self._switched = False

    # ---- starting and stopping ----------------------------------------------------------

    def startup(self, restart: str | RestartType = "warm") -> ScanRecord:
        """STOP → STARTUP → RUN with ``restart``; the state is written at once (marked as
        a run that has not ended cleanly) and the writer starts."""
        self._watch()
        record = self.cpu.start(restart)
        if self.store is not None:
            self.log_alarms(record)
            self.store.save(self.cpu, clean=False)
            self.writer = StoreWriter(self.store)
        return record

    def stop(self) -> None:
        """Ask the loop to end after the current scan (thread-safe)."""
        self._stop.set()

    def request_stop(self) -> None:
        """A stop from outside (SIGTERM, Ctrl-C): end after this scan, and if the scan does
        not return within ``grace_s``, save what is saved and end the process."""
        if self._stop_at is None:
            self._stop_at = time.monotonic()
        self._stop.set()

    def on_stop_signal(self, signum: int, frame: FrameType | None) -> None:
        """A handler for SIGTERM and SIGINT: ``request_stop`` (never interrupted by an abort
        of the scan it interrupted)."""
        self.request_stop()

    # ---- the RUN/STOP switch, and a start in STOP after a hang -----------------------------

    def switch_stop(self, reason: str) -> None:
        """RUN → STOP by the switch (at a scan boundary, in the scan thread): outputs to 0,
        and not a STOP by itself (the loop goes on, ``stopped`` stays as it was)."""
        self._switched = True
        self.cpu.stop(reason)

    def switch_start(self, restart: str | RestartType) -> None:
        """STOP → RUN by the switch: the startup ``restart`` at the next scan boundary; a
        STOP by itself before it is no longer how the run ends (``stopped`` cleared)."""
        self.cpu.submit(ModeRequest(CpuMode.RUN, restart=str(restart)))
        self.stopped = ""

    def recover(self, block: str, message: str) -> ScanRecord:
        """Instead of ``startup``: the CPU stays in STOP as restored from the state file,
        with an entry ``EventId.STOP_KILLED`` naming ``block`` (the supervisor ended the
        process before, its scan hung); the state is written at once, the writer starts.
        The recovery's record (the CPU in STOP, that entry) goes to ``on_record`` at once,
        as a scan's would: the bus says STOP from then on, not only from the loop's first
        scan."""
        self._watch()
        cpu = self.cpu
        now = cpu.clock.now_ns()
        cpu.stop_entry = entry = cpu.diagnostics.record(now, EventId.STOP_KILLED, block, message)
        cpu.hot_blockers.add(error_blocker(message))  # a warm restart only
        self.stopped = stop_reason(cpu)
        if self.store is not None:
            self.store.save(cpu, clean=False)
            self.writer = StoreWriter(self.store)
        record = ScanRecord(max(cpu.cycle, 0), now, 0, cpu.mode, diagnostics=(entry,))
        if self.on_record is not None:
            self.on_record(record)
        return record

    def _why_stopped(self) -> str:
        """:func:`stop_reason`; for a STOP by the cycle time, with where the cycle that ran
        over spent its time (its :class:`~s7graph.engine.profile.CycleBreakdown`: the phase
        that took it, and whether the scan thread ran, waited for a processor or was
        blocked) — the cycle monitor says only that it was long."""
        reason = stop_reason(self.cpu)
        stop = self.cpu.stop_entry
        recent = self.profile.recent
        last = recent[-1] if recent and recent[-1].scan == self.scans - 1 else None
        if stop is not None and stop.event_id in _CYCLE_STOPS and last is not None:
            reason += f"; where the cycle's time went: {last.describe()}"
        return reason

    def _stopped_by_itself(self, was_running: bool) -> bool:
        switched, self._switched = self._switched, False
        stopped = was_running and self.cpu.mode is CpuMode.STOP
        return stopped and not switched and not self._stop.is_set()

    # ---- the loop ------------------------------------------------------------------------

    def run(self, *, duration_s: float | None = None) -> None:
        """Scan until stopped or ``duration_s`` elapsed."""
        self._scan_tid = threading.get_ident()
        self._watch()
        if self.store is not None and self.writer is None:
            self.writer = StoreWriter(self.store)
        previous = self._install_abort_signal()
        if self.marks is not None:
            self.marks.max_cycle(self.cpu.watchdog.max_cycle_ns)
            self.cpu.mark_blocks(self.marks)
        if self.rt_priority is not None:
            keep_small_pages()
            self.realtime = set_realtime(self.rt_priority)
        if self.realtime and self.rt_priority is not None:
            helpers = max(1, self.rt_priority - HELPERS_BELOW)
            for tid in _other_threads():
                set_realtime(helpers, tid, turns=True)
        everywhere = allowed_cpus() | ({self.core} if self.core is not None else set())
        if self.core is not None:  # (the calling thread may have kept off it already)
            self.pinned = keep_core(self.core, everywhere)
            encoder = self.writer.encoder_id if self.writer is not None else None
            if self.pinned and encoder is not None:
                pin({self.core}, encoder)  # it works while the scan thread sleeps
        if self.gc is not None:
            self.gc.start()
        try:
            with switching():
                self._loop(duration_s)
        finally:
            self._finish_staging(carry=False)  # nothing half-staged after the loop
            if self.gc is not None:
                self.gc.stop()
            if self.realtime:
                self.realtime = False
                for tid in _threads():
                    set_realtime(None, tid)
            if self.pinned:
                self.pinned = False
                for tid in _threads():
                    pin(everywhere, tid)
            if previous is not None:
                signal.signal(_ABORT_SIGNAL, previous)
            self._signal_abort = False

    def _loop(self, duration_s: float | None) -> None:
        cpu = self.cpu
        profile = self.profile
        clock = time.perf_counter_ns
        runq = _RunQueue()
        t0 = time.monotonic()
        deadline = None if duration_s is None else t0 + duration_s
        due = t0
        open_cycle: OpenCycle | None = None
        marks = self.marks
        try:
            while not self._stop.is_set():
                if marks is not None:
                    marks.begin(time.monotonic_ns())
                now = time.monotonic()
                started = clock()
                self._finish_staging()  # first: the bookkeeping below counts with the scan
                encoded = clock()
                cpu_ns, waited = time.thread_time_ns(), runq.read()
                if open_cycle is not None:
                    profile.add(open_cycle.close(started, cpu_ns, waited))
                if deadline is not None and now >= deadline:
                    break
                at = time.time_ns()
                was_running = cpu.mode is CpuMode.RUN
                self._cycle_start = now
                record: ScanRecord | None = None
                try:
                    with self.abortable("scan"):
                        record = cpu.scan()
                except ScanAborted as abort:
                    cpu.abort(abort.block or "CPU")
                scanned = clock()
                self.exec_stats.add(scanned - encoded)
                self.scans += 1
                if record is not None:
                    self.log_alarms(record)
                logged = clock()
                if record is not None and self.on_record is not None:
                    try:
                        self.on_record(record)
                    except ScanAborted as abort:
                        cpu.abort(abort.block or "on_record")
                edged = clock()
                due += self.cycle_s
                self._persist(until=due - ENCODE_MARGIN_S)
                staged = clock()
                if self.write_error is not None:
                    break
                if self._stopped_by_itself(was_running):
                    self.stopped = self._why_stopped()
                    if self.on_stop is not None:
                        self.on_stop(self.stopped)
                    if self.end_on_stop:
                        break
                if marks is not None:
                    marks.end()
                delay = due - time.monotonic()
                if delay > 0 and self.gc is not None and self.gc.idle(delay):
                    delay = due - time.monotonic()
                collected = clock()
                stamps = [started, encoded, scanned, logged, edged, staged, collected]
                idle_ns = max(0, int(delay * 1e9))
                open_cycle = OpenCycle(self.scans, at, stamps, cpu_ns, waited, idle_ns, delay <= 0)
                if delay > 0:
                    self._stop.wait(delay)
                else:
                    self.overruns += 1
                    due = time.monotonic()
        finally:
            runq.close()
            if marks is not None:
                marks.end()

    def _persist(self, *, until: float | None = None) -> None:
        """Stage this scan's changes (after the boundary's commands: one state) and hand
        them to the writer, which encodes the instance DBs in the idle part of the cycle,
        up to ``until`` (``time.monotonic``)."""
        writer = self.writer
        if self.store is None or writer is None:
            return
        full = writer.wants_full  # the file is built anew: with the whole state
        batch = self.store.stage(self.cpu, upto=self.scans, full=full, defer=not full)
        writer.submit(batch, self.scans, until=until)
        for note in writer.take_renewals():
            self.cpu.diagnostics.record(self.cpu.clock.now_ns(), EventId.STATE_RENEWED, "", note)
            if self.on_note is not None:
                self.on_note(note)
        if writer.error is not None and self.write_error is None:
            self.write_error = writer.error
            self.stopped = stop_on_write_error(self.cpu, writer.error)  # engine/write_stop.py
            if self.on_stop is not None:
                self.on_stop(self.stopped)  # at once: the file may never take the entry

    def _finish_staging(self, *, carry: bool = True) -> None:
        """Before the next scan changes it: the last staging encoded, or carried over to the
        next (``StoreWriter.finish``); a failure is the writer's error, seen by the next
        ``_persist``."""
        if self.writer is not None:
            self.writer.finish(carry=carry)

    def log_alarms(self, record: ScanRecord) -> None:
        """Append the message events of ``record`` to the store's alarm log (wall time)."""
        if self.store is not None and record.alarms:
            self.store.log_alarms(record.alarms, time.time_ns())

    @contextlib.contextmanager
    def abortable(self, what: str) -> Iterator[None]:
        """Mark the scan thread's section ``what`` as one the monitor may abort once the
        cycle (begun at the last scan's start) has run twice the maximum cycle time."""
        with self._lock:
            self._section = what
            self._armed = False
        if self.marks is not None:
            self.marks.section(what)
        try:
            yield
        finally:
            if self.marks is not None:
                self.marks.section(None)
            with self._lock:
                self._section = None
                if self._armed and not self._signal_abort and self._scan_tid is not None:
                    _set_async_exc(self._scan_tid, None)  # not delivered yet: withdrawn
                self._armed = False

    # ---- durability (for the command path) -------------------------------------------------

    def durable_mark(self) -> int:
        """The mark whose commit makes durable everything applied so far: a command applied
        at this scan boundary acts (and is audited) in the next scan — staged after the
        boundary, so the scan done is not yet the writer's latest."""
        later = self.scans + 1
        return max(self.writer.next_mark(), later) if self.writer is not None else later

    def when_durable(self, mark: int, fn: DurableCallback) -> None:
        """``fn(None)`` once scan ``mark`` is on disk, ``fn(error)`` if it never will be; at
        once without a store (nothing to wait for)."""
        if self.writer is None:
            fn(None if self.store is None else "the state file is not open yet")
            return
        self.writer.when_durable(mark, fn)

    def write_problem(self) -> str | None:
        """Why nothing more reaches the state file (a write error), in words; None: no such
        error (a commit may still be late)."""
        writer = self.writer
        error = self.write_error or (writer.error if writer is not None else None)
        return str(error) if error is not None else None

    def wait_durable(self, mark: int, timeout: float | None = None) -> bool:
        """Block (never in the scan thread) until scan ``mark`` is on disk."""
        return self.writer is None or self.writer.wait(mark, timeout)

    # ---- threads ---------------------------------------------------------------------------

    def start_thread(self, *, duration_s: float | None = None) -> threading.Thread:
        """Run the loop in a daemon thread (for hosts that own the main thread)."""
        thread = threading.Thread(
            target=self.run, kwargs={"duration_s": duration_s}, name="s7graph-scan", daemon=True
        )
        self._thread = thread
        thread.start()
        return thread

    def join(self, timeout: float | None = None) -> None:
        if self._thread is not None:
            self._thread.join(timeout)

    def shutdown(self, reason: str = "runner stopped") -> ScanRecord:
        """STOP the CPU (outputs 0), take a last record, save the state (marked clean) and
        end the writer and the monitor."""
        self.stop()
        self.join()
        self.cpu.stop(reason)
        record = self.cpu.scan()
        self.log_alarms(record)
        if self.on_record is not None:
            self.on_record(record)
        writer, self.writer = self.writer, None
        left = None
        if writer is not None:
            writer.close()  # commits what is pending
            left = writer.left  # the file to be built anew: the last save does it
            if writer.error is not None and self.write_error is None and left is None:
                self.write_error = writer.error
        if self.store is not None and self.write_error is None:
            try:
                self.store.save(self.cpu, clean=True, before=left)
            except StateWriteError as exc:
                self.write_error = exc
        elif self.store is not None:  # the entries the file lacks, the STOP's among them
            self.trace = leave_trace(self.store, self.cpu)
        self._done.set()
        return record

    def _watch(self) -> None:
        if self._monitor is None:
            self._monitor = threading.Thread(
                target=self._monitor_loop, name="s7graph-monitor", daemon=True
            )
            self._monitor.start()

    def _monitor_loop(self) -> None:
        above = False
        while not self._done.wait(self._poll_s()):
            if self.realtime and not above and self.rt_priority is not None:
                above = set_realtime(self.rt_priority + 1)  # it must preempt a hung scan
            now = time.monotonic()
            self._check_abort(now)
            if self._stop_at is not None and now - self._stop_at >= self.grace_s:
                self._end_hung(now - self._stop_at)
                return

    def _poll_s(self) -> float:
        max_s = self.cpu.watchdog.max_cycle_ns / 1e9
        return min(0.05, max(0.005, max_s / 4))

    def _check_abort(self, now: float) -> None:
        with self._lock:
            if self._section is None or self._scan_tid is None:
                return
            limit = 2 * self.cpu.watchdog.max_cycle_ns / 1e9
            elapsed = now - self._cycle_start
            if elapsed < limit or now - self._last_abort < limit / 2:
                return
            self._last_abort = now
            self.aborts += 1
            where = _innermost(self._scan_tid)
            self.cpu.abort_reason = (
                f"still running {elapsed * 1000:.0f} ms into the cycle{where}, past twice "
                f"the maximum cycle time ({limit * 1000:.0f} ms)"
            )
            self._armed = True
            if self._signal_abort:
                signal.pthread_kill(self._scan_tid, _ABORT_SIGNAL)
            else:
                _set_async_exc(self._scan_tid, ScanAborted)

    def _install_abort_signal(self) -> signal.Handlers | Callable[..., object] | int | None:
        if threading.current_thread() is not threading.main_thread():
            return None
        previous = signal.signal(_ABORT_SIGNAL, self._on_abort_signal)
        self._signal_abort = True
        return previous

    def _on_abort_signal(self, signum: int, frame: FrameType | None) -> None:
        if not self._armed:
            return
        up = frame
        while up is not None:  # inside the stop handler: abort at the next try instead
            if up.f_code in _SHIELDED:
                return
            up = up.f_back
        self._armed = False
        raise ScanAborted

    def _end_hung(self, waited_s: float) -> None:
        """The scan did not return after a stop request: commit what is staged with an
        entry saying so, one line on stderr, and end the process (``EXIT_HUNG``)."""
        where = _innermost(self._scan_tid) if self._scan_tid is not None else ""
        message = (
            f"the scan did not return{where} within {waited_s:.1f} s of the stop request: "
            "process ended; the state is the last finished scan's"
        )
        entry = DiagEntry(
            self.cpu.clock.now_ns(), EventId.STOP_HUNG, "", message, wall_ns=time.time_ns()
        )
        writer = self.writer
        if writer is not None and self.store is not None:
            batch = Batch(diagnostics=[self.store.diagnostic_row(entry)])
            writer.submit(batch, 0)
            writer.close(timeout=2.0)
        print(f"s7graph: error: {message}", file=sys.stderr, flush=True)
        self._exit(EXIT_HUNG)


_SHIELDED = {Runner.on_stop_signal.__code__, Runner.request_stop.__code__}


def stop_reason(cpu: Cpu) -> str:
    """One line: why ``cpu`` went to STOP — the error entry that caused it, if any, and the
    STOP entry (``Cpu.stop_entry``); or why it stays in STOP after a startup it refused
    (``refused_startup``), in the words ``s7graph run`` says it with."""
    refusal = refused_startup(cpu)
    if refusal is not None:
        return f"the CPU refused its startup: {_at(refusal)}{refusal.message}"
    stop = cpu.stop_entry
    if stop is None:
        return "the CPU is in STOP"
    cause = stop_cause(cpu.diagnostics, stop)
    if cause is None:
        return f"{_at(stop)}{stop.message}"
    return f"{_at(cause)}{cause.message} ({stop.message})"


def refused_startup(cpu: Cpu) -> DiagEntry | None:
    """The entry ``16#4309`` of the startup ``cpu`` refused last (the key switch in STOP, a
    startup OB deselected), when that refusal is why it is in STOP: no startup and no STOP
    entry came after it. None otherwise — a hot restart it turned warm started."""
    if cpu.mode is not CpuMode.STOP:
        return None
    for entry in reversed(list(cpu.diagnostics)):
        if entry.event_id == EventId.STARTUP_REFUSED:
            return entry
        if entry is cpu.stop_entry or entry.event_id in _STARTED:
            return None
    return None


_STARTED = frozenset({EventId.STOP_TO_STARTUP, EventId.STARTUP_TO_RUN})


def _at(entry: DiagEntry) -> str:
    return f"{entry.block}: " if entry.block else ""


class _RunQueue:
    """The calling thread's time waiting for a processor (ns, ``run_delay`` of Linux
    ``/proc/thread-self/schedstat``), or ``None`` where the system does not say."""

    def __init__(self) -> None:
        try:
            self._fd: int | None = os.open("/proc/thread-self/schedstat", os.O_RDONLY)
        except OSError:
            self._fd = None

    def read(self) -> int | None:
        if self._fd is None:
            return None
        try:
            return int(os.pread(self._fd, 96, 0).split()[1])
        except (OSError, ValueError, IndexError):
            return None

    def close(self) -> None:
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None


def _set_async_exc(tid: int, exc: type[BaseException] | None) -> None:
    obj = ctypes.py_object(exc) if exc is not None else None
    ctypes.pythonapi.PyThreadState_SetAsyncExc(ctypes.c_ulong(tid), obj)


def _innermost(tid: int) -> str:
    """`` (file.py:12 in f)``: where thread ``tid`` is running now, for the diagnostics; in
    code generated from a source (S7-SCL), the innermost place of that source
    (`` (mix.scl:7:3)``), never the generated code's."""
    frame = sys._current_frames().get(tid)
    if frame is None:
        return ""
    outer: FrameType | None = frame
    while outer is not None:
        place = generated_place(outer.f_code.co_filename, outer.f_lineno)
        if place is not None:
            return f" ({place})"
        outer = outer.f_back
    return f" ({Path(frame.f_code.co_filename).name}:{frame.f_lineno} in {frame.f_code.co_name})"
