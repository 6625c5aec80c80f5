"""``s7graph run PROGRAM --listen/--connect``: a program of blocks on the bus.

:class:`ProgramEdge` is the :class:`~web.bus.scan_edge.CpuEdge` of a CPU without a GRAPH FB,
with its own end of the bus (a :class:`CpuSide` serving no chart): ``status`` with the
STOP's reason, the diagnostic buffer (``diag``), the message list of its ALARM_S and
ALARM_SQ calls (``alarms``, ``alarms/list``, acknowledged by ``ack_msg``), the force table
(``force``, ``forces``), the RUN/STOP switch and the memory reset (``stop``, ``start``,
``mres``), the watch of addresses and DB variables (``watch``), logins and the audit —
everything a chart's CPU serves but its FB. The runner calls
:meth:`~web.bus.scan_edge.CpuEdge.on_record` after each scan, in the scan thread.
"""

from __future__ import annotations

from s7graph.engine.cpu import Cpu
from s7graph.sfb.alarms import message_list
from s7graph.web.bus.cpu_side import CpuSide
from s7graph.web.bus.forcing import Forcing
from s7graph.web.bus.gate import Gate
from s7graph.web.bus.scan_edge import CpuEdge
from s7graph.web.bus.session import BusEnds

__all__ = ["ProgramEdge"]


class ProgramEdge(CpuEdge):
    """``cpu`` on the bus as ``name`` at ``ends`` (a unix socket of its own by default),
    commands through ``gate``; close it when done."""

    def __init__(
        self,
        cpu: Cpu,
        *,
        name: str = "cpu1",
        ends: BusEnds | None = None,
        gate: Gate | None = None,
    ) -> None:
        self.cpu_side: CpuSide | None = CpuSide({}, cpu=name, ends=ends or BusEnds(), gate=gate)
        try:
            super().__init__(
                self.cpu_side.publisher, forcing=Forcing(cpu), cpu=cpu, messages=message_list(cpu)
            )
        except BaseException:
            self.cpu_side.close()
            raise
        self.endpoint = self.cpu_side.endpoint

    def close(self) -> None:
        """Close the bus and its zenoh session."""
        super().close()
        if self.cpu_side is not None:
            self.cpu_side.close()
            self.cpu_side = None
        self.publisher = None

    def __enter__(self) -> ProgramEdge:
        return self
