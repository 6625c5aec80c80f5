"""``s7graph web [--connect EP] [--cpu NAME] [--fb NAME]``: the browser view as a process of
its own, for any CPU on the bus.

It lists the CPUs answering on the bus with their FBs, serves the view of ``--cpu`` (by
default the first, by name) and ``--fb`` (by default its first FB; a CPU without one, a
program of blocks, gets its status, watch table and diagnostics) on ``--host:--port``,
and knows the CPU only over the bus. Given no ``--connect`` it serves the CPU of this
machine (``web.cli.waiting.local_cpu``: ``--cpu``'s, else the only one running here),
waiting for it as ``s7graph watch`` does. ``s7graph run --web`` starts it so, as its child
(``--child``: it ends when its stdin closes — the CPU's process went — and yields the
processor to the CPU). The page may leave this machine (``--host``) only when the CPU
checks logins (a users file). Once it serves, what it built to start is frozen
(``web.collector.freeze_start``): a full collection walks only what came later and holds a
step change up on its way to the page for less. Stopped, it says so in one line on stderr.
"""

from __future__ import annotations

import sys
import threading

from s7graph.web.bus.client import unread_note, wait_for_cpus
from s7graph.web.bus.session import open_session, peer_problem
from s7graph.web.cli.net import NetOptions, error_words, is_loopback_host
from s7graph.web.cli.stopping import wait_until_stopped
from s7graph.web.cli.view_process import as_child
from s7graph.web.cli.waiting import local_cpu
from s7graph.web.collector import freeze_start
from s7graph.web.view.edge import ViewSide
from s7graph.web.view.port import PortError, check_port

__all__ = ["web_command"]


def _fail(message: str) -> int:
    print(f"s7graph: error: {message}", file=sys.stderr)
    return 2


def web_command(
    net: NetOptions,
    *,
    cpu: str | None,
    fb: str | None,
    port: int,
    duration_s: float | None = None,
    wait_s: float = 10.0,
    child: bool = False,
) -> int:
    stop = threading.Event()
    if child:
        as_child(stop)
    problem = NetOptions(**{**net.__dict__, "host": "127.0.0.1"}).problem()
    if problem:
        return _fail(problem)
    if not child:  # a port out of range or taken: said at once, before any wait for a CPU
        try:
            check_port(net.host, port)
        except PortError as exc:
            return _fail(str(exc))
    if not net.connect:  # the CPU of this machine (web.bus.local), waited for
        here = local_cpu(net, cpu, duration_s)
        if isinstance(here, int):
            return here
        net, cpu, duration_s = here.net, here.cpu, here.left_s
    try:
        with open_session(connect=net.connect, tls=net.tls, login=net.login) as probe:
            cpus, unreadable = wait_for_cpus(probe, wait_s)
            first = cpus[0] if cpus else None
            chosen = next((s for s in cpus if s.cpu == cpu), None) if cpu else first
            wrong = peer_problem(probe, chosen.cpu) if chosen is not None else None
    except Exception as exc:
        return _fail(net.join_error(exc))
    if not cpus:
        return _fail(f"no CPU answers on {', '.join(net.connect)}{unread_note(unreadable)}")
    if wrong is not None:
        return _fail(wrong)  # before a word of what it said is shown
    for status in cpus:
        print(
            f"s7graph: CPU {status.cpu} ({status.state}, logins: {status.login}): "
            f"{', '.join(status.fbs) or 'no FB'}",
            flush=True,
        )
    if chosen is None:
        return _fail(f"no CPU {cpu!r} on the bus; found {', '.join(s.cpu for s in cpus)}")
    if fb is not None and fb not in chosen.fbs:
        runs = ", ".join(chosen.fbs) or "none (a program of blocks: leave --fb out)"
        return _fail(f"CPU {chosen.cpu} runs no FB {fb!r}; it runs {runs}")
    if not is_loopback_host(net.host) and chosen.login != "users":
        return _fail(
            f"--host {net.host} is not loopback and CPU {chosen.cpu} has no users file: "
            "the page stays on this machine"
        )
    try:
        view = ViewSide(
            cpu=chosen.cpu,
            fb=fb,
            ends=net.ends,
            host=net.host,
            port=port,
            allowed_origins=net.origins,
        )
    except (PortError, TimeoutError) as exc:
        return _fail(str(exc))
    except Exception as exc:
        return _fail(f"cannot serve the view: {error_words(exc)}")
    freeze_start()  # the process is the view's alone: a full collection skips what it built
    of = f"{chosen.cpu}/{view.fb}" if view.fb else f"{chosen.cpu} (a program)"
    print(f"s7graph: view {view.url} of {of}; Ctrl-C to stop", flush=True)
    try:
        wait_until_stopped(duration_s, stop)
    finally:
        view.close()
    print("s7graph: view stopped", file=sys.stderr, flush=True)
    return 0
