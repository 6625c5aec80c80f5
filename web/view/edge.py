"""Wire a chart, a feed of scans, the bus and the browser view together.

:class:`CpuSide` is the CPU's end of the bus: a zenoh session listening on (or connecting
to) the given endpoints — a unix socket in a temporary folder by default — and its
:class:`BusPublisher` with the :class:`Gate`. :class:`ViewSide` is a view's end: its own
session connecting to the bus, a :class:`BusClient`, a viser server and the
:class:`ChartView` — all it knows of the CPU comes over the bus, so it runs as well in
another process (``s7graph web``) as beside the CPU (``s7graph run --web``).
``serve_view(chart, updates)`` starts both, as ``run --web`` does.
"""

from __future__ import annotations

import contextlib
import shutil
import socket
import tempfile
import threading
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass

from s7graph.sequencer.text.model import Chart
from s7graph.web.bus.gate import Apply, Gate
from s7graph.web.bus.protocol import ChartLayout, Command, CpuStatus, StepStateUpdate
from s7graph.web.bus.zenoh_bus import BusClient, BusPublisher, TlsFiles, open_session
from s7graph.web.view.chart_view import ChartView, make_server
from s7graph.web.view.engineering import Engineering

__all__ = ["BusEnds", "CpuSide", "PortError", "ViewSide", "WebEdge", "check_port", "serve_view"]


ENGINEERING_TIMEOUT_S = 30.0  # a download compiles, writes the file and waits for a scan


class PortError(ValueError):
    """A page port out of range or taken."""


@dataclass(frozen=True, slots=True)
class BusEnds:
    """Where a session meets the bus: endpoints to listen on and to connect to, and TLS."""

    listen: Sequence[str] = ()
    connect: Sequence[str] = ()
    tls: TlsFiles | None = None


def check_port(host: str, port: int) -> None:
    """:class:`PortError` if ``port`` is out of range or taken on ``host`` (0: any free one)."""
    if not 0 <= port <= 65535:
        raise PortError(f"--port {port} is out of range (0-65535; 0 picks a free one)")
    if port == 0:
        return
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    with socket.socket(family, socket.SOCK_STREAM) as s:
        # as the page's server binds: connections of a view that just ended (TIME_WAIT)
        # do not make the port busy, a listening server does
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            s.bind((host, port))
        except OSError as exc:
            raise PortError(f"port {port} on {host} is in use ({exc.strerror})") from None


class CpuSide:
    """The CPU's end of the bus; ``endpoint`` is where a view connects."""

    def __init__(
        self,
        charts: dict[str, ChartLayout],
        *,
        cpu: str,
        ends: BusEnds = BusEnds(),
        gate: Gate | None = None,
    ) -> None:
        self._tmp = None
        listen = list(ends.listen)
        if not listen and not ends.connect:
            self._tmp = tempfile.mkdtemp(prefix="s7graph-bus-")
            listen = [f"unixsock-stream/{self._tmp}/bus.sock"]
        self.endpoint = listen[0] if listen else ends.connect[0]
        self.session = open_session(listen=listen, connect=ends.connect, tls=ends.tls)
        try:
            self.publisher = BusPublisher(self.session, cpu, charts, gate=gate)
        except BaseException:
            self.close()
            raise

    def close(self) -> None:
        with contextlib.suppress(Exception):
            if hasattr(self, "publisher"):
                self.publisher.close()
        with contextlib.suppress(Exception):
            self.session.close()  # type: ignore[no-untyped-call]  # zenoh's stub
        if self._tmp:
            shutil.rmtree(self._tmp, ignore_errors=True)
            self._tmp = None


class ViewSide:
    """A browser view of one FB of ``cpu``, reached over the bus at ``ends.connect``."""

    def __init__(
        self,
        *,
        cpu: str,
        fb: str | None,
        ends: BusEnds,
        host: str = "127.0.0.1",
        port: int = 8080,
        allowed_origins: Iterable[str] = (),
        wait_s: float = 5.0,
    ) -> None:
        self._closers: list[Callable[[], object]] = []
        try:
            check_port(host, port)
            session = open_session(connect=ends.connect, tls=ends.tls)
            self._closers.append(session.close)
            self.session = session
            self.client = BusClient(session, cpu)
            self._closers.append(self.client.close)
            status, layout = self._wait_for_chart(fb, wait_s)
            self.fb = layout.fb
            self.server, guard = make_server(host, port, allowed_origins=allowed_origins)
            self._closers.append(self.server.stop)
            if port and self.server.get_port() != port:  # viser moved on to the next port
                raise PortError(f"port {port} on {host} is in use")
            client = self.client
            name = self.fb
            engineering = Engineering(
                source=lambda: client.source(name),
                project=client.project,
                send=lambda command: client.send(command, timeout=ENGINEERING_TIMEOUT_S),
            )
            self.view = ChartView(
                self.server, layout, client.send, cpu=cpu, guard=guard,
                login=lambda user, password, origin: client.login(user, password, origin=origin),
                logout=lambda token, user, origin: client.logout(token, user=user, origin=origin),
                demo=status is None or status.login == "demo", history=client.history,
                engineering=engineering,
            )  # fmt: skip
            self._closers.append(self.view.close)
            client.on_chart(self.fb, self.view.apply_chart)
            self.follower = client.follow(self.fb, self.view.apply)
            client.on_status(self.view.apply_status)
            client.on_alarms(self.view.apply_alarms)
            client.on_forces(self.view.apply_forces)
            client.on_audit(self.view.apply_audit)
            client.on_alive(self.view.set_connected)
            with contextlib.suppress(Exception):
                listed = client.audit()
                if listed is not None:
                    self.view.apply_audit_list(listed.entries)
        except BaseException:
            self.close()
            raise
        shown = f"[{host}]" if ":" in host else host
        self.url = f"http://{shown}:{self.server.get_port()}/"

    def _wait_for_chart(
        self, fb: str | None, timeout: float
    ) -> tuple[CpuStatus | None, ChartLayout]:
        deadline = time.monotonic() + timeout
        while True:
            status = self.client.status()
            name = fb or (status.fbs[0] if status is not None and status.fbs else None)
            layout = self.client.chart(name) if name else None
            if layout is not None:
                return status, layout
            if time.monotonic() > deadline:
                what = f"FB {fb!r}" if fb else "a CPU with an FB"
                raise TimeoutError(f"no chart for {what} on the bus within {timeout:g} s")
            time.sleep(0.05)

    def close(self) -> None:
        while self._closers:
            with contextlib.suppress(Exception):  # keep closing the rest
                self._closers.pop()()


class WebEdge:
    """A running view beside its CPU: ``publisher`` is the CPU's side of the bus, ``url``
    the page, ``client``/``view``/``follower`` the view's side."""

    def __init__(
        self,
        chart: Chart | ChartLayout,
        *,
        host: str,
        port: int,
        cpu: str,
        fb: str | None,
        endpoint: str | None = None,
        ends: BusEnds | None = None,
        gate: Gate | None = None,
        allowed_origins: Iterable[str] = (),
    ) -> None:
        layout = chart if isinstance(chart, ChartLayout) else ChartLayout.from_chart(chart, fb=fb)
        self.fb = layout.fb
        self._stop = threading.Event()
        self._pump: threading.Thread | None = None
        if ends is None:
            ends = BusEnds(listen=[endpoint] if endpoint else [])
        self.cpu_side = CpuSide({self.fb: layout}, cpu=cpu, ends=ends, gate=gate)
        self.endpoint = self.cpu_side.endpoint
        self.publisher = self.cpu_side.publisher
        try:
            connect = list(ends.connect) or [self.endpoint]
            self.view_side = ViewSide(
                cpu=cpu, fb=self.fb, ends=BusEnds(connect=connect, tls=ends.tls),
                host=host, port=port, allowed_origins=allowed_origins,
            )  # fmt: skip
        except BaseException:
            self.cpu_side.close()
            raise
        self.client = self.view_side.client
        self.view = self.view_side.view
        self.follower = self.view_side.follower
        self.server = self.view_side.server
        self.url = self.view_side.url

    def pump(self, updates: Iterable[StepStateUpdate], apply: Apply | None) -> None:
        """Publish ``updates`` in a thread; between two of them, apply pending commands."""

        def refuse(command: Command) -> tuple[bool, str]:
            return False, "this CPU takes no commands"

        def run() -> None:
            for update in updates:
                if self._stop.is_set():
                    return
                self.publisher.publish(self.fb, update)
                self.publisher.apply_commands(apply or refuse, cycle=update.cycle)

        self._pump = threading.Thread(target=run, name="s7graph-feed", daemon=True)
        self._pump.start()

    def wait(self) -> None:
        """Block until the feed ends or Ctrl-C."""
        try:
            while self._pump is not None and self._pump.is_alive():
                self._pump.join(0.2)
            if self._pump is None:
                while True:
                    time.sleep(1.0)
        except KeyboardInterrupt:
            pass

    def close(self) -> None:
        """Stop the feed, the view, the bus and the server; close both sessions."""
        self._stop.set()
        if self._pump is not None:
            self._pump.join(timeout=2.0)
        self.view_side.close()
        self.cpu_side.close()

    def __enter__(self) -> WebEdge:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def serve_view(
    chart: Chart | ChartLayout,
    updates_source: Iterable[StepStateUpdate] | None,
    *,
    host: str = "127.0.0.1",
    port: int = 8080,
    cpu: str = "cpu1",
    fb: str | None = None,
    apply_command: Apply | None = None,
    endpoint: str | None = None,
    ends: BusEnds | None = None,
    gate: Gate | None = None,
    allowed_origins: Iterable[str] = (),
) -> WebEdge:
    """Serve the browser view of ``chart`` and return the running edge (close it when done).

    ``updates_source`` yields one :class:`StepStateUpdate` per scan (it may block to pace
    the scans); between two of them, ``apply_command(command) -> (applied, reason)`` runs
    for each command from the view that the gate lets through — a scan boundary when the
    iterator runs the scan. With ``updates_source=None`` the caller drives
    ``edge.publisher`` itself. ``endpoint`` (or ``ends``) is where the bus listens
    (default: a unix socket in a temporary directory); ``gate`` who may command (default:
    the demo)."""
    edge = WebEdge(
        chart, host=host, port=port, cpu=cpu, fb=fb, endpoint=endpoint, ends=ends, gate=gate,
        allowed_origins=allowed_origins,
    )  # fmt: skip
    if updates_source is not None:
        edge.pump(updates_source, apply_command)
    return edge
