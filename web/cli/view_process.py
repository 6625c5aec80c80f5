"""The browser view of ``s7graph run CHART --web`` as a process of its own.

:class:`ViewProcess` runs ``python -m s7graph web --connect <the CPU's endpoint> --cpu NAME
--port ... --child`` beside the CPU: the view knows the CPU only over the bus, so a page
load, a slow browser or a crash of the view costs the view's process, never a scan. The
child runs in a session of its own (a Ctrl-C at the terminal reaches the CPU, which stops
the view — one line each) and ends by itself when its stdin closes, so a CPU killed with
SIGKILL leaves no view behind.

When the view ends while the CPU runs it is started again after a back-off — 1 s, doubling
up to ``MAX_BACKOFF_S``, back to 1 s once a view has run ``STABLE_S`` — with one line on
stderr each time. The supervising thread only waits on the child's pipes; it never touches
the CPU.
"""

from __future__ import annotations

import contextlib
import os
import re
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from s7graph.web.cli.net import NetOptions

__all__ = [
    "CHILD_NICE",
    "MAX_BACKOFF_S",
    "STABLE_S",
    "ViewProcess",
    "as_child",
    "run_view",
    "view_endpoints",
]

FIRST_BACKOFF_S = 1.0
MAX_BACKOFF_S = 30.0
STABLE_S = 60.0
"""A view that ran this long before it ended is restarted after the first back-off again."""
STOP_GRACE_S = 10.0
_URL = re.compile(r"^s7graph: view (\S+) of ")


def view_endpoints(listen: Sequence[str], connect: Sequence[str]) -> list[str]:
    """Where the view joins the bus of a CPU that listens on ``listen`` (the first, a
    wildcard address made loopback) or connects to ``connect`` (the same router)."""
    if listen:
        proto, _, address = listen[0].partition("/")
        for wildcard, local in (("0.0.0.0", "127.0.0.1"), ("[::]", "[::1]")):
            if address.startswith(wildcard + ":"):
                address = local + address[len(wildcard) :]
        return [f"{proto}/{address}"]
    return list(connect)


def _ended(code: int) -> str:
    if code < 0:
        try:
            return f"killed by {signal.Signals(-code).name}"
        except ValueError:
            return f"killed by signal {-code}"
    return f"exit status {code}"


class ViewProcess:
    """``s7graph web`` for CPU ``cpu`` at ``connect``, kept running until :meth:`stop`.

    ``bus_args``: the credential options the view joins the bus with — the CPU's own
    (``NetOptions.credential_args``: its certificate, or its bus user), so a CPU that lets
    in only nodes with credentials lets its view in.

    ``on_url(url)`` is called (in the supervising thread) each time a view serves its page;
    ``port`` 0 picks a free port the first time and keeps it for the restarts. A subclass
    runs another face so (``web.cli.opcua.OpcuaProcess``): ``what`` it is, the line it
    prints when ready (``ready``, its first group the URL) and its :meth:`command`."""

    what = "view"
    ready: re.Pattern[str] = _URL

    def __init__(
        self,
        *,
        connect: Sequence[str],
        cpu: str,
        host: str = "127.0.0.1",
        port: int = 8080,
        origins: Sequence[str] = (),
        tls_ca: Path | None = None,
        bus_args: Sequence[str] = (),
        on_url: Callable[[str], object] | None = None,
        first_backoff_s: float = FIRST_BACKOFF_S,
    ) -> None:
        self.connect = list(connect)
        self.cpu = cpu
        self.host = host
        self.port = port
        self.origins = list(origins)
        self.tls_ca = tls_ca
        self.bus_args = list(bus_args)
        self.on_url = on_url
        self.first_backoff_s = first_backoff_s
        self.url = ""
        self.starts = 0
        self.pid: int | None = None
        self._stop = threading.Event()
        self._lock = threading.Lock()
        self._proc: subprocess.Popen[str] | None = None
        name = f"s7graph-{self.what.replace(' ', '-')}"
        self._thread = threading.Thread(target=self._supervise, name=name, daemon=True)

    def command(self) -> list[str]:
        """The child's command line."""
        cmd = [
            sys.executable,
            "-m",
            "s7graph",
            "web",
            "--cpu",
            self.cpu,
            "--host",
            self.host,
            "--port",
            str(self.port),
            "--child",
        ]
        for endpoint in self.connect:
            cmd += ["--connect", endpoint]
        for origin in self.origins:
            cmd += ["--origin", origin]
        if self.tls_ca is not None and "--tls-ca" not in self.bus_args:
            cmd += ["--tls-ca", str(self.tls_ca)]
        return cmd + self.bus_args

    def start(self) -> None:
        self._thread.start()

    def stop(self) -> None:
        """End the view (SIGTERM, SIGKILL after ``STOP_GRACE_S``) and its supervision."""
        self._stop.set()
        with self._lock:
            proc = self._proc
        if proc is not None and proc.poll() is None:
            with contextlib.suppress(ProcessLookupError):
                proc.terminate()
            try:
                proc.wait(STOP_GRACE_S)
            except subprocess.TimeoutExpired:
                proc.kill()
        if self._thread.is_alive():
            self._thread.join(STOP_GRACE_S)

    # ---- the supervising thread ----------------------------------------------------------

    def _supervise(self) -> None:
        backoff = self.first_backoff_s
        while not self._stop.is_set():
            started = time.monotonic()
            code = self._run_once()
            if code is None or self._stop.is_set():
                return
            if time.monotonic() - started >= STABLE_S:
                backoff = self.first_backoff_s
            print(
                f"s7graph: the {self.what} process ended ({_ended(code)}); "
                f"restarting it in {backoff:g} s",
                file=sys.stderr,
                flush=True,
            )
            if self._stop.wait(backoff):
                return
            backoff = min(backoff * 2, MAX_BACKOFF_S)

    def _run_once(self) -> int | None:
        """Run one view until it ends; its exit status (None: it could not be started)."""
        with self._lock:
            if self._stop.is_set():
                return None
            try:
                proc = subprocess.Popen(
                    self.command(),
                    stdin=subprocess.PIPE,
                    stdout=subprocess.PIPE,
                    text=True,
                    start_new_session=True,
                )
            except OSError as exc:
                print(f"s7graph: error: cannot start the {self.what}: {exc}", file=sys.stderr)
                return None
            self._proc = proc
            self.pid = proc.pid
            self.starts += 1
        assert proc.stdout is not None
        for line in proc.stdout:  # until the view ends (its stdout closes)
            found = self.ready.match(line)
            if found:
                self._served(found[1])
        proc.stdout.close()
        code = proc.wait()
        if proc.stdin is not None:
            with contextlib.suppress(OSError):
                proc.stdin.close()
        return code

    def _served(self, url: str) -> None:
        self.url = url
        if self.port == 0:
            port = url.rstrip("/").rsplit(":", 1)[-1]
            if port.isdigit():
                self.port = int(port)
        if self.on_url is not None:
            self.on_url(url)


def run_view(net: NetOptions, port: int, bus: str) -> ViewProcess:
    """The page of ``run --web`` as a child process (not started yet): on the CPU's bus
    (``bus``, its endpoint, when it neither listens nor connects elsewhere) with the run's
    own credentials, printing where it serves the first time it does."""
    view: ViewProcess | None = None

    def served(url: str) -> None:
        if view is not None and view.starts == 1:
            print(f"s7graph: view {url} (bus {bus}); Ctrl-C to stop", flush=True)

    view = ViewProcess(
        connect=view_endpoints(net.listen, net.connect) or [bus],
        cpu=net.cpu,
        host=net.host,
        port=port,
        origins=net.origins,
        bus_args=net.credential_args(),
        on_url=served,
    )
    return view


CHILD_NICE = 5
"""How much a ``--child`` view lowers its priority below the CPU's process."""


def as_child(stop: threading.Event) -> None:
    """The view of a ``run --web``: lower its priority, and set ``stop`` when stdin closes
    (the CPU's process ended, even by SIGKILL)."""
    with contextlib.suppress(OSError):
        os.nice(CHILD_NICE)

    def watch() -> None:
        try:  # the raw descriptor: a buffered reader's lock would hold the exit up
            while os.read(0, 4096):
                pass
        except OSError:
            pass
        stop.set()

    threading.Thread(target=watch, name="s7graph-parent", daemon=True).start()
