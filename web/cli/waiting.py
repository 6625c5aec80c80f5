"""How ``s7graph watch`` and ``watch --address`` meet their CPU at start: one that is not
there yet — no CPU of that name on this machine's bus, nothing answers at ``--connect``, or
the bus has no such CPU — is waited for, as a CPU that goes while watched is. The watch
says once on stderr that it waits and where (``s7graph: waiting for CPU cpu1 at
tcp/127.0.0.1:7461 (nothing answers there yet)``), tries again every half second and goes
on when the CPU answers; Ctrl-C or SIGTERM end the wait (exit 0), ``--duration-s`` too,
with exit 2 and why (``CPU cpu1 did not appear … within 5 s``). Wrong options, a bus that
refuses this node for another reason or a node that is not the CPU stay an error at once.
A CPU of this machine that starts again while watched is joined at its new socket
(``web.cli.rejoin``). :func:`join_bus` is how every shell command joins the bus; those
that do not wait say :class:`Absent`'s ``message`` and end. :func:`local_cpu` is how
``s7graph web`` and ``s7graph opcua`` given no ``--connect`` find, and wait for, the CPU
of this machine: the one named with ``--cpu``, else the only one running here.
"""

from __future__ import annotations

import contextlib
import dataclasses
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
from s7graph.web.bus.protocol import CpuStatus, valid_name
from s7graph.web.bus.session import open_session, peer_problem
from s7graph.web.cli.net import NetOptions
from s7graph.web.cli.rejoin import POLL_S, Link, answer

__all__ = ["POLL_S", "Absent", "Local", "Reached", "cpu_reached", "join_bus", "local_cpu"]


@dataclass(frozen=True, slots=True)
class Absent:
    """The CPU is not reachable (yet): where it is looked for (``where``), why it is not
    there in a few words (``why``), and what a command that does not wait says."""

    where: str
    why: str
    message: str


@dataclass(frozen=True, slots=True)
class _Joined:
    """A session where CPU ``cpu`` is looked for; ``endpoint``: the one of this machine's
    endpoint file it joined (None: ``--connect``)."""

    session: zenoh.Session
    cpu: str
    endpoint: str | None


def _running_here() -> list[str]:
    """The CPUs of this machine for this user, by name: those whose endpoint file names a
    socket that takes a connection."""
    return [n for n in local.names() if valid_name(n) and local.listening(local.find(n) or "")]


def _here(cpu: str | None) -> tuple[str, str] | Absent | str:
    """(name, endpoint) of CPU ``cpu`` of this machine — with None, of the only CPU that
    runs here; :class:`Absent` when none does (yet), why when several do."""
    if cpu is None:
        names = _running_here()
        if len(names) > 1:
            return (
                f"several CPUs run on this machine for this user ({', '.join(names)}): "
                "name one with --cpu NAME, or give the bus with --connect ENDPOINT"
            )
        cpu = names[0] if names else None
    endpoint = local.find(cpu) if cpu is not None else None
    if cpu is None or endpoint is None:
        which = f"CPU {cpu}" if cpu is not None else "CPU"
        return Absent(
            f"{ROOT}/{cpu or '*'} on this machine",
            f"no {which} is on this machine's bus for this user yet",
            f"give the bus with --connect ENDPOINT (no {which} is on this machine's bus for this "
            "user; a run given none of --web, --opcua, --listen and --connect is on none)",
        )
    return cpu, endpoint


def _join(net: NetOptions, cpu: str | None) -> _Joined | Absent | str:
    """A session on the bus of ``net`` where CPU ``cpu`` is (None: the one of this machine;
    with ``--connect``, ``net.cpu``), :class:`Absent` when it is not there, or why the
    options or the bus are wrong."""
    problem = net.problem(listening=False)
    if problem:
        return problem
    connect, endpoint = list(net.connect), None
    if not connect:
        here = _here(cpu)  # a CPU of this machine (web.bus.local)
        if not isinstance(here, tuple):
            return here
        cpu, endpoint = here
        connect = [endpoint]
    name = cpu or net.cpu
    try:
        session = open_session(connect=connect, tls=net.tls, login=net.login)
    except Exception as exc:
        if net.unreached(exc):
            ends = ", ".join(connect)
            return Absent(ends, "nothing answers there yet", net.join_error(exc))
        return net.join_error(exc)
    wrong = peer_problem(session, name)
    if wrong is not None:
        session.close()  # type: ignore[no-untyped-call]  # zenoh's stub
        return wrong
    return _Joined(session, name, endpoint)


def join_bus(net: NetOptions) -> zenoh.Session | Absent | str:
    """A session on the bus of ``net`` (connecting only); :class:`Absent` when the CPU is
    not there (no CPU of that name on this machine, nothing answers at ``--connect``), or
    why the options or the bus are wrong."""
    got = _join(net, net.cpu)
    return got.session if isinstance(got, _Joined) else got


@dataclass(frozen=True, slots=True)
class Reached:
    """The CPU answered: its status, whether only after a wait (said on stderr), what is
    left of ``--duration-s`` (None: no limit), and the :class:`Link` to it."""

    status: CpuStatus
    waited: bool
    left_s: float | None
    link: Link

    @property
    def client(self) -> BusClient:
        """A client of the CPU (of its run joined last)."""
        return self.link.client


@contextlib.contextmanager
def cpu_reached(net: NetOptions, duration_s: float | None) -> Iterator[Reached | int]:
    """A client of ``net.cpu`` once it answers (its session closed after), or the exit
    status when the watch ends before: 0 stopped (Ctrl-C, SIGTERM), 2 an error or
    ``duration_s`` over (the reason printed)."""
    waiter = _Waiter(net, net.cpu, duration_s)
    got = waiter.wait()
    if isinstance(got, int):
        yield got
        return
    joined, status = got
    link = Link(net, joined.session, joined.endpoint)
    try:
        yield Reached(status, waiter.said, waiter.left(), link)
    finally:
        link.close()


@dataclass(frozen=True, slots=True)
class Local:
    """The CPU of this machine found: ``net`` with its endpoint as ``--connect``, its
    name, and what is left of ``--duration-s`` (None: no limit)."""

    net: NetOptions
    cpu: str
    left_s: float | None


def local_cpu(net: NetOptions, cpu: str | None, duration_s: float | None) -> Local | int:
    """For ``s7graph web`` and ``opcua`` given no ``--connect``: CPU ``cpu`` of this
    machine (None: the only one running here) once it answers, waited for as the watch
    waits; or the exit status: 0 stopped meanwhile, 2 an error, several CPUs to choose
    from, or ``duration_s`` over (the reason printed)."""
    waiter = _Waiter(net, cpu, duration_s)
    got = waiter.wait()
    if isinstance(got, int):
        return got
    joined, _ = got
    joined.session.close()  # type: ignore[no-untyped-call]  # zenoh's stub
    connect = (joined.endpoint,) if joined.endpoint is not None else tuple(net.connect)
    found = dataclasses.replace(net, connect=connect, cpu=joined.cpu)
    return Local(found, joined.cpu, waiter.left())


class _Waiter:
    """Tries to reach ``cpu`` (None: the one of this machine) until it answers, Ctrl-C,
    SIGTERM or ``duration_s``."""

    def __init__(self, net: NetOptions, cpu: str | None, duration_s: float | None) -> None:
        self.net, self.cpu, self.duration_s = net, cpu, duration_s
        self.deadline = None if duration_s is None else time.monotonic() + duration_s
        self.stop = threading.Event()
        self.said = False
        self.where = ""

    def wait(self) -> tuple[_Joined, CpuStatus] | int:
        """:meth:`reach`, with SIGTERM and Ctrl-C ending the wait (exit status 0)."""
        previous = signal.signal(signal.SIGTERM, lambda *_: self.stop.set())
        try:
            return self.reach()
        except KeyboardInterrupt:
            return 0
        finally:
            signal.signal(signal.SIGTERM, previous)

    def left(self) -> float | None:
        """What is left of ``duration_s`` (None: no limit)."""
        return None if self.deadline is None else max(self.deadline - time.monotonic(), 0.0)

    def reach(self) -> tuple[_Joined, CpuStatus] | int:
        """(a session the CPU answers on, its status), or the exit status."""
        while True:
            got = _join(self.net, self.cpu)
            if isinstance(got, str):
                return _fail(got)
            if isinstance(got, Absent):
                self._say(got.where, got.why)
            else:
                reached = self._answered(got)
                if reached:
                    return reached
                got.session.close()  # type: ignore[no-untyped-call]  # zenoh's stub
            ended = self._pause()
            if ended is not None:
                return ended

    def _answered(self, joined: _Joined) -> tuple[_Joined, CpuStatus] | None:
        """(``joined``, the CPU's status) when it answers; None when it does not (said
        once)."""
        status = answer(joined.session, joined.cpu)
        if status is not None:
            return joined, status
        ends = ", ".join(self.net.connect) or "this machine"
        self._say(f"{ROOT}/{joined.cpu} on {ends}", "not on the bus yet")
        return None

    def _say(self, where: str, why: str) -> None:
        if not self.said:
            who = f"CPU {self.cpu}" if self.cpu is not None else "a CPU"
            print(f"s7graph: waiting for {who} at {where} ({why})", file=sys.stderr, flush=True)
            self.said, self.where = True, where

    def _pause(self) -> int | None:
        """Wait before the next try; the exit status when the watch ends meanwhile."""
        wait = POLL_S
        if self.deadline is not None:
            wait = min(wait, self.deadline - time.monotonic())
        if wait > 0 and self.stop.wait(wait):
            return 0
        if self.deadline is not None and time.monotonic() >= self.deadline:
            who = f"CPU {self.cpu} did not appear" if self.cpu is not None else "no CPU appeared"
            return _fail(f"{who} at {self.where} within {self.duration_s:g} s (--duration-s)")
        return None


def _fail(message: str) -> int:
    print(f"s7graph: error: {message}", file=sys.stderr)
    return 2
