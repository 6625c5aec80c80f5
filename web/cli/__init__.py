"""The ``s7graph`` command line: ``run``, ``sim``, ``check``, ``import``, ``export``,
``--version``; for the bus ``web``, ``router``, ``watch``, ``status`` and the shell's
commands (``ack``, ``mode``, ..., ``force``, ``download``, ``stop``, ``start``); ``users``
and ``audit``.

Each command lives in its own module (``web/cli/*.py``) and is imported only when used, so
``s7graph check`` never pays for zenoh or viser. Errors are one line on stderr and a
non-zero exit, never a traceback.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

if TYPE_CHECKING:
    from s7graph.web.cli.net import NetOptions

from s7graph import __version__
from s7graph.engine.errors import S7Error
from s7graph.engine.runner import COMM_LOAD_PCT
from s7graph.web.commands import OPS

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    help="s7graph: S7-GRAPH sequential control on a soft PLC.",
    pretty_exceptions_enable=False,
)


def _show_version(value: bool) -> None:
    if value:
        typer.echo(f"s7graph {__version__}")
        raise typer.Exit(0)


@app.callback()
def _root(
    version_: Annotated[
        bool,
        typer.Option("--version", callback=_show_version, is_eager=True, help="Print the version."),
    ] = False,
) -> None:
    """s7graph: S7-GRAPH sequential control on a soft PLC."""


# ---------------------------------------------------------------- bus and page options

Listen = Annotated[
    list[str] | None,
    typer.Option(
        "--listen",
        help="A zenoh endpoint to listen on (several allowed), "
        "e.g. tcp/127.0.0.1:7447 or tls/0.0.0.0:7447.",
    ),
]
Connect = Annotated[
    list[str] | None,
    typer.Option(
        "--connect", help="A zenoh endpoint to connect to: a router or a CPU (several allowed)."
    ),
]
Host = Annotated[str, typer.Option(help="Address of the browser page (loopback unless --users).")]
Users = Annotated[
    Path | None, typer.Option(help="The users file (s7graph users add); without it: the demo.")
]
TlsCa = Annotated[Path | None, typer.Option(help="CA certificate (PEM) for tls/ endpoints.")]
TlsCert = Annotated[Path | None, typer.Option(help="This node's certificate (PEM), to listen.")]
TlsKey = Annotated[Path | None, typer.Option(help="This node's private key (PEM), to listen.")]
Origin = Annotated[
    list[str] | None,
    typer.Option(
        "--origin",
        help="Another Origin the page may be opened from (the public https URL behind a "
        "reverse proxy).",
    ),
]
CpuName = Annotated[str, typer.Option("--cpu", help="The CPU's name on the bus.")]
FbName = Annotated[str | None, typer.Option("--fb", help="The FB (default: the CPU's first).")]
UserName = Annotated[str, typer.Option("--user", help="Log in as this user.")]
UsersFileArg = Annotated[Path, typer.Option("--file", help="The users file.")]


def _net(**kw: Any) -> NetOptions:
    from s7graph.web.cli.net import NetOptions

    for key in ("listen", "connect", "origins"):
        kw[key] = tuple(kw.get(key) or ())
    return NetOptions(**kw)


def _positive_ms(value: float | None) -> float | None:
    if value is not None and not value > 0:
        raise typer.BadParameter("--max-cycle-ms must be more than 0 ms")
    return value


def _rt_priority(value: int | None) -> int | None:
    if value is not None and not 0 <= value <= 98:
        raise typer.BadParameter("--rt-priority must be 0 (normal scheduling) to 98")
    return value


def _scan_priority(value: int | None) -> int | None:
    """The Runner's ``rt_priority`` for ``--rt-priority``: the default, or None for 0; a
    priority asked for that the system refuses is one note on stderr."""
    from s7graph.engine.runner import RT_PRIORITY, realtime_allowed

    if value is None:
        return RT_PRIORITY
    if value == 0:
        return None
    if not realtime_allowed(value):
        print(
            f"s7graph: note: real-time priority {value} refused by the system (needs root, "
            "CAP_SYS_NICE or an rtprio limit): the scan runs at normal priority",
            file=sys.stderr,
        )
    return value


def _restart_type(value: str | None) -> str | None:
    if value is not None and value.lower() not in ("warm", "hot", "cold"):
        raise typer.BadParameter("--restart must be warm, hot or cold")
    return value.lower() if value is not None else None


_ENTRY_ARGS: list[str] | None = None
"""The command line of ``main()`` run as the program (not called with ``argv``)."""


def _supervised() -> bool:
    """Whether this ``run`` becomes the supervisor of a CPU process of its own
    (``web/cli/supervisor.py``): as the program, on Linux, not yet the supervised CPU."""
    from s7graph.web.cli.supervisor import MARKS_ENV

    child = MARKS_ENV in os.environ
    return _ENTRY_ARGS is not None and hasattr(os, "memfd_create") and not child


# The options of ``run`` (``s7graph run --help``).
ProgramArg = Annotated[
    Path, typer.Argument(help="A Python program of blocks (.py) or a chart (.s7g).")
]
StateFile = Annotated[
    Path | None,
    typer.Option(help="SQLite file for retentive data (default: beside the program)."),
]
MaxCycleMs = Annotated[
    float | None,
    typer.Option(
        callback=_positive_ms,
        help="Maximum cycle time in ms; a longer scan is a time error (OB80, else STOP). "
        "Default: 150 (S7's), 1000 with --web (the view shares the process); "
        "for a program, its CPU dict's max_cycle_ms, else 150.",
    ),
]
Duration = Annotated[
    float | None, typer.Option(help="Stop after this many seconds (default: until Ctrl-C).")
]
Record = Annotated[Path | None, typer.Option(help="Record the chart's run to a rerun .rrd file.")]
Restart = Annotated[
    str | None,
    typer.Option(
        callback=_restart_type,
        help="The startup from a saved state: warm (OB100, the sequencer initialized; "
        "the default), hot (OB101, it resumes where it was) or cold (OB102, everything "
        "to its initial values). For a program, its CPU dict's restart, else warm.",
    ),
]
Fresh = Annotated[
    bool,
    typer.Option(help="Start anew: keep an existing state file as FILE.old-N."),
]
RtPriority = Annotated[
    int | None,
    typer.Option(
        callback=_rt_priority,
        help="Real-time (SCHED_FIFO) priority of the scan thread, 1-98; 0: normal "
        "scheduling. Default 40 where the system allows it (root, CAP_SYS_NICE, an "
        "rtprio limit), else normal.",
    ),
]
CommLoad = Annotated[
    float,
    typer.Option(
        min=1,
        max=100,
        help="Scan cycle load from communication, % (charts): the share of the cycle "
        "commands may take at each scan boundary; the rest wait for the next. S7's "
        "default: 20.",
    ),
]
Core = Annotated[
    str | None,
    typer.Option(
        help="The processor kept for the scan thread, as an S7-1500 software controller "
        "keeps cores: auto (the last one, when the scan runs real-time on a machine of "
        "two or more; the default), off, or a processor number. The bus, the view and "
        "the writer run on the others. For a program, its CPU dict's core, else auto.",
    ),
]


@app.command()
def run(
    program: ProgramArg,
    plant: Annotated[Path | None, typer.Option(help="A simulated plant (.py) for a chart.")] = None,
    symbols: Annotated[Path | None, typer.Option(help="A symbol table file for a chart.")] = None,
    state: StateFile = None,
    cycle_ms: Annotated[float, typer.Option(help="Minimum cycle time in ms.")] = 10.0,
    max_cycle_ms: MaxCycleMs = None,
    duration_s: Duration = None,
    web: Annotated[bool, typer.Option(help="Serve the browser view (charts only).")] = False,
    port: Annotated[int, typer.Option(help="Port of the browser view.")] = 8080,
    record: Record = None,
    cpu: CpuName = "cpu1",
    listen: Listen = None,
    connect: Connect = None,
    host: Host = "127.0.0.1",
    users: Users = None,
    tls_ca: TlsCa = None,
    tls_cert: TlsCert = None,
    tls_key: TlsKey = None,
    origin: Origin = None,
    restart: Restart = None,
    fresh: Fresh = False,
    rt_priority: RtPriority = None,
    comm_load: CommLoad = COMM_LOAD_PCT,
    core: Core = None,
) -> None:
    """Run a program or a chart on the system clock until Ctrl-C."""
    if _supervised():
        from s7graph.web.cli.supervisor import supervise

        raise typer.Exit(supervise(_ENTRY_ARGS or []))
    priority = _scan_priority(rt_priority)
    if program.suffix.lower() == ".s7g":
        from s7graph.web.cli.run_chart import run_chart

        net = _net(
            cpu=cpu,
            listen=listen,
            connect=connect,
            host=host,
            users=users,
            tls_ca=tls_ca,
            tls_cert=tls_cert,
            tls_key=tls_key,
            origins=origin,
        )
        problem = net.problem(listening=web)
        if problem:
            print(f"s7graph: error: {problem}", file=sys.stderr)
            raise typer.Exit(2)
        if not 0 <= port <= 65535:
            print(f"s7graph: error: --port {port} is out of range (0-65535)", file=sys.stderr)
            raise typer.Exit(2)

        raise typer.Exit(
            run_chart(
                program,
                plant=plant,
                symbols=symbols,
                state=state,
                cycle_ms=cycle_ms,
                max_cycle_ms=max_cycle_ms,
                duration_s=duration_s,
                web=web,
                port=port,
                record=record,
                net=net,
                restart=restart or "warm",
                fresh=fresh,
                rt_priority=priority,
                comm_load_pct=comm_load,
                core=core if core is not None else "auto",
            )
        )
    from s7graph.web.cli.run_program import run_program

    raise typer.Exit(
        run_program(
            program,
            state=state,
            cycle_ms=cycle_ms,
            max_cycle_ms=max_cycle_ms,
            duration_s=duration_s,
            restart=restart,
            fresh=fresh,
            rt_priority=priority,
            core=core,
        )
    )


@app.command()
def check(
    chart: Annotated[Path, typer.Argument(help="A chart in .s7g source, or an .scl source.")],
    symbols: Annotated[Path | None, typer.Option(help="A symbol table file.")] = None,
) -> None:
    """Print a chart's (or an SCL source's) diagnostics; exit 0 clean, 1 warnings only, 2
    errors."""
    if chart.suffix.lower() == ".scl":
        from s7graph.web.cli.scl import check_scl_command

        raise typer.Exit(check_scl_command(chart, symbols=symbols))
    from s7graph.web.cli.check import check_command

    raise typer.Exit(check_command(chart, symbols=symbols))


@app.command()
def sim(
    chart: Annotated[Path, typer.Argument(help="A chart in .s7g source, or an .scl source.")],
    stimulus: Annotated[
        Path | None, typer.Option(help='JSONL stimulus: {"at_ms": 0, "set": {...}} a line.')
    ] = None,
    cycle_ms: Annotated[float, typer.Option(help="Virtual cycle time in ms.")] = 10.0,
    cycles: Annotated[int, typer.Option(help="Number of cycles to run.")] = 100,
    watch: Annotated[
        str, typer.Option(help="Comma-separated addresses, symbols or FB pins to report.")
    ] = "",
    trace: Annotated[
        Path | None, typer.Option(help="Write the per-cycle JSONL here (default stdout).")
    ] = None,
    symbols: Annotated[Path | None, typer.Option(help="A symbol table file.")] = None,
    plant: Annotated[
        Path | None, typer.Option(help="A simulated plant (.py) run each cycle.")
    ] = None,
) -> None:
    """Run a chart (or an .scl program) on the virtual clock: stimulus in, one JSON line
    per cycle out."""
    if chart.suffix.lower() == ".scl":
        from s7graph.web.cli.scl import sim_scl_command

        raise typer.Exit(
            sim_scl_command(
                chart,
                stimulus=stimulus,
                cycle_ms=cycle_ms,
                cycles=cycles,
                watch=watch,
                trace=trace,
                symbols=symbols,
                plant=plant,
            )
        )
    from s7graph.web.cli.sim import sim_command

    raise typer.Exit(
        sim_command(
            chart,
            stimulus=stimulus,
            cycle_ms=cycle_ms,
            cycles=cycles,
            watch=watch,
            trace=trace,
            symbols=symbols,
            plant=plant,
        )
    )


# ---------------------------------------------------------------- other formats


@app.command("import")
def import_(
    source: Annotated[
        Path, typer.Argument(help="A SimaticML GRAPH block, PLCopen XML or IEC text SFC file.")
    ],
    output: Annotated[
        Path | None, typer.Option("-o", "--output", help="The .s7g chart (default: stdout).")
    ] = None,
    symbols_out: Annotated[
        Path | None, typer.Option(help="Write the chart's symbols to this symbol table file.")
    ] = None,
    symbols: Annotated[
        Path | None, typer.Option(help="A symbol table the source's tags refer to (SimaticML).")
    ] = None,
    pou: Annotated[
        str | None, typer.Option(help="The POU to import when there are several.")
    ] = None,
    strict: Annotated[
        bool, typer.Option(help="Fail (exit 2) when anything cannot be mapped.")
    ] = False,
) -> None:
    """Import a chart written elsewhere; exit 0 as it is, 1 with warnings, 2 not imported."""
    from s7graph.web.cli.exchange import import_command

    raise typer.Exit(
        import_command(
            source,
            output=output,
            symbols_out=symbols_out,
            symbols=symbols,
            pou=pou,
            strict=strict,
        )
    )


@app.command()
def export(
    chart: Annotated[Path, typer.Argument(help="A chart in .s7g source.")],
    to: Annotated[str, typer.Option(help="plcopen or simaticml.")],
    output: Annotated[Path, typer.Option("-o", "--output", help="The file to write.")],
    symbols: Annotated[Path | None, typer.Option(help="A symbol table file.")] = None,
) -> None:
    """Export a chart as PLCopen TC6 XML or a TIA Portal SimaticML GRAPH block."""
    from s7graph.web.cli.exchange import export_command

    raise typer.Exit(export_command(chart, to=to, output=output, symbols=symbols))


# ---------------------------------------------------------------- the bus


@app.command()
def web(
    connect: Connect = None,
    cpu: Annotated[str | None, typer.Option("--cpu", help="The CPU (default: the first).")] = None,
    fb: FbName = None,
    host: Host = "127.0.0.1",
    port: Annotated[int, typer.Option(help="Port of the browser view (0: a free one).")] = 8080,
    tls_ca: TlsCa = None,
    origin: Origin = None,
    duration_s: Annotated[float | None, typer.Option(help="Stop after this many seconds.")] = None,
    child: Annotated[
        bool, typer.Option("--child", hidden=True, help="The view of a run --web.")
    ] = False,
) -> None:
    """Serve the browser view of a CPU on the bus, as a process of its own."""
    from s7graph.web.cli.view import web_command

    net = _net(connect=connect, host=host, tls_ca=tls_ca, origins=origin)
    raise typer.Exit(
        web_command(net, cpu=cpu, fb=fb, port=port, duration_s=duration_s, child=child)
    )


@app.command()
def router(
    listen: Listen = None,
    connect: Connect = None,
    users: Users = None,
    tls_ca: TlsCa = None,
    tls_cert: TlsCert = None,
    tls_key: TlsKey = None,
    duration_s: Annotated[float | None, typer.Option(help="Stop after this many seconds.")] = None,
) -> None:
    """Run a zenoh router where CPUs and views on several machines meet."""
    from s7graph.web.cli.router import router_command

    net = _net(
        listen=listen,
        connect=connect,
        users=users,
        tls_ca=tls_ca,
        tls_cert=tls_cert,
        tls_key=tls_key,
    )
    raise typer.Exit(router_command(net, duration_s))


@app.command()
def watch(
    cpu: CpuName = "cpu1",
    connect: Connect = None,
    fb: FbName = None,
    tls_ca: TlsCa = None,
    duration_s: Annotated[float | None, typer.Option(help="Stop after this many seconds.")] = None,
) -> None:
    """Print a CPU's step changes live (one line each)."""
    from s7graph.web.cli.remote import watch_command

    net = _net(cpu=cpu, connect=connect, tls_ca=tls_ca)
    raise typer.Exit(watch_command(net, fb=fb, duration_s=duration_s))


@app.command()
def status(cpu: CpuName = "cpu1", connect: Connect = None, tls_ca: TlsCa = None) -> None:
    """Print a CPU's state and cycle time, and where its longest cycles went."""
    from s7graph.web.cli.remote import status_command

    raise typer.Exit(status_command(_net(cpu=cpu, connect=connect, tls_ca=tls_ca)))


def _remote(
    op: str,
    args: dict[str, Any],
    cpu: str,
    connect: list[str] | None,
    fb: str | None,
    user: str,
    tls_ca: Path | None,
) -> None:
    from s7graph.web.cli.remote import send_command

    net = _net(cpu=cpu, connect=connect, tls_ca=tls_ca)
    raise typer.Exit(send_command(net, fb=fb, user=user, op=op, args=args))


@app.command()
def ack(
    user: UserName,
    cpu: CpuName = "cpu1",
    connect: Connect = None,
    fb: FbName = None,
    tls_ca: TlsCa = None,
    step: Annotated[int | None, typer.Option(help="Only this step (ACK_S).")] = None,
    message: Annotated[str | None, typer.Option(help="One message of the alarm list.")] = None,
) -> None:
    """Acknowledge the FB's supervision faults (ACK_EF), one step's or one message."""
    if message is not None:
        msg_id: int | str = int(message) if message.isdigit() else message
        _remote("ack_msg", {"msg_id": msg_id}, cpu, connect, fb, user, tls_ca)
    if step is not None:
        _remote("ack_step", {"step": step}, cpu, connect, fb, user, tls_ca)
    _remote("ack", {}, cpu, connect, fb, user, tls_ca)


@app.command()
def mode(
    new_mode: Annotated[str, typer.Argument(metavar="MODE", help="AUTO, MAN, TAP or TOP.")],
    user: UserName,
    cpu: CpuName = "cpu1",
    connect: Connect = None,
    fb: FbName = None,
    tls_ca: TlsCa = None,
) -> None:
    """Switch the FB's mode."""
    _remote("mode", {"mode": new_mode.upper()}, cpu, connect, fb, user, tls_ca)


@app.command()
def init(
    user: UserName,
    cpu: CpuName = "cpu1",
    connect: Connect = None,
    fb: FbName = None,
    tls_ca: TlsCa = None,
) -> None:
    """Initialize the sequencer (INIT_SQ)."""
    _remote("init", {}, cpu, connect, fb, user, tls_ca)


@app.command()
def off(
    user: UserName,
    cpu: CpuName = "cpu1",
    connect: Connect = None,
    fb: FbName = None,
    tls_ca: TlsCa = None,
) -> None:
    """Switch the sequencer off (OFF_SQ)."""
    _remote("off", {}, cpu, connect, fb, user, tls_ca)


@app.command("stop")
def stop_cpu(
    user: UserName,
    cpu: CpuName = "cpu1",
    connect: Connect = None,
    fb: FbName = None,
    tls_ca: TlsCa = None,
) -> None:
    """Put the CPU in STOP, as its RUN/STOP switch (engineer; outputs to 0)."""
    _remote("stop", {}, cpu, connect, fb, user, tls_ca)


@app.command("start")
def start_cpu(
    user: UserName,
    cpu: CpuName = "cpu1",
    connect: Connect = None,
    fb: FbName = None,
    tls_ca: TlsCa = None,
) -> None:
    """Start the CPU from STOP with its configured restart (--restart of its run; engineer)."""
    _remote("start", {}, cpu, connect, fb, user, tls_ca)


@app.command("step-on")
def step_on(
    step: Annotated[int, typer.Argument(help="The step number.")],
    user: UserName,
    cpu: CpuName = "cpu1",
    connect: Connect = None,
    fb: FbName = None,
    tls_ca: TlsCa = None,
) -> None:
    """Activate a step (MAN, S_ON)."""
    _remote("step_on", {"step": step}, cpu, connect, fb, user, tls_ca)


@app.command("step-off")
def step_off(
    step: Annotated[int, typer.Argument(help="The step number.")],
    user: UserName,
    cpu: CpuName = "cpu1",
    connect: Connect = None,
    fb: FbName = None,
    tls_ca: TlsCa = None,
) -> None:
    """Deactivate a step (MAN, S_OFF)."""
    _remote("step_off", {"step": step}, cpu, connect, fb, user, tls_ca)


@app.command("t-push")
def t_push(
    user: UserName,
    cpu: CpuName = "cpu1",
    connect: Connect = None,
    fb: FbName = None,
    tls_ca: TlsCa = None,
) -> None:
    """Switch a ready transition (TAP, TOP; T_PUSH)."""
    _remote("t_push", {}, cpu, connect, fb, user, tls_ca)


@app.command("send", context_settings={"ignore_unknown_options": True})
def send(
    op: Annotated[str, typer.Argument(metavar="OP", help="One of " + ", ".join(OPS) + ".")],
    arguments: Annotated[
        list[str] | None, typer.Argument(metavar="[NAME=VALUE]...", help="Its arguments.")
    ] = None,
    user: Annotated[str | None, typer.Option("--user", help="Log in as this user.")] = None,
    cpu: CpuName = "cpu1",
    connect: Connect = None,
    fb: FbName = None,
    tls_ca: TlsCa = None,
) -> None:
    """Send any command of the vocabulary with its arguments (s7graph send halt on=true)."""
    from s7graph.web.commands import command_args

    try:
        args = command_args(op, arguments or [])
    except ValueError as exc:
        raise typer.BadParameter(str(exc)) from None
    if user is None:
        raise typer.BadParameter("give the user to log in as with --user")
    _remote(op, args, cpu, connect, fb, user, tls_ca)


@app.command(context_settings={"ignore_unknown_options": True})  # MW10 -5: a value
def force(
    job: Annotated[
        list[str] | None,
        typer.Argument(
            metavar="ADDRESS VALUE|off",
            help="An I, Q or M address or a symbol, and TRUE/FALSE, a number or "
            "an S7 literal (16#00FF, T#5S); off unforces it.",
        ),
    ] = None,
    user: Annotated[str | None, typer.Option("--user", help="Log in as this user.")] = None,
    cpu: CpuName = "cpu1",
    connect: Connect = None,
    fb: FbName = None,
    tls_ca: TlsCa = None,
    list_: Annotated[bool, typer.Option("--list", help="Print the force jobs.")] = False,
    all_: Annotated[bool, typer.Option("--all", help="With off: unforce every job.")] = False,
) -> None:
    """Force an input, output or flag until unforced (engineers), unforce it, or list the
    force jobs."""
    words = list(job or [])
    if list_:
        if words or all_:
            raise typer.BadParameter("--list takes no address, value or --all")
        from s7graph.web.cli.remote import list_forces

        raise typer.Exit(list_forces(_net(cpu=cpu, connect=connect, tls_ca=tls_ca)))
    if user is None:
        raise typer.BadParameter("give the user to log in as with --user")
    if all_:
        if [w.lower() for w in words] != ["off"]:
            raise typer.BadParameter("--all unforces every job: s7graph force --all off")
        _remote("force", {"all": True}, cpu, connect, fb, user, tls_ca)
    if len(words) != 2:
        raise typer.BadParameter("give ADDRESS VALUE (or ADDRESS off), e.g. force I0.3 TRUE")
    address, value = words
    args = {"address": address, "value": None if value.lower() == "off" else value}
    _remote("force", args, cpu, connect, fb, user, tls_ca)


@app.command()
def download(
    chart: Annotated[Path, typer.Argument(help="The changed chart (.s7g).")],
    user: UserName,
    cpu: CpuName = "cpu1",
    connect: Connect = None,
    fb: FbName = None,
    tls_ca: TlsCa = None,
    removed: Annotated[
        str | None,
        typer.Option(
            help="Active steps the change removes: keep (the other steps go on) "
            "or init (initialize the sequencer)."
        ),
    ] = None,
    yes: Annotated[bool, typer.Option("--yes", help="Download without asking.")] = False,
) -> None:
    """Download a changed chart into the running FB (online change): the change summary,
    then the swap at a scan boundary with the state carried over by step number."""
    from s7graph.web.cli.remote import download_command

    if removed is not None and removed not in ("keep", "init"):
        raise typer.BadParameter("--removed must be keep or init")
    net = _net(cpu=cpu, connect=connect, tls_ca=tls_ca)
    raise typer.Exit(download_command(net, chart, fb=fb, user=user, removed=removed, yes=yes))


# ---------------------------------------------------------------- users and audit

users_app = typer.Typer(no_args_is_help=True, help="The users file: add, list, remove, passwd.")
app.add_typer(users_app, name="users")
PasswordStdin = Annotated[
    bool, typer.Option("--password-stdin", help="Read the password from standard input.")
]


@users_app.command("add")
def users_add(
    name: Annotated[str, typer.Argument(help="1-32 of A-Z a-z 0-9 . _ -")],
    role: Annotated[str, typer.Option(help="viewer, operator or engineer.")],
    file: UsersFileArg = Path("users.json"),
    password_stdin: PasswordStdin = False,
) -> None:
    """Add a user with a role (the password from a prompt or --password-stdin)."""
    from s7graph.web.cli import users as cmd

    raise typer.Exit(cmd.users_add(file, name, role, password_stdin=password_stdin))


@users_app.command("list")
def users_list(file: UsersFileArg = Path("users.json")) -> None:
    """List the users and their roles."""
    from s7graph.web.cli import users as cmd

    raise typer.Exit(cmd.users_list(file))


@users_app.command("remove")
def users_remove(name: str, file: UsersFileArg = Path("users.json")) -> None:
    """Remove a user (their logins stop working at once)."""
    from s7graph.web.cli import users as cmd

    raise typer.Exit(cmd.users_remove(file, name))


@users_app.command("passwd")
def users_passwd(
    name: str, file: UsersFileArg = Path("users.json"), password_stdin: PasswordStdin = False
) -> None:
    """Change a user's password."""
    from s7graph.web.cli import users as cmd

    raise typer.Exit(cmd.users_passwd(file, name, password_stdin=password_stdin))


@app.command()
def audit(
    state: Annotated[Path, typer.Option(help="The CPU's SQLite state file.")],
    since: Annotated[
        str | None, typer.Option(help="From this time (2026-11-22T08:30, 08:30) or age (2h).")
    ] = None,
) -> None:
    """Print who commanded what, when, from where, applied or refused."""
    from s7graph.web.cli.audit import audit_command

    raise typer.Exit(audit_command(state, since))


def main(argv: list[str] | None = None) -> int:
    """Entry point of the console script; turns every known error into one stderr line.

    Run as the program (``argv`` None), ``s7graph run`` supervises its CPU as a process of
    its own (``web.cli.supervisor``); called with ``argv`` it runs in this process."""
    global _ENTRY_ARGS
    _ENTRY_ARGS = sys.argv[1:] if argv is None else None
    try:
        rc = app(args=argv, standalone_mode=False)
    except S7Error as exc:
        print(f"s7graph: error: {exc}", file=sys.stderr)
        return 2
    except typer.Exit as exc:
        return int(exc.exit_code or 0)
    except SystemExit as exc:  # click usage errors
        return int(exc.code or 0) if isinstance(exc.code, int) else 2
    except Exception as exc:
        message = getattr(exc, "format_message", None)
        if callable(message):  # a usage error of the command line (typer's click)
            print(f"s7graph: error: {message()} (see s7graph --help)", file=sys.stderr)
            code = getattr(exc, "exit_code", 2)
            return code if isinstance(code, int) else 2
        if type(exc).__name__ == "Abort":  # Ctrl-C at a prompt
            return 130
        print(f"s7graph: internal error: {type(exc).__name__}: {exc}", file=sys.stderr)
        return 2
    return rc if isinstance(rc, int) else 0


if __name__ == "__main__":
    sys.exit(main())
