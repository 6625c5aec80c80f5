"""The CPU's end of the bus: :class:`CpuSide` is a zenoh session listening on (or
connecting to) the given endpoints — a unix socket in a temporary folder by default — and
its :class:`BusPublisher` with the :class:`Gate`.

The session proves the CPU's identity with the credentials of ``ends`` and always runs
zenoh's access control for its own keys (``web.bus.acl``): another node that declares a
queryable, publishes or holds a liveliness token on ``s7graph/<cpu>/…`` through this
session is refused by zenoh, so a login or a command reaches this CPU and nobody else."""

from __future__ import annotations

import contextlib
import shutil
import tempfile

from s7graph.web.bus import local
from s7graph.web.bus.gate import Gate
from s7graph.web.bus.protocol import ChartLayout
from s7graph.web.bus.publisher import BusPublisher
from s7graph.web.bus.session import BusEnds, open_session

__all__ = ["CpuSide"]


class CpuSide:
    """The CPU's end of the bus; ``endpoint`` is where a view connects."""

    def __init__(
        self,
        charts: dict[str, ChartLayout],
        *,
        cpu: str,
        ends: BusEnds = BusEnds(),  # noqa: B008  (frozen: one default shared is safe)
        gate: Gate | None = None,
    ) -> None:
        self._tmp = None
        self._cpu = cpu
        listen = list(ends.listen)
        if not listen and not ends.connect:
            self._tmp = tempfile.mkdtemp(prefix="s7graph-bus-")
            listen = [f"unixsock-stream/{self._tmp}/bus.sock"]
        self.endpoint = listen[0] if listen else ends.connect[0]
        self.session = open_session(
            listen=listen, connect=ends.connect, tls=ends.tls, login=ends.login, guard=(cpu,)
        )
        try:
            self.publisher = BusPublisher(self.session, cpu, charts, gate=gate)
        except BaseException:
            self.close()
            raise
        if self._tmp:  # a shell of this machine finds it without --connect (web.bus.local)
            local.publish(cpu, self.endpoint, keep=local.KEEP_S)

    def close(self) -> None:
        with contextlib.suppress(Exception):
            if hasattr(self, "publisher"):
                self.publisher.close()
        with contextlib.suppress(Exception):
            self.session.close()  # type: ignore[no-untyped-call]  # zenoh's stub
        if self._tmp:
            local.withdraw(self._cpu, self.endpoint)
            shutil.rmtree(self._tmp, ignore_errors=True)
            self._tmp = None
