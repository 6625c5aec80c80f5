"""Where the CPUs of this machine listen, for a shell on it (docs/cli.md, "The bus from a
shell").

``s7graph run`` given no ``--listen`` or ``--connect`` listens on a unix socket in a
private temporary folder, and writes that endpoint to ``<cpu>.endpoint`` in a folder of
this user's (``$XDG_RUNTIME_DIR/s7graph``, else ``/tmp/s7graph-<uid>``, mode 0700); a
command given no ``--connect`` (``status``, ``watch``, ``ack`` …) reads it there for its
``--cpu`` — as TIA Portal lists the accessible devices. Only a folder this user owns and
nobody else may enter is read or written; a CPU that ended takes its file away (one
killed leaves it, and the command then says nothing answers there) — only while the file
is still its own. A CPU that publishes with ``keep`` writes its file again, on a slow
timer of its own (never the scan's), when it is gone or names a socket that takes no
connection: two runs of one name, the newer's file is the newer's while it runs, and the
older is found again once it ends."""

from __future__ import annotations

import contextlib
import os
import socket
import tempfile
import threading
from pathlib import Path
from typing import Final

__all__ = ["KEEP_S", "find", "listening", "local_dir", "names", "publish", "withdraw"]

_SUFFIX = ".endpoint"
KEEP_S: Final = 2.0
"""How often a CPU that publishes with ``keep`` looks whether its file is still there."""
_KEEPERS: dict[tuple[str, str], threading.Event] = {}
"""The keepers running, by (cpu, endpoint): set to stop one."""
_WRITING: Final = threading.Lock()
"""Held by a keeper writing and by :func:`withdraw` stopping it: none writes after."""


def local_dir(*, create: bool = False) -> Path | None:
    """This user's folder of endpoints (made with ``create``), or None when there is none
    that only this user may enter."""
    uid = getattr(os, "getuid", lambda: -1)()
    runtime = os.environ.get("XDG_RUNTIME_DIR", "")
    if runtime and Path(runtime).is_dir():
        root = Path(runtime) / "s7graph"
    else:
        root = Path(tempfile.gettempdir()) / f"s7graph-{uid}"
    if create:
        with contextlib.suppress(OSError):
            root.mkdir(mode=0o700, exist_ok=True)
    try:
        st = root.lstat()
    except OSError:
        return None
    if not root.is_dir() or root.is_symlink() or st.st_uid != uid or st.st_mode & 0o077:
        return None  # not ours, or others may enter it: never trusted
    return root


def publish(cpu: str, endpoint: str, *, keep: float = 0.0) -> Path | None:
    """Write ``endpoint`` as where CPU ``cpu`` listens; its file, or None when there is no
    private folder for it (the CPU runs all the same). ``keep``: every so many seconds,
    write it again when it is gone or names a socket that takes no connection, until
    :func:`withdraw`."""
    if keep > 0 and (cpu, endpoint) not in _KEEPERS:
        stop = _KEEPERS[(cpu, endpoint)] = threading.Event()
        name = f"s7graph-endpoint-{cpu}"
        threading.Thread(
            target=_keep, args=(cpu, endpoint, keep, stop), name=name, daemon=True
        ).start()
    return _write(cpu, endpoint)


def _keep(cpu: str, endpoint: str, every: float, stop: threading.Event) -> None:
    """Write CPU ``cpu``'s file again whenever it is gone or names a socket nothing listens
    on (another run of that name ended or was killed); one naming another live run's
    socket is left to it."""
    while not stop.wait(every):
        now = find(cpu, check=False)
        if now != endpoint and (now is None or not listening(now)):
            with _WRITING:
                if not stop.is_set():
                    _write(cpu, endpoint)


def listening(endpoint: str) -> bool:
    """Whether a unix socket endpoint takes a connection (one a killed CPU left does not);
    any other endpoint is taken as listening."""
    path = endpoint.removeprefix("unixsock-stream/")
    if path == endpoint:
        return True
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as probe:
        probe.settimeout(1.0)
        try:
            probe.connect(path)
        except OSError:
            return False
    return True


def _write(cpu: str, endpoint: str) -> Path | None:
    root = local_dir(create=True)
    if root is None:
        return None
    path = root / f"{cpu}{_SUFFIX}"
    try:
        fd, tmp = tempfile.mkstemp(dir=root, prefix=".ep-")
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(endpoint + "\n")
        os.replace(tmp, path)
    except OSError:
        return None
    return path


def withdraw(cpu: str, endpoint: str) -> None:
    """Stop keeping CPU ``cpu``'s file, and take it away if it still names ``endpoint``
    (another run of that CPU may have written its own since: that one is left)."""
    stop = _KEEPERS.pop((cpu, endpoint), None)
    if stop is not None:
        with _WRITING:
            stop.set()
    if find(cpu, check=False) == endpoint:
        root = local_dir()
        if root is not None:
            with contextlib.suppress(OSError):
                (root / f"{cpu}{_SUFFIX}").unlink()


def find(cpu: str, *, check: bool = True) -> str | None:
    """Where CPU ``cpu`` of this machine listens, or None; with ``check``, a unix socket
    that is gone is no answer."""
    root = local_dir()
    if root is None:
        return None
    try:
        endpoint = (root / f"{cpu}{_SUFFIX}").read_text(encoding="utf-8").strip()
    except (OSError, UnicodeDecodeError):
        return None
    if not endpoint.isprintable() or "/" not in endpoint:
        return None
    socket = endpoint.removeprefix("unixsock-stream/")
    if check and socket != endpoint and not Path(socket).exists():
        return None
    return endpoint


def names() -> list[str]:
    """The CPUs of this machine that wrote where they listen, by name, sorted (whether
    they still listen there: :func:`find`)."""
    root = local_dir()
    if root is None:
        return []
    return sorted(p.name.removesuffix(_SUFFIX) for p in root.glob(f"*{_SUFFIX}"))
