"""Wire a chart, a feed of scans, the bus and the browser view together.

``serve_view(chart, updates)`` opens two loopback zenoh sessions — the CPU's and the
view's — so the view reaches the CPU only over the bus, the same path a remote view takes.
"""

from __future__ import annotations

import contextlib
import shutil
import tempfile
import threading
import time
from collections.abc import Callable, Iterable

from s7graph.sequencer.model import Chart
from s7graph.web.bus.protocol import ChartLayout, Command, StepStateUpdate
from s7graph.web.bus.zenoh_bus import BusClient, BusPublisher, open_session
from s7graph.web.view.chart_view import ChartView, make_server

__all__ = ["WebEdge", "serve_view"]

Apply = Callable[[Command], tuple[bool, str]]


class WebEdge:
    """A running view: ``publisher`` is the CPU's side of the bus, ``url`` the page."""

    def __init__(
        self,
        chart: Chart | ChartLayout,
        *,
        host: str,
        port: int,
        cpu: str,
        fb: str | None,
        endpoint: str | None,
    ) -> None:
        layout = chart if isinstance(chart, ChartLayout) else ChartLayout.from_chart(chart, fb=fb)
        self.fb = layout.fb
        self._tmp = None if endpoint else tempfile.mkdtemp(prefix="s7graph-bus-")
        self.endpoint = endpoint or f"unixsock-stream/{self._tmp}/bus.sock"
        self._stop = threading.Event()
        self._pump: threading.Thread | None = None
        self._closers: list[Callable[[], object]] = []
        try:
            cpu_session = open_session(listen=[self.endpoint])
            self._closers.append(cpu_session.close)
            self.publisher = BusPublisher(cpu_session, cpu, {self.fb: layout})
            self._closers.append(self.publisher.close)
            view_session = open_session(connect=[self.endpoint])
            self._closers.append(view_session.close)
            self.client = BusClient(view_session, cpu)
            self._closers.append(self.client.close)
            seen = self._wait_for_chart()
            self.server = make_server(host, port)
            self._closers.append(self.server.stop)
            self.view = ChartView(self.server, seen, self.client.send)
            self._closers.append(self.view.close)
            self.follower = self.client.follow(self.fb, self.view.apply)
            self.client.on_status(self.view.apply_status)
            self.client.on_alarms(self.view.apply_alarms)
        except BaseException:
            self.close()
            raise
        self.url = f"http://{host}:{self.server.get_port()}/"

    def _wait_for_chart(self, timeout: float = 5.0) -> ChartLayout:
        deadline = time.monotonic() + timeout
        while True:
            layout = self.client.chart(self.fb)
            if layout is not None:
                return layout
            if time.monotonic() > deadline:
                raise TimeoutError(f"no chart for FB {self.fb!r} on the bus within {timeout:g} s")
            time.sleep(0.05)

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
        while self._closers:
            with contextlib.suppress(Exception):  # keep closing the rest
                self._closers.pop()()
        if self._tmp:
            shutil.rmtree(self._tmp, ignore_errors=True)

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
) -> WebEdge:
    """Serve the browser view of ``chart`` and return the running edge (close it when done).

    ``updates_source`` yields one :class:`StepStateUpdate` per scan (it may block to pace
    the scans); between two of them, ``apply_command(command) -> (applied, reason)`` runs
    for each command from the view — a scan boundary when the iterator runs the scan. With
    ``updates_source=None`` the caller drives ``edge.publisher`` itself. ``endpoint`` is the
    bus's listen endpoint (default: a unix socket in a temporary directory)."""
    edge = WebEdge(chart, host=host, port=port, cpu=cpu, fb=fb, endpoint=endpoint)
    if updates_source is not None:
        edge.pump(updates_source, apply_command)
    return edge
