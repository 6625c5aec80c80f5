"""How ``s7graph watch`` and ``watch --address`` meet their CPU at start: one that is not
there yet — no CPU of that name runs on this machine, nothing answers at ``--connect``, or
the bus has no such CPU — is waited for, as a CPU that goes while watched is. The watch
says once on stderr that it waits and where (``s7graph: waiting for CPU cpu1 at
tcp/127.0.0.1:7461 (nothing answers there yet)``), tries again every half second and goes
on when the CPU answers; Ctrl-C or SIGTERM end the wait (exit 0), ``--duration-s`` too,
with exit 2 and why (``CPU cpu1 did not appear … within 5 s``). Wrong options, a bus that
refuses this node for another reason or a node that is not the CPU stay an error at once.
:func:`join_bus` is how every shell command joins the bus; those that do not wait say
:class:`Absent`'s ``message`` and end.
"""

from __future__ import annotations

import contextlib
import signal
import sys
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass

import zenoh

from s7graph.web.bus import local
from s7graph.web.bus.client import BusClient
from s7graph.web.bus.keys import ROOT
from s7graph.web.bus.protocol import CpuStatus
from s7graph.web.bus.session import open_session, peer_problem
from s7graph.web.cli.net import NetOptions

__all__ = ["POLL_S", "Absent", "Reached", "cpu_reached", "join_bus"]

POLL_S = 0.5
"""How often a watch that waits for its CPU tries again."""
_PROBE_S = 1.0
"""How long one try waits for the CPU's status."""


@dataclass(frozen=True, slots=True)
class Absent:
    """The CPU is not reachable (yet): where it is looked for (``where``), why it is not
    there in a few words (``why``), and what a command that does not wait says."""

    where: str
    why: str
    message: str


def join_bus(net: NetOptions) -> zenoh.Session | Absent | str:
    """A session on the bus of ``net`` (connecting only); :class:`Absent` when the CPU is
    not there (no CPU of that name on this machine, nothing answers at ``--connect``), or
    why the options or the bus are wrong."""
    problem = net.problem(listening=False)
    if problem:
        return problem
    connect = list(net.connect)
    if not connect:
        here = local.find(net.cpu)  # a CPU of this machine (web.bus.local)
        if here is None:
            return Absent(
                f"{ROOT}/{net.cpu} on this machine",
                f"no CPU {net.cpu} runs here for this user yet",
                f"give the bus with --connect ENDPOINT (no CPU {net.cpu} runs on this "
                "machine for this user)",
            )
        connect = [here]
    try:
        session = open_session(connect=connect, tls=net.tls, login=net.login)
    except Exception as exc:
        if net.unreached(exc):
            ends = ", ".join(connect)
            return Absent(ends, "nothing answers there yet", net.join_error(exc))
        return net.join_error(exc)
    wrong = peer_problem(session, net.cpu)
    if wrong is not None:
        session.close()  # type: ignore[no-untyped-call]  # zenoh's stub
        return wrong
    return session


@dataclass(frozen=True, slots=True)
class Reached:
    """The CPU answered: a client of it (``waited``: only after a wait, said on stderr),
    its status, and what is left of ``--duration-s`` (None: no limit)."""

    client: BusClient
    status: CpuStatus
    waited: bool
    left_s: float | None


@contextlib.contextmanager
def cpu_reached(net: NetOptions, duration_s: float | None) -> Iterator[Reached | int]:
    """A client of ``net.cpu`` once it answers (its session closed after), or the exit
    status when the watch ends before: 0 stopped (Ctrl-C, SIGTERM), 2 an error or
    ``duration_s`` over (the reason printed)."""
    deadline = None if duration_s is None else time.monotonic() + duration_s
    stop = threading.Event()
    previous = signal.signal(signal.SIGTERM, lambda *_: stop.set())
    waiter = _Waiter(net, deadline, duration_s, stop)
    try:
        got = waiter.reach()
    except KeyboardInterrupt:
        got = 0
    finally:
        signal.signal(signal.SIGTERM, previous)
    if isinstance(got, int):
        yield got
        return
    session, status = got
    left = None if deadline is None else max(deadline - time.monotonic(), 0.0)
    try:
        with BusClient(session, net.cpu) as client:
            yield Reached(client, status, waiter.said, left)
    finally:
        session.close()  # type: ignore[no-untyped-call]  # zenoh's stub


class _Waiter:
    """Tries to reach ``net.cpu`` until it answers, ``stop`` or ``deadline``."""

    def __init__(
        self,
        net: NetOptions,
        deadline: float | None,
        duration_s: float | None,
        stop: threading.Event,
    ) -> None:
        self.net, self.deadline, self.duration_s, self.stop = net, deadline, duration_s, stop
        self.said = False
        self.where = ""

    def reach(self) -> tuple[zenoh.Session, CpuStatus] | int:
        """(a session the CPU answers on, its status), or the exit status."""
        while True:
            got = join_bus(self.net)
            if isinstance(got, str):
                return _fail(got)
            if isinstance(got, Absent):
                self._say(got.where, got.why)
            else:
                reached = self._answered(got)
                if reached:
                    return reached
                got.close()  # type: ignore[no-untyped-call]  # zenoh's stub
            ended = self._pause()
            if ended is not None:
                return ended

    def _answered(self, session: zenoh.Session) -> tuple[zenoh.Session, CpuStatus] | None:
        """(``session``, the CPU's status) when it answers; None when it does not (said
        once)."""
        with BusClient(session, self.net.cpu, timeout=_PROBE_S) as probe:
            status = probe.status()
        if status is not None:
            return session, status
        ends = ", ".join(self.net.connect) or "this machine"
        self._say(f"{ROOT}/{self.net.cpu} on {ends}", "not on the bus yet")
        return None

    def _say(self, where: str, why: str) -> None:
        if not self.said:
            print(f"s7graph: waiting for CPU {self.net.cpu} at {where} ({why})", file=sys.stderr)
            self.said, self.where = True, where

    def _pause(self) -> int | None:
        """Wait before the next try; the exit status when the watch ends meanwhile."""
        wait = POLL_S
        if self.deadline is not None:
            wait = min(wait, self.deadline - time.monotonic())
        if wait > 0 and self.stop.wait(wait):
            return 0
        if self.deadline is not None and time.monotonic() >= self.deadline:
            return _fail(
                f"CPU {self.net.cpu} did not appear at {self.where} within "
                f"{self.duration_s:g} s (--duration-s)"
            )
        return None


def _fail(message: str) -> int:
    print(f"s7graph: error: {message}", file=sys.stderr)
    return 2
