"""An exclusive lock on a file, taken without waiting: how a process tells the others it
holds something (a state file, a processor kept for a scan) for as long as it lives — the
kernel lets go of an ``flock`` when the last descriptor of the file is closed, the process
ending however it ends (SIGKILL included)."""

from __future__ import annotations

import fcntl

__all__ = ["try_lock"]


def try_lock(fd: int) -> bool | None:
    """Lock the open file ``fd`` (exclusive ``flock``, not waiting): True when this
    descriptor holds it now, False when another holds it, None where the file system has
    no such locks. The descriptor is the caller's to close either way."""
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        return False
    except OSError:
        return None
    return True
