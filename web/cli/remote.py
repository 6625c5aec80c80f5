"""``s7graph watch`` and the shell's commands: ``ack``, ``mode``, ``init``, ``off``,
``step-on``, ``step-off``, ``set-steps``, ``t-push``, ``force`` and ``download`` for one CPU
on the bus.

A command logs in as ``--user`` (the password from ``S7GRAPH_PASSWORD``, else a prompt
when the CPU checks passwords), sends the command with the token, logs out, and exits 0
when the CPU applied it, 1 when it refused it (the reason on stderr) or did not answer.
``watch`` prints every change of the FBs' active steps, mode and errors, and the events,
one line each, until Ctrl-C or ``--duration-s``, waiting first for a CPU not there yet
(``web.cli.waiting``). ``force --list`` prints the CPU's force
jobs (a read: no login).
"""

from __future__ import annotations

import contextlib
import getpass
import os
import re
import socket
import sys
import threading
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import TypeVar

import msgspec
import zenoh

from s7graph.engine.text import NotUtf8, read_utf8
from s7graph.sequencer.change.base import MAX_SOURCE, EditRefused
from s7graph.sequencer.change.typed import parse_source
from s7graph.sequencer.checks.diagnostics import format_diagnostic
from s7graph.web.bus.client import BusClient
from s7graph.web.bus.cycle_text import cycle_lines
from s7graph.web.bus.protocol import (
    REFUSAL_KINDS,
    Command,
    CommandReply,
    CpuStatus,
    StepStateUpdate,
)
from s7graph.web.cli.diag_text import event_line, when
from s7graph.web.cli.net import NetOptions
from s7graph.web.cli.stopping import say, wait_until_stopped
from s7graph.web.cli.waiting import Absent, cpu_reached, join_bus
from s7graph.web.commands import MAX_FILE_NAME, Args, Download, DownloadArgs, checked, op_of

__all__ = [
    "PASSWORD_ENV",
    "alive_line",
    "ask",
    "download_command",
    "fb_to_read",
    "list_forces",
    "on_bus",
    "send_command",
    "shell_login",
    "status_command",
    "status_lines",
    "watch_command",
]

PASSWORD_ENV = "S7GRAPH_PASSWORD"
T = TypeVar("T")


def _fail(message: str, code: int = 2) -> int:
    print(f"s7graph: error: {message}", file=sys.stderr)
    return code


def _origin() -> str:
    who = os.environ.get("USER", "") or "?"
    return f"shell {who}@{socket.gethostname()} pid {os.getpid()}"[:160]


def _join(net: NetOptions) -> zenoh.Session | str:
    """A session on the bus of ``net`` (connecting only), or why there is none."""
    got = join_bus(net)
    return got.message if isinstance(got, Absent) else got


@contextlib.contextmanager
def on_bus(net: NetOptions) -> Iterator[BusClient | str]:
    """A client of ``net.cpu`` on the bus (its session closed after), or why there is none."""
    session = _join(net)
    if isinstance(session, str):
        yield session
        return
    try:
        with BusClient(session, net.cpu) as client:
            yield client
    finally:
        session.close()  # type: ignore[no-untyped-call]  # zenoh's stub


@contextlib.contextmanager
def _logged_in(net: NetOptions, *, fb: str | None, user: str) -> Iterator[_Shell | int]:
    """A shell logged in at ``net.cpu`` as ``user`` (logged out again after), or the exit
    status when that fails (the reason printed)."""
    with on_bus(net) as client:
        if isinstance(client, str):
            yield _fail(client)
            return
        status = client.status()
        if status is None:
            yield _fail(f"CPU {net.cpu!r} does not answer", 1)
            return
        # a CPU without an FB (a program) takes its CPU's ops whatever FB they name
        name = fb or (status.fbs[0] if status.fbs else net.cpu)
        with shell_login(client, status, user) as token:
            yield token if isinstance(token, int) else _Shell(client, name, user, token)


@contextlib.contextmanager
def shell_login(client: BusClient, status: CpuStatus, user: str) -> Iterator[str | int]:
    """The token of ``user`` logged in at the CPU of ``status`` from a shell (logged out
    again after) — the password from ``S7GRAPH_PASSWORD``, else a prompt when the CPU
    checks passwords — or the exit status 1 when the login is refused (the reason
    printed)."""
    password = os.environ.get(PASSWORD_ENV, "")
    if status.login == "users" and not password and sys.stdin.isatty():
        password = getpass.getpass(f"Password for {user}: ")
    login = client.login(user, password, origin=_origin())
    if not login.ok:
        yield _fail(f"login refused: {login.reason}", 1)
        return
    try:
        yield login.token
    finally:
        client.logout(login.token, user=user, origin=_origin())


class _Shell:
    """One logged-in shell: sends commands as its user, to its FB."""

    def __init__(self, client: BusClient, fb: str, user: str, token: str) -> None:
        self.client, self.fb, self.user, self.token = client, fb, user, token

    def send(
        self, kind: type[Command], args: Args, *, timeout: float | None = None
    ) -> CommandReply:
        """Send op ``kind`` with ``args``; ``ValueError`` (nothing sent) for what the bus
        would refuse to decode."""
        made = kind(fb=self.fb, user=self.user, token=self.token, origin=_origin(), args=args)
        return self.client.send(checked(made), timeout=timeout)


def send_command(
    net: NetOptions, *, fb: str | None, user: str, kind: type[Command], args: Args
) -> int:
    """Log in, send op ``kind`` with ``args``, log out; 0 applied, 1 refused, 2 a usage or
    bus error."""
    op = op_of(kind)
    with _logged_in(net, fb=fb, user=user) as shell:
        if isinstance(shell, int):
            return shell
        try:
            reply = shell.send(kind, args)
        except (TypeError, ValueError) as exc:
            return _fail(str(exc))
    if not reply.applied:
        return _refused(op, reply)
    on = net.cpu if kind.where in ("cpu", "force") else f"{net.cpu}/{shell.fb}"
    for line in reply.lines:  # an engineering op's change summary, diagnostics, notes
        print(f"s7graph: {line}")
    when = f" (cycle {reply.cycle})" if reply.cycle is not None else ""
    runs = f": version {reply.version} runs" if reply.version is not None else ""
    print(f"s7graph: {op} applied on {on}{when}{runs}")
    if reply.reason:  # what an applied command will not do (a fault that stays latched)
        print(f"s7graph: {reply.reason}")
    return 0


def fb_to_read(status: CpuStatus, fb: str | None, *, without: str) -> tuple[str, str]:
    """The FB a read of the CPU of ``status`` names — ``fb``, or the CPU's first — and "";
    or "" and why there is none: ``without`` when the CPU runs no GRAPH FB, or ``fb`` is
    none it runs."""
    if not status.fbs:
        return "", without
    if fb is not None and fb not in status.fbs:
        return "", f"this CPU runs no FB {fb!r}; it runs {', '.join(status.fbs)}"
    return fb or status.fbs[0], ""


def ask(net: NetOptions, query: Callable[[BusClient], T | None]) -> T | int:
    """What ``query`` gets from ``net.cpu``, or the exit status (2, the reason printed)
    when there is no bus or the CPU does not answer."""
    with on_bus(net) as client:
        if isinstance(client, str):
            return _fail(client)
        answer = query(client)
    if answer is None:
        return _fail(f"CPU {net.cpu!r} does not answer")
    return answer


def list_forces(net: NetOptions) -> int:
    """``s7graph force --list``: the CPU's force jobs, one line each; 0, or 2 when the CPU
    does not answer."""
    forces = ask(net, BusClient.forces)
    if isinstance(forces, int):
        return forces
    if not forces.entries:
        print(f"no force job active on {net.cpu}")
        return 0
    width = max(len(e.address) for e in forces.entries)
    for e in forces.entries:
        symbol = f'  "{e.symbol}"' if e.symbol else ""
        who = f"  ({e.user})" if e.user else ""
        print(f"{e.address:<{width}} = {e.value}{symbol}{who}")
    return 0


def download_command(
    net: NetOptions,
    chart: Path,
    *,
    fb: str | None,
    user: str,
    removed: str | None = None,
    yes: bool = False,
    timeout: float = 30.0,
    blocks: Sequence[Path] = (),
) -> int:
    """``s7graph download CHART.s7g [--blocks B.scl …]``: the change summary, a
    confirmation (``yes`` skips it), then the download into the running FB (with the
    changed S7-SCL sources ``blocks``, by file name); 0 downloaded, 1 refused or not
    confirmed, 2 a usage or bus error."""
    sources: dict[str, str] = {}
    try:
        source = read_utf8(chart)
        for path in blocks:
            if path.name in sources:
                return _fail(f"--blocks {path}: a source named {path.name} is given twice")
            sources[path.name] = read_utf8(path)
    except NotUtf8 as exc:  # located, as check says it: FILE:LINE:COL: not UTF-8: byte 0xff
        return _fail(str(exc))
    except OSError as exc:
        where = exc.filename or chart
        return _fail(f"cannot read {where}: {exc.strerror or exc}")
    for path, text in [(chart, source), *((p, sources[p.name]) for p in blocks)]:
        if len(text) > MAX_SOURCE:
            return _fail(
                f"{path}: {len(text):,} characters; a download carries at most {MAX_SOURCE:,} "
                "a file (split a source of blocks into several)"
            )
    try:  # a syntax error is said in this file's own name, before anything is sent
        parse_source(source, str(chart))
    except EditRefused as exc:
        for d in exc.diagnostics:
            print(format_diagnostic(d), file=sys.stderr)
        return _fail(f"{chart}: not downloaded: {exc.reason}")
    sent: dict[str, str] | msgspec.UnsetType = sources or msgspec.UNSET
    named = str(chart) if len(str(chart)) <= MAX_FILE_NAME else chart.name[-MAX_FILE_NAME:]
    with _logged_in(net, fb=fb, user=user) as shell:
        if isinstance(shell, int):
            return shell
        try:
            asked = DownloadArgs(source=source, preview=True, blocks=sent, file=named)
            preview = shell.send(Download, asked, timeout=timeout)
        except (TypeError, ValueError) as exc:
            return _fail(str(exc))
        if not preview.applied:
            return _refused("download", _as_given(preview, blocks))
        print(f"s7graph: {chart.name} over version {preview.version} on {net.cpu}/{shell.fb}:")
        for line in preview.lines:
            print(f"  {line}")
        if preview.removed and removed is None:
            steps = ", ".join(f"S{n}" for n in preview.removed)
            print(
                f"s7graph: download refused: active steps {steps} would be removed; choose "
                "--removed keep (the other steps go on) or --removed init",
                file=sys.stderr,
            )
            return 1
        if not yes and not _confirmed("Download into the running CPU?"):
            print(
                "s7graph: download not confirmed (--yes downloads without asking)",
                file=sys.stderr,
            )
            return 1
        args = DownloadArgs(source=source, blocks=sent, file=named)
        if preview.version is not None:
            args = msgspec.structs.replace(args, base=preview.version)
        if removed is not None:
            args = msgspec.structs.replace(args, removed=removed)
        try:
            reply = shell.send(Download, args, timeout=timeout)
        except (TypeError, ValueError) as exc:
            return _fail(str(exc))
    if not reply.applied and _unanswered(reply):
        # sent, no answer: the CPU may have swapped the chart before it went
        print(
            f"s7graph: download not confirmed: {reply.reason}; it may or may not have taken "
            "effect: `s7graph upload` shows the chart the CPU runs once it answers",
            file=sys.stderr,
        )
        return 1
    if not reply.applied:
        return _refused("download", _as_given(reply, blocks))
    for line in reply.lines:
        print(f"s7graph: {line}")
    print(f"s7graph: download applied on {net.cpu}/{shell.fb}: version {reply.version} runs")
    return 0


def _as_given(reply: CommandReply, blocks: Sequence[Path]) -> CommandReply:
    """``reply`` with each S7-SCL diagnostic's place (``valve.scl:13:12:``, the CPU knows a
    source by its file name) written as the command line gave the file
    (``v2/valve.scl:13:12:``), as a chart's diagnostics are."""
    named = {p.name: str(p) for p in blocks if str(p) != p.name}
    if not named:
        return reply
    place = re.compile(r"(?<![\w/.-])(" + "|".join(re.escape(n) for n in named) + r")(?=:\d+:\d+:)")

    def given(text: str) -> str:
        return place.sub(lambda found: named[found[1]], text)

    return msgspec.structs.replace(
        reply, reason=given(reply.reason), lines=[given(line) for line in reply.lines]
    )


def _kind(reply: CommandReply) -> str:
    """The reply's kind of refusal; "" when not said (an older CPU) or not known (a later
    CPU's): then only the reason's words tell."""
    return reply.kind if reply.kind in REFUSAL_KINDS else ""


def _unanswered(reply: CommandReply) -> bool:
    """No answer, or none readable (kind ``communication``; without a kind, the client's
    words ``no answer from CPU``): the command may or may not have taken effect."""
    kind = _kind(reply)
    return kind == "communication" if kind else reply.reason.startswith("no answer from CPU")


def _refused(op: str, reply: CommandReply) -> int:
    """A reply not *applied*: refused, or applied but not confirmed durable (kind
    ``timeout``; without a kind, a reason starting ``not confirmed:``)."""
    kind = _kind(reply)
    unconfirmed = kind == "timeout" if kind else reply.reason.startswith("not confirmed: ")
    how = "refused: "
    if unconfirmed:
        how = "" if reply.reason.startswith("not confirmed: ") else "not confirmed: "
    said = f"{op} {how}{reply.reason}"
    if reply.reason.startswith(f"{op} refused: "):  # the CPU said it already
        said = reply.reason
    print(f"s7graph: {said}", file=sys.stderr)
    for line in reply.lines:
        print(f"  {line}", file=sys.stderr)
    return 1


def _confirmed(question: str) -> bool:
    if not sys.stdin.isatty():
        return False
    return input(f"{question} [y/N] ").strip().lower() in ("y", "yes")


def _line(fb: str, update: StepStateUpdate) -> str:
    active = " ".join(f"S{n}" for n in update.active) or "-"
    parts = [f"cycle {update.cycle}", fb, update.mode, f"active {active}"]
    bad = sorted(set(update.disturbed) | set(update.latched))
    if bad:
        parts.append("error " + " ".join(f"S{n}" for n in bad))
    if update.events:
        parts.append("events " + " ".join(f"{e}:S{s}" for e, s in update.events))
    return "  ".join(parts)


def status_lines(status: CpuStatus) -> list[str]:
    """``s7graph status``: the CPU's state, its cycle statistics and where the longest and
    the last long cycle went (as TIA Portal's cycle time page, with the why)."""
    fbs = ", ".join(status.fbs) or "none"
    lines = [
        f"CPU {status.cpu}: {status.state}, cycle {status.cycle}, FBs {fbs}, "
        f"{status.forces} force job{'s' if status.forces != 1 else ''}"
    ]
    if status.reason:
        lines.append(f"STOP: {status.reason}")
    for what, event in (("STOP entry", status.stop), ("caused by", status.cause)):
        if event is not None:
            lines.append(f"  {what}: {when(event)}  {event_line(event)}")
    stats = status.stats
    if stats is None:
        return [*lines, "cycle time: not measured yet"]
    lines.append(
        f"cycle time: last {stats.last_ms:.1f} ms, min {stats.min_ms:.1f}, max {stats.max_ms:.1f};"
        f" scan {stats.exec_ms:.2f} ms on average; {stats.overruns} overruns"
        + (f"; {stats.long} over {stats.long_over_ms:.1f} ms" if stats.long_over_ms else "")
    )
    return lines + cycle_lines(stats)


def status_command(net: NetOptions) -> int:
    """Print ``status_lines`` of ``net.cpu``; 0, or 2 when it does not answer."""
    status = ask(net, BusClient.status)
    if isinstance(status, int):
        return status
    for line in status_lines(status):
        print(line)
    return 0


def alive_line(cpu: str, up: bool) -> str:
    """What ``watch`` says when CPU ``cpu`` appears on the bus (``up``) or goes."""
    return f"CPU {cpu} {'reachable' if up else 'disconnected'}"


def watch_command(net: NetOptions, *, fb: str | None, duration_s: float | None = None) -> int:
    """Print step changes of ``net.cpu`` live (of ``fb``, or of every FB); 0 at the end, 2
    when nothing can be watched: it runs no such FB, or none, or it did not appear within
    ``duration_s``. A CPU not there at the start is waited for (``web.cli.waiting``); one
    that comes back (``CPU cpu1 reachable``) shows its steps again, changed or not, and one
    of this machine started again is joined at its new socket (``web.cli.rejoin``)."""
    lock = threading.Lock()
    with cpu_reached(net, duration_s) as reached:
        if isinstance(reached, int):
            return reached
        status, duration_s = reached.status, reached.left_s
        without = "this CPU runs no GRAPH FB: no steps to watch (--address watches operands)"
        name, why = fb_to_read(status, fb, without=without)
        if why:
            return _fail(f"{net.cpu}: {why}")
        names = [name] if fb else list(status.fbs)
        last: dict[str, tuple[object, ...]] = {}
        stop = threading.Event()  # set by the end, or by a reader gone (| head -1)

        def show(name: str, update: StepStateUpdate) -> None:
            key = (update.mode, update.active, update.disturbed, update.latched)
            with lock:
                if last.get(name) == key and not update.events:
                    return
                last[name] = key
                say(_line(name, update), stop)

        def alive(up: bool) -> None:
            with lock:
                if not up:  # once back, its steps are shown again, changed or not
                    last.clear()
                say(alive_line(net.cpu, up), stop)

        def attach(client: BusClient) -> None:
            for name in names:
                client.follow(name, lambda u, n=name: show(n, u))  # type: ignore[misc]

        reached.link.keep(attach, alive)
        wait_until_stopped(duration_s, stop)
    return 0
