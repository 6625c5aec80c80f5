"""``s7graph router --listen ENDPOINT ...``: a zenoh router in Python, where CPUs and views
on several machines meet (no extra binary). Runs until Ctrl-C or SIGTERM."""

from __future__ import annotations

import sys

from s7graph.web.bus.session import open_session
from s7graph.web.cli.net import NetOptions
from s7graph.web.cli.stopping import wait_until_stopped

__all__ = ["router_command"]


def router_command(net: NetOptions, duration_s: float | None = None) -> int:
    problem = net.problem(listening=False)
    if problem is None and not net.listen:
        problem = "a router needs at least one --listen endpoint"
    if problem:
        print(f"s7graph: error: {problem}", file=sys.stderr)
        return 2
    try:
        session = open_session(net.listen, net.connect, mode="router", tls=net.tls)
    except Exception as exc:
        print(
            f"s7graph: error: cannot open the router: {type(exc).__name__}: {exc}", file=sys.stderr
        )
        return 2
    print(f"s7graph: router on {', '.join(net.listen)}; Ctrl-C to stop", flush=True)
    try:
        wait_until_stopped(duration_s)
    finally:
        session.close()  # type: ignore[no-untyped-call]  # zenoh's stub
    return 0
