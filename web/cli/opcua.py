"""``s7graph opcua [--connect EP] [--cpu NAME] [--listen opc.tcp://127.0.0.1:4840]``: the
OPC UA server of a CPU on the bus, as a process of its own (``web.opcua``; docs/opcua.md).

It finds the CPU on the bus (waiting up to ``wait_s`` for it), serves its address space
on ``--listen`` and knows the CPU only over the bus, like the view. Given no
``--connect`` it serves the CPU of this machine (``web.cli.waiting.local_cpu``:
``--cpu``'s, else the only one running here), waiting for it as ``s7graph watch`` does.
``s7graph run … --opcua URL`` starts it so, as its child (``--child``: it ends when its
stdin closes — the CPU's process went — and yields the processor to the CPU;
:class:`OpcuaProcess` restarts it when it ends). Beyond loopback it serves only with
``--users`` (the CPU must check logins: its status says ``users``) and a certificate
(``--cert``/``--key``: ``SignAndEncrypt`` only). Stopped, it says so in one line on stderr.
"""

from __future__ import annotations

import logging
import re
import sys
import threading
from collections.abc import Sequence
from pathlib import Path

from s7graph.web.cli.net import NetOptions, error_words
from s7graph.web.cli.stopping import wait_until_stopped
from s7graph.web.cli.view_process import ViewProcess, as_child

__all__ = ["ANONYMOUS", "OpcuaProcess", "opcua_command", "writes_problem"]

ANONYMOUS = ("read", "refuse")
"""What an anonymous OPC UA session may do: read (browse, subscribe), or nothing."""


def _fail(message: str) -> int:
    print(f"s7graph: error: {message}", file=sys.stderr)
    return 2


def _logging() -> None:
    """The face's lines (logins refused, commands and their outcome) on stderr."""
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(logging.Formatter("s7graph: %(message)s"))
    log = logging.getLogger("s7graph.web.opcua")
    log.addHandler(handler)
    log.setLevel(logging.INFO)
    log.propagate = False


def writes_problem(writes: str | None, option: str) -> str | None:
    """Why ``writes`` is not an op a symbol's write may send, else None."""
    if writes is None:
        return None
    from s7graph.web.opcua.space import WRITES

    if writes not in WRITES:
        return f"{option} must be {' or '.join(WRITES)}, not {writes!r}"
    return None


def opcua_command(
    net: NetOptions,
    *,
    cpu: str | None,
    listen: str,
    anonymous: str | None = None,
    writes: str | None = None,
    cert: Path | None = None,
    key: Path | None = None,
    trust: Path | None = None,
    duration_s: float | None = None,
    wait_s: float = 10.0,
    child: bool = False,
) -> int:
    """Serve OPC UA for ``cpu`` (None: the first on the bus) at ``listen``; 0 when
    stopped, 2 when it cannot serve (one line on stderr)."""
    stop = threading.Event()
    if child:
        as_child(stop)  # lower its priority before the imports: they take a while
    from s7graph.web.bus.client import unread_note, wait_for_cpus
    from s7graph.web.bus.protocol import ProtocolError
    from s7graph.web.bus.session import open_session, peer_problem
    from s7graph.web.opcua.server import (
        OpcuaOptions,
        OpcuaServer,
        listen_problem,
        loopback,
        trust_problem,
    )

    problem = NetOptions(**{**net.__dict__, "host": "127.0.0.1"}).problem()
    if anonymous is not None and anonymous not in ANONYMOUS:
        problem = "--anonymous must be read or refuse"
    problem = problem or writes_problem(writes, "--writes")
    if problem is None and net.users is not None and not net.users.is_file():
        problem = f"{net.users}: no such users file"
    problem = problem or listen_problem(listen, users=net.users is not None, cert=cert, key=key)
    if problem is None and trust is not None:
        problem = trust_problem(trust) if trust.is_dir() else f"--trust {trust}: no such folder"
    if problem:
        return _fail(problem)
    if not net.connect:  # the CPU of this machine (web.bus.local), waited for
        from s7graph.web.cli.waiting import local_cpu

        here = local_cpu(net, cpu, duration_s)
        if isinstance(here, int):
            return here
        net, cpu, duration_s = here.net, here.cpu, here.left_s
    _logging()
    session = None
    try:
        session = open_session(connect=net.connect, tls=net.tls, login=net.login)
        cpus, unreadable = wait_for_cpus(
            session, wait_s, lambda found: any(cpu in (None, s.cpu) for s in found)
        )
        chosen = next((s for s in cpus if cpu in (None, s.cpu)), None)
        if chosen is None:
            found = ", ".join(s.cpu for s in cpus) or "none"
            where = ", ".join(net.connect)
            return _fail(
                f"no CPU {cpu or ''} answers on {where} (found: {found}){unread_note(unreadable)}"
            )
        wrong = peer_problem(session, chosen.cpu)
        if wrong is not None:
            return _fail(wrong)
        if net.users is not None and chosen.login != "users":
            return _fail(f"--users given, but CPU {chosen.cpu} checks no logins (no users file)")
        reads = anonymous == "read" or (anonymous is None and loopback(listen))
        options = OpcuaOptions(
            url=listen,
            anonymous=reads,
            cert=cert,
            key=key,
            trust=trust,
            own_process=True,
            writes=writes or "force",
        )
        server = OpcuaServer(session, chosen, options)
        try:
            server.start()
        except ProtocolError as exc:  # what the CPU answered while the nodes were built
            return _fail(f"cannot serve OPC UA of CPU {chosen.cpu}: {exc}")
        except Exception as exc:
            return _fail(f"cannot serve OPC UA at {listen}: {error_words(exc)}")
        print(f"s7graph: opcua {server.url} of {chosen.cpu}; Ctrl-C to stop", flush=True)
        try:
            wait_until_stopped(duration_s, stop)
        finally:
            server.stop()
    except Exception as exc:
        return _fail(net.join_error(exc))
    finally:
        if session is not None:
            session.close()  # type: ignore[no-untyped-call]  # zenoh's stub
    print("s7graph: opcua stopped", file=sys.stderr, flush=True)
    return 0


class OpcuaProcess(ViewProcess):
    """``s7graph opcua`` for CPU ``cpu`` at ``connect``, serving ``url``, kept running
    until :meth:`stop` (restarted after a back-off when it ends, as the view is)."""

    what = "OPC UA server"
    ready = re.compile(r"^s7graph: opcua (\S+) of ")

    def __init__(
        self,
        *,
        connect: Sequence[str],
        cpu: str,
        url: str,
        users: Path | None = None,
        cert: Path | None = None,
        key: Path | None = None,
        tls_ca: Path | None = None,
        bus_args: Sequence[str] = (),
        first_backoff_s: float = 1.0,
        writes: str = "force",
    ) -> None:
        super().__init__(
            connect=connect,
            cpu=cpu,
            tls_ca=tls_ca,
            bus_args=bus_args,
            first_backoff_s=first_backoff_s,
        )
        self.opcua_url = url
        self.users = users
        self.cert = cert
        self.key = key
        self.writes = writes

    def command(self) -> list[str]:
        cmd = [sys.executable, "-m", "s7graph", "opcua", "--cpu", self.cpu]
        cmd += ["--listen", self.opcua_url, "--writes", self.writes, "--child"]
        for endpoint in self.connect:
            cmd += ["--connect", endpoint]
        for option, path in (
            ("--users", self.users),
            ("--cert", self.cert),
            ("--key", self.key),
            ("--tls-ca", None if "--tls-ca" in self.bus_args else self.tls_ca),
        ):
            if path is not None:
                cmd += [option, str(path)]
        return cmd + self.bus_args
