"""``s7graph router --listen ENDPOINT ...``: a zenoh router in Python, where CPUs and views
on several machines meet (no extra binary). Runs until Ctrl-C or SIGTERM.

With credentials (a certificate, or ``--bus-user`` and ``--bus-users``) the router lets
in only nodes that prove who they are, and runs zenoh's access control for the CPUs named
with ``--cpu`` (``web.bus.acl``): each CPU's identity ``cpu.<name>`` alone may serve and
publish on ``s7graph/<name>/**``, every other node may only ask and listen. Without
credentials it stays on loopback and relays anything (the demo)."""

from __future__ import annotations

import sys

from s7graph.web.bus.session import open_session
from s7graph.web.cli.net import NetOptions, error_words
from s7graph.web.cli.stopping import wait_until_stopped

__all__ = ["router_command"]


def router_command(net: NetOptions, duration_s: float | None = None) -> int:
    problem = net.problem(listening=False, role="router")
    if problem is None and not net.listen:
        problem = "a router needs at least one --listen endpoint"
    if problem:
        print(f"s7graph: error: {problem}", file=sys.stderr)
        return 2
    guard = tuple(net.relays) if net.has_credentials else ()
    try:
        session = open_session(
            net.listen, net.connect, mode="router", tls=net.tls, login=net.login, guard=guard
        )
    except Exception as exc:
        print(f"s7graph: error: cannot open the router: {error_words(exc)}", file=sys.stderr)
        return 2
    serves = f"; CPUs {', '.join(guard)}" if guard else ""
    print(f"s7graph: router on {', '.join(net.listen)}{serves}; Ctrl-C to stop", flush=True)
    try:
        wait_until_stopped(duration_s)
    finally:
        session.close()  # type: ignore[no-untyped-call]  # zenoh's stub
    return 0
