"""``s7graph watch`` and the shell's commands: ``ack``, ``mode``, ``init``, ``off``,
``step-on``, ``step-off``, ``t-push`` for one CPU on the bus.

A command logs in as ``--user`` (the password from ``S7GRAPH_PASSWORD``, else a prompt
when the CPU checks passwords), sends the command with the token, logs out, and exits 0
when the CPU applied it, 1 when it refused it (the reason on stderr) or did not answer.
``watch`` prints every change of the FBs' active steps, mode and errors, and the events,
one line each, until Ctrl-C or ``--duration-s``.
"""

from __future__ import annotations

import getpass
import os
import socket
import sys
import threading
from typing import Any

import zenoh

from s7graph.web.bus.protocol import Command, StepStateUpdate
from s7graph.web.bus.zenoh_bus import BusClient, open_session
from s7graph.web.cli.net import NetOptions
from s7graph.web.cli.stopping import wait_until_stopped

__all__ = ["PASSWORD_ENV", "send_command", "watch_command"]

PASSWORD_ENV = "S7GRAPH_PASSWORD"


def _fail(message: str, code: int = 2) -> int:
    print(f"s7graph: error: {message}", file=sys.stderr)
    return code


def _origin() -> str:
    who = os.environ.get("USER", "") or "?"
    return f"shell {who}@{socket.gethostname()} pid {os.getpid()}"[:160]


def _join(net: NetOptions) -> zenoh.Session | str:
    """A session on the bus of ``net`` (connecting only), or why there is none."""
    problem = net.problem(listening=False)
    if problem is None and not net.connect:
        problem = "give the bus with --connect ENDPOINT"
    if problem:
        return problem
    try:
        return open_session(connect=net.connect, tls=net.tls)
    except Exception as exc:
        return f"cannot join the bus: {type(exc).__name__}: {exc}"


def send_command(
    net: NetOptions, *, fb: str | None, user: str, op: str, args: dict[str, Any]
) -> int:
    """Log in, send one command, log out; 0 applied, 1 refused, 2 a usage or bus error."""
    session = _join(net)
    if isinstance(session, str):
        return _fail(session)
    try:
        with BusClient(session, net.cpu) as client:
            status = client.status()
            if status is None:
                return _fail(f"CPU {net.cpu!r} does not answer", 1)
            name = fb or (status.fbs[0] if status.fbs else "")
            password = os.environ.get(PASSWORD_ENV, "")
            if status.login == "users" and not password and sys.stdin.isatty():
                password = getpass.getpass(f"Password for {user}: ")
            login = client.login(user, password, origin=_origin())
            if not login.ok:
                return _fail(f"login refused: {login.reason}", 1)
            try:
                fields: dict[str, Any] = {"op": op, "args": args}
                command = Command(
                    fb=name, user=user, token=login.token, origin=_origin(), **fields
                )
                reply = client.send(command)
            except (TypeError, ValueError) as exc:
                return _fail(str(exc))
            finally:
                client.logout(login.token, user=user, origin=_origin())
    finally:
        session.close()  # type: ignore[no-untyped-call]  # zenoh's stub
    if not reply.applied:
        print(f"s7graph: {op} refused: {reply.reason}", file=sys.stderr)
        return 1
    print(f"s7graph: {op} applied on {net.cpu}/{name} (cycle {reply.cycle})")
    return 0


def _line(fb: str, update: StepStateUpdate) -> str:
    active = " ".join(f"S{n}" for n in update.active) or "-"
    parts = [f"cycle {update.cycle}", fb, update.mode, f"active {active}"]
    bad = sorted(set(update.disturbed) | set(update.latched))
    if bad:
        parts.append("error " + " ".join(f"S{n}" for n in bad))
    if update.events:
        parts.append("events " + " ".join(f"{e}:S{s}" for e, s in update.events))
    return "  ".join(parts)


def watch_command(net: NetOptions, *, fb: str | None, duration_s: float | None = None) -> int:
    """Print step changes of ``net.cpu`` live; 0 at the end, 2 when nothing can be watched."""
    lock = threading.Lock()
    session = _join(net)
    if isinstance(session, str):
        return _fail(session)
    try:
        with BusClient(session, net.cpu) as client:
            status = client.status()
            if status is None:
                return _fail(f"CPU {net.cpu!r} does not answer")
            names = [fb] if fb else list(status.fbs)
            last: dict[str, tuple[object, ...]] = {}

            def show(name: str, update: StepStateUpdate) -> None:
                key = (update.mode, update.active, update.disturbed, update.latched)
                if last.get(name) == key and not update.events:
                    return
                last[name] = key
                with lock:
                    print(_line(name, update), flush=True)

            def alive(up: bool) -> None:
                with lock:
                    print(f"CPU {net.cpu} {'reachable' if up else 'disconnected'}", flush=True)

            client.on_alive(alive)
            for name in names:
                client.follow(name, lambda u, n=name: show(n, u))  # type: ignore[misc]
            wait_until_stopped(duration_s)
    finally:
        session.close()  # type: ignore[no-untyped-call]  # zenoh's stub
    return 0
