"""A CPU's end of the bus and a browser view beside it, in one process.

:class:`WebEdge` starts the CPU's :class:`CpuSide` and a :class:`ViewSide` connecting to
it; ``serve_view(chart, updates)`` starts both and publishes a feed of scans (the tests and
the demos; ``s7graph run --web`` in one process goes through ``web.wiring.live_edge``).
"""

from __future__ import annotations

import threading
import time
from collections.abc import Iterable
from typing import TYPE_CHECKING

from s7graph.sequencer.text.model import Chart
from s7graph.web.bus.cpu_side import CpuSide
from s7graph.web.bus.gate import Apply, Gate
from s7graph.web.bus.protocol import ChartLayout, Command, StepStateUpdate
from s7graph.web.bus.session import BusEnds

if TYPE_CHECKING:
    from s7graph.web.view.edge import ViewSide

__all__ = ["WebEdge", "serve_view"]


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
            from s7graph.web.view.edge import ViewSide  # viser: only in a process that serves

            connect = list(ends.connect) or [self.endpoint]
            self.view_side: ViewSide = ViewSide(
                cpu=cpu,
                fb=self.fb,
                ends=ends.joining(connect),
                host=host,
                port=port,
                allowed_origins=allowed_origins,
            )
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
        chart,
        host=host,
        port=port,
        cpu=cpu,
        fb=fb,
        endpoint=endpoint,
        ends=ends,
        gate=gate,
        allowed_origins=allowed_origins,
    )
    if updates_source is not None:
        edge.pump(updates_source, apply_command)
    return edge
