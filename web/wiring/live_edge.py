"""``s7graph run CHART``'s edges around the real scan loop: the CPU's bus, the recording,
and the browser view when it runs in the same process.

:class:`LiveEdge` is the :class:`~web.bus.scan_edge.ScanEdge` of one
:class:`~web.bus.live.LiveGraph` (called back after each scan, in the scan thread) with
what it publishes to: the CPU's end of the bus alone (``bus``: a :class:`CpuSide`, for a
view in its own process or elsewhere on the bus), or with a view beside it (``serve``: a
:class:`WebEdge`, a CPU-side and a view-side zenoh session, a viser server on
127.0.0.1), and the rerun ``.rrd`` recording (``record``).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from s7graph.web.bus.cpu_side import CpuSide
from s7graph.web.bus.gate import Gate
from s7graph.web.bus.live import LiveGraph
from s7graph.web.bus.publisher import BusPublisher
from s7graph.web.bus.scan_edge import ScanEdge
from s7graph.web.bus.session import BusEnds
from s7graph.web.wiring.web_edge import WebEdge, serve_view

if TYPE_CHECKING:
    from s7graph.engine.cpu import Cpu
    from s7graph.web.bus.forcing import Forcing
    from s7graph.web.bus.online import OnlineChange
    from s7graph.web.bus.operands import OperandFeed

__all__ = ["LiveEdge"]


class LiveEdge(ScanEdge):
    """The view and bus (``serve``), or the bus alone (``bus``), and the recording
    (``record``) of one running GraphFB; close it when done. ``cpu_of``: the CPU whose
    diagnostic buffer and memory the bus serves (default: the force table's)."""

    def __init__(
        self,
        live: LiveGraph,
        *,
        host: str = "127.0.0.1",
        port: int = 8080,
        cpu: str = "cpu1",
        record: Path | None = None,
        endpoint: str | None = None,
        serve: bool = True,
        ends: BusEnds | None = None,
        gate: Gate | None = None,
        allowed_origins: tuple[str, ...] = (),
        bus: bool = False,
        online: OnlineChange | None = None,
        forcing: Forcing | None = None,
        cpu_of: Cpu | None = None,
        operands: OperandFeed | None = None,
    ) -> None:
        self.edge: WebEdge | None = None
        self.cpu_side: CpuSide | None = None
        publisher: BusPublisher | None = None
        if serve:
            self.edge = serve_view(
                live.layout,
                None,
                host=host,
                port=port,
                cpu=cpu,
                endpoint=endpoint,
                ends=ends,
                gate=gate,
                allowed_origins=allowed_origins,
            )
            publisher = self.edge.publisher
        elif bus:
            self.cpu_side = CpuSide(
                {live.fb: live.layout}, cpu=cpu, ends=ends or BusEnds(), gate=gate
            )
            publisher = self.cpu_side.publisher
        super().__init__(
            live, publisher, online=online, forcing=forcing, cpu=cpu_of, operands=operands
        )
        try:
            if record is not None:
                from s7graph.web.recorder import Recorder  # rerun-sdk only when recording

                self.recorder = Recorder(live.layout, record)
        except BaseException:
            self.close()
            raise
        self.url = self.edge.url if self.edge is not None else ""
        self.endpoint = (
            self.edge.endpoint
            if self.edge is not None
            else self.cpu_side.endpoint
            if self.cpu_side is not None
            else ""
        )

    def close(self) -> None:
        """Close the recording, the view, the bus and both zenoh sessions."""
        super().close()
        if self.edge is not None:
            self.edge.close()
            self.edge = None
        if self.cpu_side is not None:
            self.cpu_side.close()
            self.cpu_side = None
        self.publisher = None

    def __enter__(self) -> LiveEdge:
        return self
