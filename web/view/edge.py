"""The view's end of the bus: :class:`ViewSide` is a browser view's own session connecting
to the bus, a :class:`BusClient`, a viser server and the :class:`ChartView` (a program's
:class:`ProgramView`), with a Diagnostics folder on every page — all it knows
of the CPU comes over the bus, so it runs as well in another process (``s7graph web``, the
view of ``s7graph run --web``) as beside the CPU (``web.wiring``). Whether the page's
port is free: ``web.view.port``.
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Callable, Iterable

from s7graph.web.bus.client import BusClient
from s7graph.web.bus.protocol import ChartLayout, CpuStatus, ProtocolError
from s7graph.web.bus.session import BusEnds, open_session
from s7graph.web.view import sync_view, watch_table
from s7graph.web.view.chart_view import ChartView, make_server
from s7graph.web.view.diagnostics import DiagnosticsPanel
from s7graph.web.view.engineering import Engineering
from s7graph.web.view.guard import OriginGuard
from s7graph.web.view.port import PortError, check_port
from s7graph.web.view.program_view import ProgramView

__all__ = ["ViewSide"]


ENGINEERING_TIMEOUT_S = 30.0  # a download compiles, writes the file and waits for a scan


class ViewSide:
    """A browser view of one FB of ``cpu``, reached over the bus at ``ends.connect`` — or,
    for a CPU without an FB (a program of blocks), its status, watch table and
    diagnostics (``program``); every page has a Diagnostics folder (``diagnostics``)."""

    view: ChartView
    program: ProgramView | None = None

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
            session = open_session(connect=ends.connect, tls=ends.tls, login=ends.login)
            self._closers.append(session.close)
            self.session = session
            self.client = BusClient(session, cpu)
            self._closers.append(self.client.close)
            status, layout = self._wait_for_chart(fb, wait_s)
            self.server, guard = make_server(host, port, allowed_origins=allowed_origins)
            self._closers.append(self.server.stop)
            if port and self.server.get_port() != port:  # viser moved on to the next port
                raise PortError(f"port {port} on {host} is in use")
            if layout is None:  # a program of blocks: its status, watch table, diagnostics
                self.fb = ""
                self.program = ProgramView(
                    self.server,
                    self.client,
                    cpu=cpu,
                    demo=status is None or status.login == "demo",
                    guard=guard,
                )
                self._closers.append(self.program.close)
            else:
                self._chart_view(cpu, layout, status, guard)
            self.diagnostics = DiagnosticsPanel(
                self.server, self.client, guard=guard, expand=layout is None
            )
            self._closers.append(self.diagnostics.close)
        except BaseException:
            self.close()
            raise
        shown = f"[{host}]" if ":" in host else host
        self.url = f"http://{shown}:{self.server.get_port()}/"

    def _chart_view(
        self, cpu: str, layout: ChartLayout, status: CpuStatus | None, guard: OriginGuard
    ) -> None:
        """The chart's view of the FB ``layout`` draws, following it over the bus."""
        self.fb = layout.fb
        client = self.client
        name = self.fb
        engineering = Engineering(
            source=lambda: client.source(name),
            project=client.project,
            send=lambda command: client.send(command, timeout=ENGINEERING_TIMEOUT_S),
        )
        self.view = ChartView(
            self.server,
            layout,
            client.send,
            cpu=cpu,
            guard=guard,
            login=lambda user, password, origin: client.login(user, password, origin=origin),
            logout=lambda token, user, origin: client.logout(token, user=user, origin=origin),
            demo=status is None or status.login == "demo",
            history=client.history,
            engineering=engineering,
            blocks=client.blocks,
            watch=lambda operands, token: client.watch(
                operands, timeout=watch_table.TIMEOUT_S, token=token
            ),
            sync=lambda: client.synchronization(name, timeout=sync_view.TIMEOUT_S),
        )
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

    def _wait_for_chart(
        self, fb: str | None, timeout: float
    ) -> tuple[CpuStatus | None, ChartLayout | None]:
        """The CPU's status and the chart of ``fb`` (default: its first FB's); no chart for
        a CPU that answers without an FB (a program of blocks) when ``fb`` is not asked."""
        deadline = time.monotonic() + timeout
        problem = ""  # the last answer that could not be read, said when the time is up
        while True:
            status: CpuStatus | None = None
            layout: ChartLayout | None = None
            try:
                status = self.client.status()
                if fb is None and status is not None and not status.fbs:
                    return status, None
                name = fb or (status.fbs[0] if status is not None and status.fbs else None)
                layout = self.client.chart(name) if name else None
            except ProtocolError as exc:
                problem = f" (last answer: {exc})"
            if layout is not None:
                return status, layout
            if time.monotonic() > deadline:
                what = f"FB {fb!r}" if fb else "a CPU with an FB"
                raise TimeoutError(f"no chart for {what} on the bus within {timeout:g} s{problem}")
            time.sleep(0.05)

    def close(self) -> None:
        while self._closers:
            with contextlib.suppress(Exception):  # keep closing the rest
                self._closers.pop()()
