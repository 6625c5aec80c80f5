"""The processor kept for the scan: the scan thread on one core, everything else off it.

S7-1500 software controllers (CPU 1507S, 1508S) run the PLC on processor cores set aside
for it, the PC's other software on the rest; a soft PLC sharing every core with its own
view, bus and writer finds them on its processor when a scan falls due, and a real-time
thread on a kernel that is not fully preemptible waits for them to leave it. Measured with
200 sequencers under a command flood on 2 cores (``bench/jitter.py``): the scan thread
waited for a processor 0.46 ms per cycle on average sharing both cores, 0.11-0.14 ms with
one kept for it.

``--core`` (``CPU = {"core": ...}`` in a program) says which:

- ``auto`` (the default): the last processor this process may use that no other CPU on the
  machine keeps (never the first), when the scan runs real-time and the process may use
  two or more; otherwise none (a scan at the normal priority is better off free to move to
  whichever processor is idle);
- a processor number: that one (real-time or not), even if another CPU keeps it;
- ``off``: none; every thread may run anywhere.

:func:`kept_free` (the chart runner, before the bus and the view start: threads and
processes inherit it) moves the calling thread off the kept core; the runner then puts its
scan thread on it and the process's other threads on the rest while its loop runs
(``engine/runner.py``), and gives every thread the whole set back when it ends. Processes
other than s7graph's may still run there: a machine that must keep the core for the scan
alone says so to the kernel (``isolcpus=``).

Two CPUs on one machine never keep the same processor by ``auto`` (:class:`CoreClaims`): a
CPU claims the processor it keeps with a lock on a file per processor, which the kernel
lets go of when the process ends however it ends (SIGKILL included). Both scan threads
real-time at one priority on one processor, the one whose scan hung in C code would keep
it from the other until its supervisor killed it, and every long scan of one would delay
the other's — as an S7-1500 software controller gives each CPU instance cores of its own.
For the same reason a CPU's other threads stay off the processors other CPUs keep
(:meth:`CoreClaims.kept_elsewhere`, :func:`rest_of`), beside its own scan when no other
processor is left.
"""

from __future__ import annotations

import functools
import os
import tempfile
from collections.abc import Iterator, Set
from contextlib import contextmanager
from pathlib import Path

from s7graph.engine.file_lock import try_lock

__all__ = [
    "CoreClaims",
    "allowed_cpus",
    "kept_free",
    "machine_claims",
    "others",
    "pin",
    "rest_of",
    "scan_core",
]


def allowed_cpus() -> set[int]:
    """The processors this thread may run on (all of them where the system does not say)."""
    try:
        return set(os.sched_getaffinity(0))
    except (OSError, AttributeError):  # not Linux
        return set(range(os.cpu_count() or 1))


class CoreClaims:
    """The processors the CPUs on this machine keep: one lock file per processor in
    ``folder``, locked (``flock``) by the process that keeps it for as long as it lives or
    until :meth:`release` (``engine.file_lock``). Where the folder cannot be used or the
    file system has no such locks, every claim is granted (there is nothing to agree with)."""

    def __init__(self, folder: Path) -> None:
        self.folder = folder
        self._held: dict[int, int] = {}  # processor -> the locked file's descriptor

    def take(self, core: int) -> bool:
        """Claim ``core`` for this process: True if it holds it now (or did already), False
        if another process holds it."""
        if core in self._held:
            return True
        try:
            fd = os.open(self._file(core), os.O_RDWR | os.O_CREAT, 0o666)
        except OSError:
            return True
        locked = try_lock(fd)
        if locked is not True:  # held elsewhere; or a file system without locks: granted
            os.close(fd)
            return locked is None
        os.ftruncate(fd, 0)
        os.write(fd, f"{os.getpid()}\n".encode())
        self._held[core] = fd
        return True

    def _file(self, core: int) -> Path:
        """The lock file of ``core``, its folder made open to every user of the machine
        (sticky, as ``/tmp``: the CPUs of several users agree on the processors too)."""
        if not self.folder.is_dir():
            self.folder.mkdir(parents=True, exist_ok=True)
            self.folder.chmod(0o1777)
        path = self.folder / f"core-{core}.lock"
        if not path.exists():
            path.touch()
            path.chmod(0o666)
        return path

    def held(self) -> frozenset[int]:
        """The processors this process holds."""
        return frozenset(self._held)

    def holder(self, core: int) -> int | None:
        """The process that last claimed ``core`` (its pid as it wrote it), or None."""
        try:
            text = (self.folder / f"core-{core}.lock").read_text()
        except OSError:
            return None
        return int(text) if text.strip().isdigit() else None

    def kept_elsewhere(self, cores: set[int]) -> frozenset[int]:
        """The processors of ``cores`` another process keeps now: their lock files locked
        by another pid in the kernel's list of locks (``/proc/locks``; read, not probed by
        locking, so a CPU starting meanwhile is never refused). Empty where there is no
        such list."""
        try:
            locks = Path("/proc/locks").read_text()
        except OSError:
            return frozenset()
        mine = str(os.getpid())
        locked = set()
        for line in locks.splitlines():  # "1: FLOCK  ADVISORY  WRITE 1234 fe:00:5678 0 EOF"
            words = line.split()
            if len(words) >= 6 and words[1] == "FLOCK" and words[4] != mine:
                device, _, inode = words[5].rpartition(":")
                if inode.isdigit():
                    locked.add((device, int(inode)))
        kept = set()
        for core in cores:
            try:
                st = (self.folder / f"core-{core}.lock").stat()
            except OSError:
                continue
            device = f"{os.major(st.st_dev):02x}:{os.minor(st.st_dev):02x}"
            if (device, st.st_ino) in locked:
                kept.add(core)
        return frozenset(kept)

    def release(self, core: int | None) -> None:
        """Let ``core`` go, if this process holds it (the lock goes with its file)."""
        fd = self._held.pop(core, None) if core is not None else None
        if fd is not None:
            os.close(fd)


@functools.cache
def machine_claims() -> CoreClaims:
    """The claims of every s7graph CPU of this machine (in the system's temporary folder)."""
    return CoreClaims(Path(tempfile.gettempdir()) / "s7graph-cores")


def scan_core(
    choice: str | int | None,
    *,
    realtime: bool,
    allowed: set[int] | None = None,
    claims: CoreClaims | None = None,
) -> int | None:
    """The processor kept for the scan for ``choice`` (``auto``/None, ``off``, or a number as
    an int or a string), the scan running ``realtime`` or not, among ``allowed`` (default:
    this thread's); None: no processor kept. With ``claims``, ``auto`` takes the last one
    it can claim but the first (none if it claims none), and a number is claimed if it can
    be. ValueError naming the choice and the processors there are for one that cannot be."""
    pool = sorted(allowed_cpus() if allowed is None else allowed)
    if choice is None or choice == "auto":
        if not realtime or len(pool) < 2:
            return None
        if claims is None:
            return pool[-1]
        return next((core for core in reversed(pool[1:]) if claims.take(core)), None)
    if choice == "off":
        return None
    if isinstance(choice, bool) or not (
        isinstance(choice, int) or (isinstance(choice, str) and choice.isdigit())
    ):
        raise ValueError(f"core {choice!r} is none of auto, off or a processor number")
    core = int(choice)
    if core not in pool:
        there = ", ".join(map(str, pool))
        raise ValueError(f"core {core} is not a processor this process may use ({there})")
    if claims is not None:
        claims.take(core)  # so that a CPU started with auto leaves it
    return core


def others(core: int, allowed: set[int] | None = None, kept: Set[int] = frozenset()) -> set[int]:
    """The processors for a CPU's threads but its scan: those of ``allowed`` but ``core``
    and the ``kept`` ones other CPUs keep; when that leaves none, ``core`` itself (a
    processor another CPU keeps is free only while that CPU's scan sleeps, never while it
    hangs in C code; this CPU's own scan leaves ``core`` between scans); all of ``allowed``
    when ``core`` is the only one."""
    pool = allowed_cpus() if allowed is None else allowed
    return pool - {core} - set(kept) or pool & {core} or set(pool)


def rest_of(core: int, everywhere: set[int]) -> set[int]:
    """Where a CPU that keeps ``core`` runs its other threads and processes: :func:`others`
    of ``everywhere``, the processors the other CPUs of this machine keep now left out
    (``machine_claims``)."""
    return others(core, everywhere, machine_claims().kept_elsewhere(everywhere))


def pin(cpus: set[int], tid: int = 0) -> bool:
    """Let thread ``tid`` (a native id; 0: the calling thread) run on ``cpus`` only; False
    when the system refuses (or the thread is gone)."""
    try:
        os.sched_setaffinity(tid, cpus)
    except (OSError, AttributeError, ValueError):
        return False
    return True


@contextmanager
def kept_free(core: int | None) -> Iterator[None]:
    """The calling thread, and so the threads and processes it starts meanwhile, off
    ``core`` (nothing for None); its processors back at the end, and this process's claim on
    ``core`` (``machine_claims``) let go."""
    if core is None:
        yield
        return
    before = allowed_cpus()
    everywhere = before | {core}
    moved = pin(rest_of(core, everywhere))
    try:
        yield
    finally:
        if moved:
            pin(before)
        machine_claims().release(core)
