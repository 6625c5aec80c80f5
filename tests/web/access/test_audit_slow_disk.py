"""The audit store and a slow or renewed state file (web/access/audit.py): a command's row is
queued at the scan boundary (``record``, in the scan thread) while a reader of the trail or
the alarm history waits for the disk — the read must not hold the row, and so the scan, up;
and when the run's store builds the file anew (engine/renew.py) the audit follows it."""

from __future__ import annotations

import threading
from pathlib import Path
from typing import Any

from s7graph.engine import Cpu, VirtualClock
from s7graph.engine.persistence import StateStore
from s7graph.engine.writer import StoreWriter
from s7graph.web.access.audit import AuditStore, Facts

MODE = Facts("ann", "operator", "shell", "mode", "FB1", {"mode": "MAN"}, True)


class _SlowDisk:
    """A connection whose reads wait until ``go`` is set (a stalled disk)."""

    def __init__(self, real: Any) -> None:
        self.real = real
        self.entered = threading.Event()
        self.go = threading.Event()

    def execute(self, *args: Any) -> Any:
        self.entered.set()
        self.go.wait(30)
        return self.real.execute(*args)


def test_a_read_waiting_for_a_slow_disk_never_holds_up_a_commands_row(tmp_path: Path) -> None:
    state = StateStore(tmp_path / "s.sqlite")
    writer = StoreWriter(state)  # the run's: rows are queued, committed with the scan's state
    audit = AuditStore(state.path, state=state)
    slow = _SlowDisk(audit._db)
    audit._db = slow  # type: ignore[assignment]
    reader = threading.Thread(target=audit.alarm_history, daemon=True)
    try:
        reader.start()
        assert slow.entered.wait(10)
        queued = threading.Event()
        boundary = threading.Thread(target=lambda: (audit.record(1, MODE), queued.set()))
        boundary.start()
        assert queued.wait(10), "the command's row waited for a read of the disk"
        assert not slow.go.is_set()  # the read is still waiting
    finally:
        slow.go.set()
        reader.join(10)
        writer.close()
        audit._db = slow.real
        audit.close()
        state.close()


def test_the_audit_follows_a_state_file_built_anew(tmp_path: Path) -> None:
    path = tmp_path / "s.sqlite"
    cpu = Cpu(VirtualClock())
    cpu.start()
    state = StateStore(path)
    state.save(cpu)
    writer = StoreWriter(state)
    audit = AuditStore(path, state=state)
    try:
        audit.record(1, MODE)
        writer.submit(state.stage(cpu, upto=1), 1)
        assert writer.wait(1, timeout=10)
        path.unlink()
        audit.record(2, MODE)
        writer.submit(state.stage(cpu, upto=2), 2)
        for mark in range(3, 1000):  # as the runner: a whole staging once the writer asks
            if writer.wait(2, timeout=0.01):
                break
            writer.submit(state.stage(cpu, upto=mark, full=writer.wants_full), mark)
        assert writer.durable(2), writer.error
        assert [r.t_ns for r in audit.last()] == [1, 2]  # both rows, read from the new file
        assert (tmp_path / "s.sqlite.damaged-1-wal").exists()
    finally:
        writer.close()
        audit.close()
        state.close()
