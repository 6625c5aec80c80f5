"""Real-time pacing on the system clock (DESIGN.md "Process model").

The only engine module allowed ``threading`` and sleeping: it calls ``cpu.scan()`` every
``cycle_ms`` (a minimum cycle time: a late scan starts the next one at once), hands each
``ScanRecord`` to ``on_record``, lets a ``StateStore`` save changed retentive data and log
the scan's message events (``ScanRecord.alarms``, stamped with the wall clock), and keeps
statistics of the scan execution time and of overruns.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable

from s7graph.engine.cpu import Cpu
from s7graph.engine.modes import CpuMode
from s7graph.engine.persistence import StateStore
from s7graph.engine.record import ScanRecord
from s7graph.engine.watchdog import CycleStatistics


class Runner:
    """Paces one CPU in real time until ``duration_s`` has passed or ``stop()`` is called."""

    def __init__(
        self,
        cpu: Cpu,
        *,
        cycle_ms: float = 10.0,
        store: StateStore | None = None,
        on_record: Callable[[ScanRecord], None] | None = None,
    ) -> None:
        if cycle_ms <= 0:
            raise ValueError("cycle time must be positive")
        self.cpu = cpu
        self.cycle_s = cycle_ms / 1000.0
        self.store = store
        self.on_record = on_record
        self.exec_stats = CycleStatistics()
        """Wall time spent inside ``scan()`` (ns)."""
        self.overruns = 0
        self.scans = 0
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def stop(self) -> None:
        """Ask the loop to end after the current scan (thread-safe)."""
        self._stop.set()

    def run(self, *, duration_s: float | None = None) -> None:
        """Scan until stopped or ``duration_s`` elapsed (KeyboardInterrupt propagates)."""
        t0 = time.monotonic()
        deadline = None if duration_s is None else t0 + duration_s
        due = t0
        while not self._stop.is_set():
            now = time.monotonic()
            if deadline is not None and now >= deadline:
                break
            started = time.perf_counter_ns()
            record = self.cpu.scan()
            self.exec_stats.add(time.perf_counter_ns() - started)
            self.scans += 1
            if self.store is not None:
                self.log_alarms(record)
                if self.cpu.mode is CpuMode.RUN:
                    self.store.maybe_save(self.cpu)
            if self.on_record is not None:
                self.on_record(record)
            due += self.cycle_s
            delay = due - time.monotonic()
            if delay > 0:
                self._stop.wait(delay)
            else:
                self.overruns += 1
                due = time.monotonic()

    def log_alarms(self, record: ScanRecord) -> None:
        """Append the message events of ``record`` to the store's alarm log (wall time)."""
        if self.store is not None and record.alarms:
            self.store.log_alarms(record.alarms, time.time_ns())

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
        """STOP the CPU (outputs 0), take a last record and save the state."""
        self.stop()
        self.join()
        self.cpu.stop(reason)
        record = self.cpu.scan()
        self.log_alarms(record)
        if self.on_record is not None:
            self.on_record(record)
        if self.store is not None:
            self.store.save(self.cpu)
        return record
