"""``s7graph watch --address`` waits for a CPU that goes away, as ``s7graph watch`` does
(web/cli/watch_table.py, docs/cli.md, "s7graph watch --address"): it says ``CPU cpu1
disconnected``, stays, says ``CPU cpu1 reachable`` when the CPU is back and shows its values
again. Real processes: a CPU running a program of blocks on a unix socket, killed and
started again, and the shell's watch."""

from __future__ import annotations

import queue
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from tests.paths import ROOT
from tests.web.cli.test_program_bus import _bus, _program
from tests.web.helpers import cpu_process

pytestmark = pytest.mark.timeout(240)


class Lines:
    """The stdout lines of ``proc``, read by a thread."""

    def __init__(self, proc: subprocess.Popen[str]) -> None:
        self.proc = proc
        self.seen: list[str] = []
        self._lines: queue.Queue[str] = queue.Queue()
        out = proc.stdout
        assert out is not None
        threading.Thread(target=lambda: [self._lines.put(x) for x in out], daemon=True).start()

    def wait_for(self, test: str, after: int = 0, timeout: float = 60) -> int:
        """The index of the first line from ``after`` on that starts with ``test``."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            for i, line in enumerate(self.seen[after:], after):
                if line.startswith(test):
                    return i
            try:
                self.seen.append(self._lines.get(timeout=0.5).rstrip("\n"))
            except queue.Empty:
                assert self.proc.poll() is None, f"watch ended: {self.seen}"
        raise AssertionError(f"no line {test!r} after line {after}: {self.seen}")


def test_watch_address_waits_for_a_cpu_that_goes_and_shows_it_again_when_it_is_back(
    tmp_path: Path,
) -> None:
    args = [*_program(tmp_path), "--fresh"]
    command = [sys.executable, "-m", "s7graph", "watch", *_bus(tmp_path), "--address"]
    command += ["MW10:INT", "--interval-ms", "50", "--duration-s", "200"]
    watch = None
    try:
        with cpu_process(tmp_path, args):
            watch = subprocess.Popen(
                command, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
            )
            lines = Lines(watch)
            first = lines.wait_for("cycle ")
            lines.wait_for("cycle ", first + 2)  # watching a while: it has heard the CPU
        # the CPU killed (cpu_process kills it at its end)
        gone = lines.wait_for("CPU cpu1 disconnected")
        time.sleep(1.0)
        assert watch.poll() is None  # still there, waiting
        (tmp_path / "bus.sock").unlink(missing_ok=True)  # a killed CPU leaves its socket
        with cpu_process(tmp_path, args[:-1]):  # started again (no --fresh)
            back = lines.wait_for("CPU cpu1 reachable", gone)
            lines.wait_for("cycle ", back)  # its values again
        watch.send_signal(signal.SIGINT)
        _, err = watch.communicate(timeout=30)
        assert watch.returncode == 0 and "Traceback" not in err, err
    finally:
        if watch is not None and watch.poll() is None:
            watch.kill()
            watch.wait(30)
