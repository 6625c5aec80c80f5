"""``s7graph watch --address MW0,Q4.0,DB20.avg``: a watch table of addresses, symbols and
DB variables of a CPU on the bus, as STEP 7's "Monitor/Modify Variables" triggered at the
end of a cycle (``web.bus.watch``).

Every ``--interval-ms`` it asks the CPU for the values at its next scan boundary and prints
one line whenever one changed — the cycle, the CPU's state and each operand as S7 writes
it (``MW0:INT=12  Q4.0=TRUE  DB20.avg=1.5``) — until Ctrl-C or ``--duration-s``. An
operand the CPU cannot read is said once on stderr (``DB20.avg: DB20 is not loaded``) and
shown as ``?``; when none can be read, or the CPU refuses the request, the exit status is
2. A CPU not there yet at the start is waited for (``web.cli.waiting``), and one that goes
away, as ``s7graph watch`` waits (``CPU cpu1 disconnected``, ``CPU cpu1 reachable``, then
its values again; one of this machine started again is joined at its new socket,
``web.cli.rejoin``); one that stops answering while there is said once on stderr, and again
when it answers. A read: no login needed; with ``--user`` each request is signed by that
user's login, and the CPU keeps them in the user's own share of its watch queue
(``web.bus.watch``) — one refused later (the login ended) is said once, and the watch goes
on without it.
"""

from __future__ import annotations

import sys
import threading

from s7graph.engine.text import is_unicode
from s7graph.web.bus.client import BusClient
from s7graph.web.bus.protocol import MAX_WATCH, WatchValues
from s7graph.web.bus.watch import login_refused, split_operands
from s7graph.web.cli.net import NetOptions
from s7graph.web.cli.remote import alive_line, shell_login
from s7graph.web.cli.stopping import say, wait_until_stopped
from s7graph.web.cli.waiting import Reached, cpu_reached

__all__ = [
    "MAX_INTERVAL_MS",
    "MIN_INTERVAL_MS",
    "check_interval",
    "split_addresses",
    "watch_addresses",
]

MIN_INTERVAL_MS = 20
MAX_INTERVAL_MS = 3_600_000  # an hour


def split_addresses(text: str) -> list[str]:
    """The operands of ``--address`` (``MW0,Q4.0, DB20.avg``), commas inside ``[i, j]``
    kept; ValueError with a one-line reason for none or too many."""
    if not is_unicode(text):  # bytes of the command line that are not UTF-8
        raise ValueError("--address: not valid UTF-8 text")
    operands = split_operands(text)
    if not operands:
        raise ValueError("--address: give the operands to watch, e.g. MW0,Q4.0,DB20.avg")
    if len(operands) > MAX_WATCH:
        raise ValueError(f"--address: at most {MAX_WATCH} operands, not {len(operands)}")
    return operands


def check_interval(ms: float) -> float:
    """``--interval-ms`` when it is from :data:`MIN_INTERVAL_MS` to :data:`MAX_INTERVAL_MS`;
    ValueError with a one-line reason otherwise (NaN included)."""
    if not MIN_INTERVAL_MS <= ms <= MAX_INTERVAL_MS:
        raise ValueError(
            f"--interval-ms: from {MIN_INTERVAL_MS} to {MAX_INTERVAL_MS:,} ms, not {ms:g}"
        )
    return ms


def _line(answer: WatchValues) -> str:
    shown = "  ".join(f"{v.address}={v.text if not v.error else '?'}" for v in answer.values)
    return f"cycle {answer.cycle} {answer.state}  {shown}"


def watch_addresses(
    net: NetOptions,
    addresses: list[str],
    *,
    interval_ms: float = 200.0,
    duration_s: float | None = None,
    user: str | None = None,
) -> int:
    """Print the watch table of ``net.cpu`` on every change until Ctrl-C, SIGTERM or
    ``duration_s``; 0 at the end, 1 when ``user``'s login is refused, 2 when nothing can
    be watched (no bus, every operand refused, no CPU within ``duration_s``). A CPU not
    there at the start is waited for (``web.cli.waiting``), and one that goes, as
    ``s7graph watch`` waits: ``CPU cpu1 disconnected``, then ``CPU cpu1 reachable`` and
    the values once it is back. With ``user`` the requests are signed by that user's login
    (the CPU keeps them in the user's own share)."""
    with cpu_reached(net, duration_s) as reached:
        if isinstance(reached, int):
            return reached
        if reached.waited:  # it said it waits: now say the CPU is there
            say(alive_line(net.cpu, True), threading.Event())
        if user is None:
            return _table(reached, net.cpu, addresses, interval_ms)
        with shell_login(reached.client, reached.status, user) as token:
            if isinstance(token, int):
                return token
            return _table(reached, net.cpu, addresses, interval_ms, token)


def _table(
    reached: Reached, cpu: str, addresses: list[str], interval_ms: float, token: str = ""
) -> int:
    """:func:`watch_addresses` once the CPU answers (``token``: a login's, "" none)."""
    client = reached.client
    first = client.watch(addresses, token=token)
    if first.error:
        print(f"s7graph: error: {cpu}: {first.error}", file=sys.stderr)
        return 2
    for value in first.values:
        if value.error:  # the operand named once: the CPU's words may start with it
            said = value.error.removeprefix(f"{value.address}: ")
            print(f"s7graph: {value.address}: {said}", file=sys.stderr)
    if first.values and all(v.error for v in first.values):
        print(f"s7graph: error: {cpu}: no operand of --address can be read", file=sys.stderr)
        return 2
    stop = threading.Event()
    say(_line(first), stop)
    poll = max(interval_ms, MIN_INTERVAL_MS) / 1000
    follower = _Follower(client, addresses, first, stop, cpu, token)
    reached.link.keep(follower.rebind, follower.alive)
    thread = threading.Thread(target=follower.run, args=(poll,), name="s7graph-watch", daemon=True)
    thread.start()
    try:
        wait_until_stopped(reached.left_s, stop)
    finally:
        stop.set()
        thread.join(timeout=5.0)
    return 0


class _Follower:
    """Asks ``client`` for the values of ``addresses`` again and again and prints a line
    for each change; told by the CPU's liveliness when it goes and comes back (``alive``,
    a zenoh thread), it says so in ``s7graph watch``'s words and, while it is gone, no
    failed request is said."""

    def __init__(
        self,
        client: BusClient,
        addresses: list[str],
        first: WatchValues,
        stop: threading.Event,
        cpu: str,
        token: str = "",
    ) -> None:
        self.client, self.addresses, self.stop, self.cpu = client, addresses, stop, cpu
        self.token = token  # the login that signs each request ("": none)
        self.shown = [(v.text, v.error) for v in first.values]
        self.up: bool | None = None  # what the CPU's liveliness said last (None: nothing yet)
        self.failed = False  # a failed request was said on stderr
        self.back = False  # it came back: show the values again, changed or not
        self.lock = threading.Lock()

    def alive(self, up: bool) -> None:
        """The CPU's liveliness changed; the first word, that it is there, is known already
        (it answered) — unless a failed request was said since."""
        with self.lock:
            was, self.up = self.up, up
            if was == up or (was is None and up and not self.failed):
                return
            self.back = self.back or up
            say(alive_line(self.cpu, up), self.stop)

    def rebind(self, client: BusClient) -> None:
        """Ask ``client`` from now on: the CPU's run joined last (``web.cli.rejoin``). A
        login does not outlive the run it was made at: said once, the requests go on
        unsigned."""
        with self.lock:
            if client is self.client:
                return
            self.client = client
            if self.token:
                print(
                    f"s7graph: {self.cpu}: the login ended with the CPU's run; watching "
                    "without a login from now on",
                    file=sys.stderr,
                    flush=True,
                )
                self.token = ""

    def run(self, poll_s: float) -> None:
        """Ask every ``poll_s`` until ``stop``; a line for each change (an answer of a
        client left meanwhile is dropped)."""
        while not self.stop.wait(poll_s):
            client = self.client
            answer = client.watch(self.addresses, timeout=2.0, token=self.token)
            if self.stop.is_set():
                return
            with self.lock:
                if client is self.client:
                    self._show(answer)

    def _show(self, answer: WatchValues) -> None:
        """One answer: a line if the values changed (or the CPU is back), a failure said
        once while the CPU is not known to be gone (``lock`` held). A signed request
        refused (the login ended: expired, logged out, a CPU started again) is said once,
        and the requests go on unsigned."""
        if self.token and login_refused(answer.error):
            print(
                f"s7graph: {self.cpu}: {answer.error}; watching without a login from now on",
                file=sys.stderr,
                flush=True,
            )
            self.token = ""
            return
        if answer.error:
            if not self.failed and self.up is not False:  # gone: "disconnected" said it
                print(f"s7graph: {self.cpu}: {answer.error}", file=sys.stderr, flush=True)
                self.failed = True
            return
        if self.failed and not self.back:
            print(f"s7graph: {self.cpu} answers again", file=sys.stderr, flush=True)
        self.failed = False
        now = [(v.text, v.error) for v in answer.values]
        if now != self.shown or self.back:
            self.shown, self.back = now, False
            say(_line(answer), self.stop)
