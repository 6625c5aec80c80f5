"""``s7graph run`` as a small supervisor with the CPU as its child: a watchdog outside the
process.

The in-process monitor (``engine/runner.py``) aborts a scan at twice the maximum cycle time,
but only between bytecodes: a plant or a block looping inside C code (``sum(range(10**13))``,
a regular expression backtracking) holds the interpreter's lock, and then nothing in the
process runs — not the bus, not ``status``, not the SIGTERM handler. So :func:`supervise`
runs the CPU as ``python -m s7graph run ...`` (the same arguments) beside a page of shared
memory (``engine/marks.py``: when the current cycle began, the section and block it runs),
and looks at it every ``POLL_S``:

- a cycle still running ``KILL_AFTER_S`` past twice the maximum cycle time (the in-process
  abort had its chance): the CPU's process is killed (SIGKILL), the processes it started
  (the view) ended, and the CPU started again **in STOP** from its last durable state, on
  the same bus keys, with the cause — where it hung and how long — in the diagnostic buffer
  (``EventId.STOP_KILLED``), on stderr, in ``status`` and on the page; ``s7graph start`` (or
  the page's RUN button) restarts it. Without a bus a STOP ends the run as before: the new
  process writes the entry, says why and exits 1;
- a CPU process killed by a signal it did not ask for (a crash in C code) after it had
  scanned is brought back the same way;
- SIGTERM and SIGINT are passed on: the CPU ends as before (its state durable); from then on
  the supervisor waits ``GRACE_S`` + ``STOP_EXTRA_S`` and kills a CPU that hangs in C code,
  exit status ``EXIT_HUNG``;
- stdout, stderr and the exit status are the CPU's own.

The child learns of its marks and of a recovery from the environment (``MARKS_ENV``: the
descriptor of the shared page; ``RECOVER_ENV``: the place and the cause) and dies with the
supervisor (``PR_SET_PDEATHSIG``). The supervisor is a child subreaper, so the view of a
killed CPU becomes its own child and is ended before the next CPU binds the same port.
"""

from __future__ import annotations

import contextlib
import ctypes
import functools
import mmap
import os
import signal
import subprocess
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from types import FrameType

from s7graph.engine.marks import EXIT_HUNG, GRACE_S, MARKS_SIZE, MarkReader, ScanMarks

__all__ = [
    "KILL_AFTER_S",
    "MARKS_ENV",
    "RECOVER_ENV",
    "Supervisor",
    "child_marks",
    "recovered_cause",
    "supervise",
    "supervises",
]

MARKS_ENV = "S7GRAPH_SCAN_MARKS"
RECOVER_ENV = "S7GRAPH_RECOVERED"
KILL_AFTER_S = 1.0
"""How long past twice the maximum cycle time a cycle may run before the CPU is killed."""
POLL_S = 0.05
STOP_EXTRA_S = 5.0
"""Beyond the CPU's own ``GRACE_S`` after a stop request, before it is killed."""
END_VIEW_S = 10.0
_PR_SET_PDEATHSIG = 1
_PR_SET_CHILD_SUBREAPER = 36
_SEP = "\x1f"


def _prctl(option: int, value: int) -> bool:
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        return int(libc.prctl(option, value, 0, 0, 0)) == 0
    except (OSError, AttributeError):
        return False


def die_with_parent(parent: int) -> None:  # in the child, between fork and exec
    """Be SIGKILLed when ``parent`` ends — at once if it ended before the signal was set
    (between the fork and here): else the CPU would run on, orphaned, writing the state file
    a restarted run reads (prctl(2), PR_SET_PDEATHSIG)."""
    _prctl(_PR_SET_PDEATHSIG, signal.SIGKILL)
    if os.getppid() != parent:
        os.kill(os.getpid(), signal.SIGKILL)


def child_marks() -> ScanMarks | None:
    """In the CPU's process: the marks its supervisor reads (None: not supervised)."""
    fd = os.environ.pop(MARKS_ENV, "")
    if not fd.isdigit():
        return None
    try:
        return ScanMarks(memoryview(mmap.mmap(int(fd), MARKS_SIZE)))
    except (OSError, ValueError):
        return None


def recovered_cause() -> tuple[str, str] | None:
    """In the CPU's process: (place, cause) when the supervisor killed the one before."""
    text = os.environ.pop(RECOVER_ENV, "")
    if not text:
        return None
    place, _, cause = text.partition(_SEP)
    return place, cause


def _ms(ns: int) -> str:
    return f"{ns / 1e6:.0f} ms"


class Supervisor:
    """Runs ``python -m s7graph <args>`` with its marks until it ends by itself."""

    def __init__(self, args: Sequence[str], *, kill_after_s: float = KILL_AFTER_S) -> None:
        self.args = list(args)
        self.kill_after_s = kill_after_s
        self.restarts = 0
        self.note = ""
        """Why the last CPU process was ended (one line)."""
        self._fd = os.memfd_create("s7graph-scan-marks")
        os.ftruncate(self._fd, MARKS_SIZE)
        self._page = mmap.mmap(self._fd, MARKS_SIZE)
        self._view = memoryview(self._page)
        self.marks = MarkReader(self._view)
        self._proc: subprocess.Popen[bytes] | None = None
        self._stop_at: float | None = None
        self._killed = False
        self._recovering = False
        self._pending: int | None = None
        """A signal that came between two CPUs: for the next, once its loop runs."""

    def run(self) -> int:
        """Supervise until the CPU ends; its exit status (``EXIT_HUNG``: killed after a stop
        request it could not answer)."""
        _prctl(_PR_SET_CHILD_SUBREAPER, 1)
        handlers = {
            sig: signal.signal(sig, self._on_signal) for sig in (signal.SIGTERM, signal.SIGINT)
        }
        recovered: tuple[str, str] | None = None
        try:
            while True:
                proc = self._spawn(recovered)
                outcome = self._watch(proc)
                self._end_orphans()
                if isinstance(outcome, int):
                    return outcome if outcome >= 0 else _die_as(-outcome)
                recovered = outcome
                print(
                    f"s7graph: error: {self.note}; starting it again in STOP",
                    file=sys.stderr,
                    flush=True,
                )
                self.restarts += 1
        finally:
            for sig, handler in handlers.items():
                signal.signal(sig, handler)
            self.marks.release()
            self._view.release()
            self._page.close()
            os.close(self._fd)

    def _spawn(self, recovered: tuple[str, str] | None) -> subprocess.Popen[bytes]:
        self._page[:] = bytes(MARKS_SIZE)
        env = dict(os.environ, **{MARKS_ENV: str(self._fd)})
        env.pop(RECOVER_ENV, None)
        if recovered is not None:
            env[RECOVER_ENV] = _SEP.join(recovered)
        self._killed = False
        self._recovering = recovered is not None
        self._proc = subprocess.Popen(
            [sys.executable, "-m", "s7graph", *self.args],
            env=env,
            pass_fds=(self._fd,),
            preexec_fn=functools.partial(die_with_parent, os.getpid()),
        )
        return self._proc

    def _watch(self, proc: subprocess.Popen[bytes]) -> int | tuple[str, str]:
        """Until ``proc`` ends: its exit status, or (place, cause) to start it again in STOP."""
        while True:
            code = proc.poll()
            if code is not None:
                return self._ended(code)
            time.sleep(POLL_S)  # one wake-up per look (Popen.wait polls far more often)
            now = time.monotonic()
            if self._pending is not None and self.marks.max_cycle_ns:  # its handlers are in
                signum, self._pending = self._pending, None
                self._stop_at = now
                with contextlib.suppress(ProcessLookupError):
                    proc.send_signal(signum)
            if self._stop_at is not None:
                if now - self._stop_at >= GRACE_S + STOP_EXTRA_S:
                    self._kill(proc)
                    waited = GRACE_S + STOP_EXTRA_S
                    print(
                        f"s7graph: error: the CPU did not end within {waited:g} s of the "
                        "stop request (a hang in C code?): killed; the state is the last "
                        "durable scan's",
                        file=sys.stderr,
                        flush=True,
                    )
                    return EXIT_HUNG
                continue
            hung = self._hung(time.monotonic_ns())
            if hung is not None:
                self._kill(proc)
                return hung

    def _hung(self, now_ns: int) -> tuple[str, str] | None:
        marks = self.marks
        since, max_ns = marks.busy_since_ns, marks.max_cycle_ns
        if not since or not max_ns:
            return None
        elapsed = now_ns - since
        if elapsed < 2 * max_ns + self.kill_after_s * 1e9:
            return None
        section, block = marks.section, marks.block
        if section and section != "scan":
            place = section
            where = f"in {section}" + (f" (block {block})" if block else "")
        else:
            place = block or "CPU"
            where = f"in {block}" if block else "between blocks"
        self.note = f"the scan hung {where} for {elapsed / 1e9:.1f} s: the CPU's process was killed"
        cause = (
            f"no scan ended for {elapsed / 1e9:.1f} s: hung {where} past twice the maximum "
            f"cycle time ({_ms(2 * max_ns)}), in code the in-process abort cannot stop (C "
            "code); the CPU's process was killed and started again in STOP from its last "
            "durable state"
        )
        return place, cause

    def _ended(self, code: int) -> int | tuple[str, str]:
        if code >= 0 or self._stop_at is not None or self.marks.scans == 0:
            return code
        try:
            name = signal.Signals(-code).name
        except ValueError:
            name = f"signal {-code}"
        place = self.marks.section if self.marks.section not in ("", "scan") else self.marks.block
        self.note = f"the CPU's process ended by {name}" + (f" in {place}" if place else "")
        cause = f"{self.note}: started again in STOP from its last durable state"
        return place or "CPU", cause

    def _kill(self, proc: subprocess.Popen[bytes]) -> None:
        self._killed = True
        with contextlib.suppress(ProcessLookupError):
            proc.kill()
        proc.wait()

    def _on_signal(self, signum: int, frame: FrameType | None) -> None:
        proc = self._proc
        listening = not self._recovering or self.marks.max_cycle_ns  # its loop runs
        if proc is None or self._killed or not listening or proc.poll() is not None:
            self._pending = signum  # between two CPUs, or the next not listening yet
            return
        if self._stop_at is None:
            self._stop_at = time.monotonic()
        with contextlib.suppress(ProcessLookupError):
            proc.send_signal(signum)

    def _end_orphans(self) -> None:
        """End what the last CPU started (its view, now this process's child) and reap it."""
        mine = os.getpid()
        orphans = _children_of(mine)
        for pid in orphans:
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGTERM)
        deadline = time.monotonic() + END_VIEW_S
        for pid in orphans:
            while True:
                try:
                    done, _ = os.waitpid(pid, os.WNOHANG)
                except ChildProcessError:
                    break
                if done:
                    break
                if time.monotonic() > deadline:
                    with contextlib.suppress(ProcessLookupError):
                        os.kill(pid, signal.SIGKILL)
                time.sleep(0.02)


def _die_as(signum: int) -> int:
    """End as the CPU ended, by signal ``signum`` (128 + it if that does not end us)."""
    with contextlib.suppress(ValueError, OSError):
        signal.signal(signum, signal.SIG_DFL)
        os.kill(os.getpid(), signum)
    return 128 + signum


def _children_of(parent: int) -> list[int]:
    """The processes whose parent is ``parent`` (Linux ``/proc``), else none."""
    found: list[int] = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
        except OSError:
            continue
        fields = stat.rsplit(")", 1)[-1].split()
        if len(fields) > 1 and fields[1] == str(parent):
            found.append(int(entry.name))
    return found


def supervises(*, as_program: bool) -> bool:
    """Whether a ``run`` becomes the supervisor of a CPU process of its own: started as the
    program (not called from Python), on Linux, not yet the supervised CPU itself."""
    return as_program and hasattr(os, "memfd_create") and MARKS_ENV not in os.environ


def supervise(args: Sequence[str]) -> int:
    """``s7graph <args>`` (a ``run``) as the supervised child of this process."""
    return Supervisor(args).run()
