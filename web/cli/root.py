"""The ``s7graph`` command line's commands (``main`` in ``web/cli/__init__.py`` starts
them): ``run``, ``sim``, ``check``, ``xref``, ``import``, ``export``,
``--version``; for the bus ``web``, ``opcua``, ``router``, ``watch``, ``status``, ``diag``
and the shell's commands (``ack``, ``mode``, ..., ``force``, ``modify``, ``download``,
``stop``, ``start``, ``mres``); ``users``, ``audit`` and ``certs``.

The shell's command of an op is built from the op's struct (``shell`` in
``web.commands``): one loop makes ``ack``, ``mode``, ``init`` ... with the op's argument
as the positional; ``send`` gives any op; ``force``, ``modify`` and ``download`` are
written here.

Each command lives in its own module (``web/cli/*.py``) and is imported only when used, so
``s7graph check`` never pays for zenoh or viser. Errors are one line on stderr and a
non-zero exit, never a traceback.
"""

from __future__ import annotations

import contextvars
import functools
import inspect
import os
import re
import sys
from collections.abc import Callable
from inspect import Parameter, Signature
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import msgspec.inspect as mi
import typer
from typer.main import get_command

if TYPE_CHECKING:
    from s7graph.web.cli.net import NetOptions
    from s7graph.web.cli.run_chart import OpcuaFace

from s7graph.engine.errors import S7Error, internal_error
from s7graph.engine.watchdog import COMM_LOAD_PCT
from s7graph.web.commands import (
    COMMAND_TYPES,
    OPS,
    Args,
    Command,
    Force,
    ForceArgs,
    Modify,
    ModifyArgs,
    Shell,
    args_of,
    argument_field,
    command_args,
    command_type,
)

_TYPE_WORDS = {"bool": "", "path": "FILE", "Path": "FILE", "float": "NUMBER", "int": "INTEGER"}


def _type_words(shown: str) -> str:
    """An option's type as typer (0.2x) shows it in the help, Python's (``<list[Path]>``,
    ``<bool>``, ``<float>``), in a user's words: ``FILE...``, nothing for a flag,
    ``NUMBER``; a choice (``<warm|hot|cold>``) as it is."""
    inner = shown[1:-1] if shown.startswith("<") and shown.endswith(">") else shown
    several = inner.startswith("list[") and inner.endswith("]")
    inner = inner[5:-1] if several else inner
    if "|" in inner:  # a choice: its values as typed
        words = inner
    else:
        words = _TYPE_WORDS.get(inner, "TEXT" if inner == "str" else inner.upper())
    return f"{words}..." if several and words else words


def _plain_help_types() -> None:
    """Say each option's and argument's type in the help in words (``_type_words``): the
    typer this runs with may show Python's; one without ``display_type`` is left as it is."""
    import typer.core

    for kind in ("TyperOption", "TyperArgument"):
        cls = getattr(typer.core, kind, None)
        shown = getattr(cls, "display_type", None)
        if cls is None or shown is None or getattr(shown, "in_words", False):
            continue

        def display_type(self: Any, ctx: Any, _shown: Any = shown) -> str:
            return _type_words(str(_shown(self, ctx)))

        display_type.in_words = True  # type: ignore[attr-defined]
        cls.display_type = display_type


def _plain_usage_names() -> None:
    """Name an argument in the usage line as a user expects, ``s7graph sim [OPTIONS] CHART``
    (``[CHART]`` when it may be left out, ``CHART...`` for several), not typer's
    ``{chart}``; a metavar given is shown as it is; a typer without ``_usage_display_name``
    is left as it is."""
    import typer.core

    cls = getattr(typer.core, "TyperArgument", None)
    shown = getattr(cls, "_usage_display_name", None)
    if cls is None or shown is None or getattr(shown, "in_words", False):
        return

    def usage_name(self: Any) -> str:
        if self.metavar:  # written as the usage line shows it: OP, [NAME=VALUE]...
            return str(self.metavar)
        name = str(self.name or "").upper()
        name = name if self.required else f"[{name}]"
        return f"{name}..." if self.nargs != 1 else name

    usage_name.in_words = True  # type: ignore[attr-defined]
    cls._usage_display_name = usage_name


_plain_help_types()
_plain_usage_names()

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    help="s7graph: S7-GRAPH sequential control on a soft PLC.",
    pretty_exceptions_enable=False,
)


def _show_version(value: bool) -> None:
    if value:
        from s7graph import __version__

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
TlsCert = Annotated[
    Path | None,
    typer.Option(help="This node's certificate (PEM; s7graph certs issue): mutual TLS."),
]
TlsKey = Annotated[Path | None, typer.Option(help="This node's private key (PEM).")]
BusUser = Annotated[
    str | None,
    typer.Option(
        "--bus-user",
        help="This node's user name on the bus (zenoh usrpwd; a CPU's: cpu.NAME), its "
        "password from --bus-password-file or S7GRAPH_BUS_PASSWORD.",
    ),
]
BusPasswordFile = Annotated[
    Path | None,
    typer.Option("--bus-password-file", help="The file whose first line is --bus-user's password."),
]
BusUsers = Annotated[
    Path | None,
    typer.Option(
        "--bus-users", help="Who may join where this node listens: user:password lines (0600)."
    ),
]
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


_CREDENTIALS: contextvars.ContextVar[tuple[tuple[str, Any], ...]] = contextvars.ContextVar(
    "s7graph_credentials", default=()
)
"""The bus credentials given to the command running now (``_with_credentials``)."""


def _net(**kw: Any) -> NetOptions:
    """The command's network options; the credential options it did not name itself come
    from ``_with_credentials``."""
    from s7graph.web.cli.net import NetOptions

    for key in ("listen", "connect", "origins", "relays"):
        kw[key] = tuple(kw.get(key) or ())
    for key, value in _CREDENTIALS.get():
        if kw.get(key) is None:
            kw[key] = value
    return NetOptions(**kw)


_CREDENTIAL_OPTIONS: dict[str, Any] = {
    "tls_cert": TlsCert,
    "tls_key": TlsKey,
    "bus_user": BusUser,
    "bus_password_file": BusPasswordFile,
}
_LISTENER_OPTIONS: dict[str, Any] = {"bus_users": BusUsers}


def _with_credentials(fn: Callable[..., Any]) -> Callable[..., Any]:
    """``fn`` with the bus-credential options it lacks when it joins the bus (it has a
    ``--connect``): ``--tls-cert``, ``--tls-key``, ``--bus-user``, ``--bus-password-file``,
    and ``--bus-users`` where it listens; their values reach ``_net`` while it runs. So
    every command on the bus proves who it is the same way, the shell's included."""
    signature = inspect.signature(fn, eval_str=True)
    have = signature.parameters
    listens = "listen" in have and have["listen"].annotation == Listen  # the bus's, not OPC UA's
    wanted = dict(_CREDENTIAL_OPTIONS, **(_LISTENER_OPTIONS if listens else {}))
    extra = {name: kind for name, kind in wanted.items() if name not in have}
    if "connect" not in have or not extra:
        return fn

    @functools.wraps(fn)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        given = tuple((name, kwargs.pop(name, None)) for name in extra)
        token = _CREDENTIALS.set(given)
        try:
            return fn(*args, **kwargs)
        finally:
            _CREDENTIALS.reset(token)

    added = [
        inspect.Parameter(name, inspect.Parameter.KEYWORD_ONLY, default=None, annotation=kind)
        for name, kind in extra.items()
    ]
    params = list(have.values())
    wrapper.__signature__ = signature.replace(parameters=[*params, *added])  # type: ignore[attr-defined]
    wrapper.__annotations__ = {
        **{p.name: p.annotation for p in params},
        **extra,
        "return": signature.return_annotation,
    }
    return wrapper


def _credentials_everywhere() -> None:
    """Give every command registered so far that joins the bus the credential options."""
    for info in app.registered_commands:
        if info.callback is not None:
            info.callback = _with_credentials(info.callback)


MAX_CYCLE_MS = 3_600_000.0  # an hour: a cycle time beyond is no cycle
MAX_DURATION_S = 1e9  # about 31 years: longer is "until stopped"
MAX_CYCLES = 100_000_000
_POSITIVE_MS = f"from more than 0 to {MAX_CYCLE_MS:,.0f} ms"
_VIRTUAL_MS = f"from 0 to {MAX_CYCLE_MS:,.0f} ms"
_DURATION = f"from 0 to {MAX_DURATION_S:,.0f} s"
_CYCLES = f"from 0 to {MAX_CYCLES:,}"
_PRIORITY = "from 0 (normal scheduling) to 98"
_COMM_LOAD = "from 1 to 100 %"
_PORT = "from 0 (a free one) to 65535"


def _positive_ms(value: float | None) -> float | None:
    if value is not None and not 0 < value <= MAX_CYCLE_MS:
        raise typer.BadParameter(f"{_POSITIVE_MS}, not {value:g}")
    return value


def _duration(value: float | None) -> float | None:
    if value is not None and not 0 <= value <= MAX_DURATION_S:
        raise typer.BadParameter(f"{_DURATION}, not {value:g}")
    return value


def _cycle_ms(value: float) -> float:
    if not 0 < value <= MAX_CYCLE_MS:
        raise typer.BadParameter(f"{_POSITIVE_MS}, not {value:g}")
    return value


def _virtual_cycle_ms(value: float) -> float:
    if not 0 <= value <= MAX_CYCLE_MS:  # 0: the virtual clock stands still
        raise typer.BadParameter(f"{_VIRTUAL_MS}, not {value:g}")
    return value


def _port(value: int) -> int:
    """``--port`` of the browser view (``run --web``, ``web``); 0 picks a free one."""
    if not 0 <= value <= 65535:
        raise typer.BadParameter(f"{_PORT}, not {value}")
    return value


def _entries(value: int) -> int:
    """``diag -n``: as many entries as one answer on the bus carries."""
    if not 1 <= value <= _max_entries():
        raise typer.BadParameter(f"{_range_of('-n')}, not {value}")
    return value


def _cycles(value: int) -> int:
    if not 0 <= value <= MAX_CYCLES:
        raise typer.BadParameter(f"{_CYCLES}, not {value}")
    return value


def _rt_priority(value: int | None) -> int | None:
    if value is not None and not 0 <= value <= 98:
        raise typer.BadParameter(f"{_PRIORITY}, not {value}")
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


Blocks = Annotated[
    list[Path] | None,
    typer.Option(
        "--blocks",
        help="An S7-SCL source of the blocks the chart or program calls (several allowed, "
        "compiled in order before it).",
    ),
]

# The options of ``run`` (``s7graph run --help``).
ProgramArg = Annotated[
    Path,
    typer.Argument(
        help="A Python program of blocks (.py), an S7-SCL program (.scl) or a chart (.s7g)."
    ),
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
        "Default: 150 (S7's), with --web too (the view runs in a process of its own); "
        "for a program, its CPU dict's max_cycle_ms, else 150.",
    ),
]
Duration = Annotated[
    float | None,
    typer.Option(callback=_duration, help="Stop after this many seconds (default: until Ctrl-C)."),
]
StopAfter = Annotated[
    float | None, typer.Option(callback=_duration, help="Stop after this many seconds.")
]
CycleMs = Annotated[float, typer.Option(callback=_cycle_ms, help="Minimum cycle time in ms.")]
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


def _comm_load(value: float) -> float:
    if not 1 <= value <= 100:  # NaN too
        raise typer.BadParameter(f"{_COMM_LOAD}, not {value:g}")
    return value


_RANGES: dict[Callable[..., Any], str] = {
    _positive_ms: _POSITIVE_MS,
    _duration: _DURATION,
    _cycle_ms: _POSITIVE_MS,
    _virtual_cycle_ms: _VIRTUAL_MS,
    _cycles: _CYCLES,
    _rt_priority: _PRIORITY,
    _comm_load: _COMM_LOAD,
    _port: _PORT,
}
"""A range check's words for its option's range: said too when the option is given no
number (``_not_a_number``)."""


ViewPort = Annotated[
    int, typer.Option(callback=_port, help="Port of the browser view (0: a free one).")
]
CommLoad = Annotated[
    float,
    typer.Option(
        callback=_comm_load,
        help="Scan cycle load from communication, %: the share of the cycle "
        "commands may take at each scan boundary; the rest wait for the next. S7's "
        "default: 20.",
    ),
]
Core = Annotated[
    str | None,
    typer.Option(
        help="The processor kept for the scan thread, as an S7-1500 software controller "
        "keeps cores: auto (the last one no other CPU of the machine keeps, when the scan "
        "runs real-time on a machine of two or more; the default), off, or a processor "
        "number. The bus, the view and the writer run on the others. For a program, its "
        "CPU dict's core, else auto.",
    ),
]


OpcuaUrl = Annotated[
    str | None,
    typer.Option(
        "--opcua",
        metavar="opc.tcp://HOST:PORT",
        help="Serve OPC UA there from a process of its own (s7graph opcua as a child, "
        "restarted when it ends; charts only).",
    ),
]
OpcuaCert = Annotated[
    Path | None,
    typer.Option(help="The OPC UA server's certificate (PEM or DER; with --opcua-key)."),
]
OpcuaKey = Annotated[Path | None, typer.Option(help="The OPC UA server's private key.")]
_WRITES_HELP = (
    "What an OPC UA client's write of a symbol sends: force (a force job on an input, "
    "output or flag, held until unforced; the default) or modify (written once, as an "
    "S7-1500 writes a PLC tag; inputs, outputs, flags, data blocks and a chart's variables)."
)
OpcuaWrites = Annotated[
    str | None, typer.Option("--opcua-writes", metavar="force|modify", help=_WRITES_HELP)
]


@app.command()
def run(
    program: ProgramArg,
    plant: Annotated[Path | None, typer.Option(help="A simulated plant (.py) for a chart.")] = None,
    symbols: Annotated[Path | None, typer.Option(help="A symbol table file for a chart.")] = None,
    state: StateFile = None,
    cycle_ms: CycleMs = 10.0,
    max_cycle_ms: MaxCycleMs = None,
    duration_s: Duration = None,
    web: Annotated[bool, typer.Option(help="Serve the browser view.")] = False,
    port: ViewPort = 8080,
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
    blocks: Blocks = None,
    opcua: OpcuaUrl = None,
    opcua_cert: OpcuaCert = None,
    opcua_key: OpcuaKey = None,
    opcua_writes: OpcuaWrites = None,
) -> None:
    """Run a program or a chart on the system clock until Ctrl-C."""
    # As the program, this runs in the CPU's process its supervisor started (``main`` in
    # web/cli/__init__.py decides, before the commands are imported).
    priority = _scan_priority(rt_priority)
    face = _opcua_face(program, opcua, users, opcua_cert, opcua_key, opcua_writes)
    net = _cpu_net(
        web,
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
    if program.suffix.lower() == ".scl" or (blocks and program.suffix.lower() != ".s7g"):
        scl: dict[str, Any] = {"symbols": symbols, "state": state, "cycle_ms": cycle_ms}
        scl |= {"duration_s": duration_s, "max_cycle_ms": max_cycle_ms, "fresh": fresh, "web": web}
        scl |= {"restart": restart, "rt_priority": priority, "net": net, "port": port, "core": core}
        _run_scl_program(program, blocks or [], plant, record, comm_load_pct=comm_load, **scl)
    if program.suffix.lower() == ".s7g":
        from s7graph.web.cli.run_chart import run_chart

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
                blocks=blocks or [],
                opcua=face,
            )
        )
    from s7graph.web.cli.run_program import run_program

    _chart_only(plant=plant, symbols=symbols, record=record)
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
            net=net,
            web=web,
            port=port,
            comm_load_pct=comm_load,
        )
    )


def _cpu_net(web: bool, **kw: Any) -> NetOptions:
    """A CPU's network options (``run``), checked: what is refused is one line, exit 2
    (``--port`` is checked as it is parsed: ``_port``)."""
    net = _net(**kw)
    problem = net.problem(listening=web, role="cpu")
    if problem:
        print(f"s7graph: error: {problem}", file=sys.stderr)
        raise typer.Exit(2)
    return net


def _run_scl_program(
    program: Path, blocks: list[Path], plant: Path | None, record: Path | None, **options: Any
) -> None:
    """``run PROGRAM.scl``: on the system clock, on the bus with ``--listen``/``--connect``
    or ``--web`` as a Python program (``web.cli.run_scl``); ``--blocks`` beside a Python
    program, a plant or a recording are refused."""
    if program.suffix.lower() != ".scl":
        print("s7graph: error: --blocks goes with a chart or an .scl program", file=sys.stderr)
        raise typer.Exit(2)
    _chart_only(plant=plant, record=record)
    from s7graph.web.cli.run_scl import run_scl

    raise typer.Exit(run_scl(program, blocks=blocks, **options))


def _chart_only(**given: Path | None) -> None:
    """``run PROGRAM.py``: the options of a chart's run are refused (exit 2, one line)."""
    for name, value in given.items():
        if value is not None:
            print(f"s7graph: error: --{name} is for a chart (.s7g), not a program", file=sys.stderr)
            raise typer.Exit(2)


def _opcua_face(
    program: Path,
    url: str | None,
    users: Path | None,
    cert: Path | None,
    key: Path | None,
    writes: str | None = None,
) -> OpcuaFace | None:
    """``run --opcua``'s child, checked before the CPU starts (exit 2 with one line)."""
    if url is not None and program.suffix.lower() != ".s7g":
        print("s7graph: error: --opcua serves a chart's CPU (.s7g)", file=sys.stderr)
        raise typer.Exit(2)
    if url is None:
        if cert is not None or key is not None or writes is not None:
            print(
                "s7graph: error: --opcua-cert, --opcua-key and --opcua-writes go with --opcua",
                file=sys.stderr,
            )
            raise typer.Exit(2)
        return None
    from s7graph.web.cli.opcua import writes_problem
    from s7graph.web.cli.run_chart import OpcuaFace
    from s7graph.web.opcua.server import listen_problem

    problem = listen_problem(url, users=users is not None, cert=cert, key=key)
    problem = problem or writes_problem(writes, "--opcua-writes")
    if problem:
        print(f"s7graph: error: --opcua: {problem}", file=sys.stderr)
        raise typer.Exit(2)
    return OpcuaFace(url=url, cert=cert, key=key, writes=writes or "force")


def _a_chart(path: Path, command: str) -> None:
    """Refuse at once, in one line (exit 2), a file ``command`` cannot read by its suffix: a
    Python program, a chart ``s7graph import`` reads (``web.cli.report.not_a_chart``)."""
    from s7graph.web.cli.report import fail, not_a_chart

    problem = not_a_chart(path, f"{command} takes a chart (.s7g) or an S7-SCL source (.scl)")
    if problem:
        raise typer.Exit(fail(problem))


@app.command()
def check(
    chart: Annotated[Path, typer.Argument(help="A chart in .s7g source, or an .scl source.")],
    symbols: Annotated[Path | None, typer.Option(help="A symbol table file.")] = None,
    blocks: Blocks = None,
) -> None:
    """Print a chart's (or an SCL source's) diagnostics; exit 0 clean, 1 warnings only, 2
    errors."""
    _a_chart(chart, "check")
    if chart.suffix.lower() == ".scl":
        from s7graph.web.cli.scl import check_scl_command

        raise typer.Exit(check_scl_command(chart, symbols=symbols, blocks=blocks or []))
    from s7graph.web.cli.check import check_command

    raise typer.Exit(check_command(chart, symbols=symbols, blocks=blocks or []))


@app.command()
def xref(
    chart: Annotated[
        Path, typer.Argument(help="A chart in .s7g source, or an S7-SCL program (.scl).")
    ],
    symbols: Annotated[Path | None, typer.Option(help="A symbol table file.")] = None,
    operand: Annotated[
        str | None,
        typer.Option(help="Only this operand's uses: a symbol, an address or a variable."),
    ] = None,
    as_json: Annotated[bool, typer.Option("--json", help="One JSON object.")] = False,
    blocks: Annotated[
        list[Path] | None,
        typer.Option(
            "--blocks", help="An S7-SCL source whose blocks' uses are listed too (several allowed)."
        ),
    ] = None,
) -> None:
    """Print a chart's cross-references: where each operand is used, and how."""
    _a_chart(chart, "xref")
    from s7graph.web.cli.xref import xref_command

    raise typer.Exit(
        xref_command(chart, symbols=symbols, operand=operand, as_json=as_json, blocks=blocks or [])
    )


@app.command()
def sim(
    chart: Annotated[Path, typer.Argument(help="A chart in .s7g source, or an .scl source.")],
    stimulus: Annotated[
        Path | None, typer.Option(help='JSONL stimulus: {"at_ms": 0, "set": {...}} a line.')
    ] = None,
    cycle_ms: Annotated[
        float, typer.Option(callback=_virtual_cycle_ms, help="Virtual cycle time in ms.")
    ] = 10.0,
    cycles: Annotated[int, typer.Option(callback=_cycles, help="Number of cycles to run.")] = 100,
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
    blocks: Blocks = None,
) -> None:
    """Run a chart (or an .scl program) on the virtual clock: stimulus in, one JSON line
    per cycle out."""
    _a_chart(chart, "sim")
    if chart.suffix.lower() == ".scl":
        from s7graph.web.cli.scl import sim_scl_command as command
    else:
        from s7graph.web.cli.sim import sim_command as command

    raise typer.Exit(
        command(
            chart,
            stimulus=stimulus,
            cycle_ms=cycle_ms,
            cycles=cycles,
            watch=watch,
            trace=trace,
            symbols=symbols,
            plant=plant,
            blocks=blocks or [],
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
    blocks: Blocks = None,
) -> None:
    """Export a chart as PLCopen TC6 XML or a TIA Portal SimaticML GRAPH block."""
    from s7graph.web.cli.exchange import export_command

    raise typer.Exit(
        export_command(chart, to=to, output=output, symbols=symbols, blocks=blocks or [])
    )


# ---------------------------------------------------------------- the bus


@app.command()
def web(
    connect: Connect = None,
    cpu: Annotated[str | None, typer.Option("--cpu", help="The CPU (default: the first).")] = None,
    fb: FbName = None,
    host: Host = "127.0.0.1",
    port: ViewPort = 8080,
    tls_ca: TlsCa = None,
    origin: Origin = None,
    duration_s: StopAfter = None,
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


Anonymous = Annotated[
    str | None,
    typer.Option(
        metavar="read|refuse",
        help="Anonymous OPC UA sessions: read (browse, read, subscribe) or refused. "
        "Default: read on loopback, refused beyond it.",
    ),
]


@app.command()
def opcua(
    connect: Connect = None,
    cpu: Annotated[str | None, typer.Option("--cpu", help="The CPU (default: the first).")] = None,
    listen: Annotated[
        str, typer.Option("--listen", metavar="opc.tcp://HOST:PORT", help="Where to serve OPC UA.")
    ] = "opc.tcp://127.0.0.1:4840",
    users: Annotated[
        Path | None,
        typer.Option(
            help="The users file the CPU checks logins against (the CPU checks each "
            "password; needed beyond loopback)."
        ),
    ] = None,
    anonymous: Anonymous = None,
    writes: Annotated[
        str | None, typer.Option("--writes", metavar="force|modify", help=_WRITES_HELP)
    ] = None,
    cert: Annotated[
        Path | None, typer.Option(help="The server's certificate (PEM or DER), for SignAndEncrypt.")
    ] = None,
    key: Annotated[Path | None, typer.Option(help="The server's private key.")] = None,
    trust: Annotated[
        Path | None,
        typer.Option(help="A folder of trusted client certificates (default: any may connect)."),
    ] = None,
    tls_ca: TlsCa = None,
    duration_s: StopAfter = None,
    child: Annotated[
        bool, typer.Option("--child", hidden=True, help="The OPC UA server of a run --opcua.")
    ] = False,
) -> None:
    """Serve a CPU on the bus over OPC UA, as a process of its own."""
    from s7graph.web.cli.opcua import opcua_command

    net = _net(connect=connect, users=users, tls_ca=tls_ca)
    raise typer.Exit(
        opcua_command(
            net,
            cpu=cpu,
            listen=listen,
            anonymous=anonymous,
            writes=writes,
            cert=cert,
            key=key,
            trust=trust,
            duration_s=duration_s,
            child=child,
        )
    )


@app.command()
def router(
    listen: Listen = None,
    connect: Connect = None,
    users: Users = None,
    tls_ca: TlsCa = None,
    tls_cert: TlsCert = None,
    tls_key: TlsKey = None,
    duration_s: StopAfter = None,
    cpu: Annotated[
        list[str] | None,
        typer.Option(
            "--cpu", help="A CPU whose keys its identity cpu.NAME alone may serve (several)."
        ),
    ] = None,
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
        relays=cpu,
    )
    raise typer.Exit(router_command(net, duration_s))


@app.command()
def watch(
    cpu: CpuName = "cpu1",
    connect: Connect = None,
    fb: FbName = None,
    tls_ca: TlsCa = None,
    duration_s: StopAfter = None,
    address: Annotated[
        list[str] | None,
        typer.Option(
            "--address",
            help="Watch these operands instead of an FB's steps, comma-separated (several "
            "--address add up): addresses (MW0, Q4.0, DB20.DBW2, T5), symbols, DB variables "
            "by name (DB20.avg, DB10.ctu.CV, DB20.speeds[2]), each optionally :TYPE (MW0:INT).",
        ),
    ] = None,
    interval_ms: Annotated[
        float,
        typer.Option(help="With --address: how often to read them, in ms (20 to 3,600,000)."),
    ] = 200.0,
    user: Annotated[
        str | None,
        typer.Option(
            "--user",
            help="With --address: log in as this user and sign the requests (the CPU keeps "
            "them in the user's own share).",
        ),
    ] = None,
) -> None:
    """Print a CPU's step changes live (one line each), or with --address the values of
    addresses and DB variables whenever one changes."""
    net = _net(cpu=cpu, connect=connect, tls_ca=tls_ca)
    if address is None and user is not None:
        raise typer.BadParameter("--user signs --address's requests: an FB's steps need none")
    if address is not None:
        from s7graph.web.cli.watch_table import check_interval, split_addresses, watch_addresses

        if fb is not None:
            raise typer.BadParameter("--address watches operands, --fb an FB's steps: not both")
        try:
            operands = split_addresses(",".join(address))
            check_interval(interval_ms)
        except ValueError as exc:
            raise typer.BadParameter(str(exc)) from None
        code = watch_addresses(
            net, operands, interval_ms=interval_ms, duration_s=duration_s, user=user
        )
        raise typer.Exit(code)
    from s7graph.web.cli.remote import watch_command

    raise typer.Exit(watch_command(net, fb=fb, duration_s=duration_s))


@app.command()
def status(cpu: CpuName = "cpu1", connect: Connect = None, tls_ca: TlsCa = None) -> None:
    """Print a CPU's state and cycle time, and where its longest cycles went."""
    from s7graph.web.cli.remote import status_command

    raise typer.Exit(status_command(_net(cpu=cpu, connect=connect, tls_ca=tls_ca)))


@app.command()
def diag(
    cpu: CpuName = "cpu1",
    connect: Connect = None,
    tls_ca: TlsCa = None,
    n: Annotated[
        int, typer.Option("-n", callback=_entries, help="How many entries, newest first (1-1000).")
    ] = 100,
    as_json: Annotated[bool, typer.Option("--json", help="Print the entries as JSON.")] = False,
) -> None:
    """Print a CPU's diagnostic buffer, newest first: time, event ID, OB and priority
    class, text."""
    from s7graph.web.cli.diag import diag_command

    net = _net(cpu=cpu, connect=connect, tls_ca=tls_ca)
    raise typer.Exit(diag_command(net, n=n, as_json=as_json))


@app.command()
def sync(
    cpu: CpuName = "cpu1",
    connect: Connect = None,
    fb: FbName = None,
    tls_ca: TlsCa = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print the report as JSON.")] = False,
) -> None:
    """Print where the process stands in an FB's chart (S7-GRAPH's synchronization): the
    steps whose interlock holds and whose next transition does not, the likely first."""
    from s7graph.web.cli.sync import sync_command

    net = _net(cpu=cpu, connect=connect, tls_ca=tls_ca)
    raise typer.Exit(sync_command(net, fb=fb, as_json=as_json))


@app.command()
def upload(
    cpu: CpuName = "cpu1",
    connect: Connect = None,
    fb: FbName = None,
    tls_ca: TlsCa = None,
    to: Annotated[
        Path | None,
        typer.Option(
            "--to",
            help="Write the chart, its symbol table and the S7-SCL sources the CPU runs "
            "beside it into this folder (default: the chart's text to stdout).",
        ),
    ] = None,
    force: Annotated[
        bool, typer.Option("--force", help="Write over files that exist in --to.")
    ] = False,
) -> None:
    """Upload the chart an FB runs from the CPU (STEP 7's "Upload from device"): the .s7g
    text it compiled, the symbol table it was compiled with, its S7-SCL sources."""
    from s7graph.web.cli.upload import upload_command

    net = _net(cpu=cpu, connect=connect, tls_ca=tls_ca)
    raise typer.Exit(upload_command(net, fb=fb, to=to, force=force))


def _remote(
    kind: type[Command],
    args: Args,
    *,
    cpu: str,
    connect: list[str] | None,
    fb: str | None,
    user: str,
    tls_ca: Path | None,
) -> None:
    from s7graph.web.cli.remote import send_command

    net = _net(cpu=cpu, connect=connect, tls_ca=tls_ca)
    raise typer.Exit(send_command(net, fb=fb, user=user, kind=kind, args=args))


# ---------------------------------------------------------------- the ops' own commands

# What every op's command takes besides its argument: who logs in, where.
_BUS_PARAMETERS = (
    Parameter("user", Parameter.KEYWORD_ONLY, annotation=UserName),
    Parameter("cpu", Parameter.KEYWORD_ONLY, annotation=CpuName, default="cpu1"),
    Parameter("connect", Parameter.KEYWORD_ONLY, annotation=Connect, default=None),
    Parameter("fb", Parameter.KEYWORD_ONLY, annotation=FbName, default=None),
    Parameter("tls_ca", Parameter.KEYWORD_ONLY, annotation=TlsCa, default=None),
)


_STEP_FIELDS = ("step", "steps")


def _step_word(word: str) -> object:
    """``S3`` or ``3`` as the step number 3; ``ValueError`` for a word that is neither."""
    m = re.fullmatch(r"[Ss]?(\d{1,9})", word.strip())
    if m is None:
        raise ValueError(f"{word!r} is not a step: write it S3 or 3, as S7-GRAPH numbers it")
    return int(m[1])


def _word(field: mi.Field, value: object) -> object:
    """A shell word as the type of the argument ``field``: a choice whatever its case
    (``mode man``), digits as a number where a number may go (``--message 17``)."""
    if field.name in _STEP_FIELDS:  # a step as S7-GRAPH names it: S3, or 3
        if isinstance(value, list):
            return [_step_word(v) for v in value]
        return _step_word(value) if isinstance(value, str) else value
    if not isinstance(value, str):
        return value
    t = field.type
    if isinstance(t, mi.LiteralType):
        return {str(c).lower(): c for c in t.values}.get(value.lower(), value)
    types = t.types if isinstance(t, mi.UnionType) else (t,)
    if value.isdigit() and any(isinstance(x, mi.IntType) for x in types):
        return int(value)
    return value


def _option_name(shell: Shell) -> str:
    """The parameter name of an op's option (``--step``: ``step``)."""
    return shell.option.lstrip("-").replace("-", "_")


def _parameter(kind: type[Command], field: mi.Field) -> Parameter:
    """The parameter that gives ``kind``'s one argument ``field``: the positional of its own
    command, or its option (``kind.shell.option``) of another op's command."""
    shell = kind.shell
    assert shell is not None
    hint: Any = Annotated  # the argument's type is known at run time only
    number = isinstance(field.type, mi.IntType) and field.name not in _STEP_FIELDS
    if shell.option:
        option = typer.Option(shell.option, help=shell.help)
        typed = hint[int | None if number else str | None, option]
        return Parameter(
            _option_name(shell), Parameter.KEYWORD_ONLY, annotation=typed, default=None
        )
    values = [str(v) for v in getattr(field.type, "values", ())]  # a choice's: AUTO, MAN ...
    choices = f"{', '.join(values[:-1])} or {values[-1]}." if values else ""
    argument = typer.Argument(metavar=shell.metavar or None, help=shell.argument or choices)
    many = isinstance(field.type, mi.ListType)  # set-steps 3 12: one word per item
    typed = list[str] if many else int if number else str  # a step: S3 or 3 (_word)
    return Parameter(field.name, Parameter.KEYWORD_ONLY, annotation=hint[typed, argument])


def _op_command(kind: type[Command], options: tuple[type[Command], ...]) -> None:
    """Add ``s7graph NAME`` (``kind.shell``): it sends ``kind`` with its one argument as the
    positional, or, when one of ``options`` is given, that option's op (the later one in
    the union when several are: ``ack --message`` before ``ack --step``). Its arguments are
    checked as the bus checks them before anything is sent."""
    shell, field = kind.shell, argument_field(kind)
    assert shell is not None
    params = [_parameter(kind, field)] if field is not None else []
    params += [*_BUS_PARAMETERS, *(_parameter(o, f) for o in options if (f := argument_field(o)))]

    def send_op(**given: Any) -> None:
        bus = {name: given.pop(name) for name in ("user", "cpu", "connect", "fb", "tls_ca")}
        chosen, value = kind, given.get(field.name) if field is not None else None
        for other in reversed(options):
            assert other.shell is not None
            option = given.get(_option_name(other.shell))
            if option is not None:
                chosen, value = other, option
                break
        of = argument_field(chosen)
        try:
            args = args_of(chosen, {of.name: _word(of, value)} if of is not None else {})
        except ValueError as exc:
            raise typer.BadParameter(str(exc)) from None
        _remote(chosen, args, **bus)

    send_op.__signature__ = Signature(params)  # type: ignore[attr-defined]  # typer reads it
    send_op.__name__ = shell.name.replace("-", "_")
    send_op.__doc__ = shell.help
    app.command(shell.name)(send_op)


def _op_commands() -> None:
    """A command for each op whose ``shell`` (web.commands) asks for one, in the union's
    order; ``force``, ``modify`` and ``download`` are written below (they take two words or
    do more than send the op)."""
    for kind in COMMAND_TYPES:
        shell = kind.shell
        if shell is None or shell.by_hand or shell.option:
            continue
        options = tuple(
            o for o in COMMAND_TYPES if o.shell and o.shell.option and o.shell.name == shell.name
        )
        _op_command(kind, options)


_op_commands()


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
    try:
        given = command_args(op, arguments or [])  # an unknown op is refused here
        kind = command_type(op)
        assert kind is not None
        args = args_of(kind, given)
    except ValueError as exc:
        raise typer.BadParameter(str(exc)) from None
    if user is None:
        raise typer.BadParameter("give the user to log in as with --user")
    _remote(kind, args, cpu=cpu, connect=connect, fb=fb, user=user, tls_ca=tls_ca)


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
    send_force = functools.partial(
        _remote, Force, cpu=cpu, connect=connect, fb=fb, user=user, tls_ca=tls_ca
    )
    if all_:
        if [w.lower() for w in words] != ["off"]:
            raise typer.BadParameter("--all unforces every job: s7graph force --all off")
        send_force(ForceArgs(all=True))
    if len(words) != 2:
        raise typer.BadParameter("give ADDRESS VALUE (or ADDRESS off), e.g. force I0.3 TRUE")
    address, value = words
    args = ForceArgs(address=address, value=None if value.lower() == "off" else value)
    send_force(args)


@app.command(context_settings={"ignore_unknown_options": True})  # MW10 -5: a value
def modify(
    job: Annotated[
        list[str],
        typer.Argument(
            metavar="ADDRESS VALUE",
            help="An I, Q, M or DB address or a symbol, and TRUE/FALSE, a number or an S7 "
            "literal (16#00FF, T#5S).",
        ),
    ],
    user: UserName,
    cpu: CpuName = "cpu1",
    connect: Connect = None,
    fb: FbName = None,
    tls_ca: TlsCa = None,
) -> None:
    """Write a value once at the next scan boundary, not held (engineers; STEP 7's Modify):
    the program and the modules may write it again."""
    if len(job) != 2:
        raise typer.BadParameter("give ADDRESS VALUE, e.g. modify M10.0 TRUE")
    address, value = job
    _remote(
        Modify,
        ModifyArgs(address=address, value=value),
        cpu=cpu,
        connect=connect,
        fb=fb,
        user=user,
        tls_ca=tls_ca,
    )


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
    blocks: Annotated[
        list[Path] | None,
        typer.Option(
            "--blocks",
            help="A changed S7-SCL source the CPU runs with the chart (several allowed): "
            "swapped in with it, instance values kept by name.",
        ),
    ] = None,
) -> None:
    """Download a changed chart into the running FB (online change): the change summary,
    then the swap at a scan boundary with the state carried over by step number."""
    from s7graph.web.cli.remote import download_command

    if removed is not None and removed not in ("keep", "init"):
        raise typer.BadParameter("--removed must be keep or init")
    net = _net(cpu=cpu, connect=connect, tls_ca=tls_ca)
    code = download_command(
        net, chart, fb=fb, user=user, removed=removed, yes=yes, blocks=blocks or []
    )
    raise typer.Exit(code)


# ---------------------------------------------------------------- certificates

certs_app = typer.Typer(
    no_args_is_help=True, help="The plant's CA and node certificates for the bus (mutual TLS)."
)
app.add_typer(certs_app, name="certs")
CertsDir = Annotated[Path, typer.Argument(help="The folder of the CA and the certificates.")]
Overwrite = Annotated[bool, typer.Option("--force", help="Replace files that are there.")]


@certs_app.command("init")
def certs_init(directory: CertsDir, force: Overwrite = False) -> None:
    """Make the plant's CA: DIR/ca.pem (for every node) and DIR/ca.key (0600, stays here)."""
    from s7graph.web.cli import certs as cmd

    raise typer.Exit(cmd.certs_init(directory, force=force))


@certs_app.command("issue")
def certs_issue(
    directory: CertsDir,
    name: Annotated[str, typer.Argument(help="The node's name: a CPU's is its --cpu.")],
    kind: Annotated[str, typer.Option(help="cpu, router, view, opcua or client.")],
    host: Annotated[
        list[str] | None,
        typer.Option("--host", help="An address or DNS name the node is reached at (several)."),
    ] = None,
    force: Overwrite = False,
) -> None:
    """Issue node KIND.NAME's certificate and key (0600) with the CA of DIR."""
    from s7graph.web.cli import certs as cmd

    raise typer.Exit(cmd.certs_issue(directory, name, kind, host or [], force=force))


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
    """Change a user's password (and move an old scrypt entry to SCRAM-SHA-256)."""
    from s7graph.web.cli import users as cmd

    raise typer.Exit(cmd.users_passwd(file, name, password_stdin=password_stdin))


@app.command()
def audit(
    state: Annotated[Path, typer.Option(help="The CPU's SQLite state file.")],
    since: Annotated[
        str | None, typer.Option(help="From this time (2026-11-22T08:30, 08:30) or age (2h).")
    ] = None,
    summary: Annotated[
        bool,
        typer.Option(
            "--summary", help="The rows rolled into the summary: per day, user, op, outcome."
        ),
    ] = False,
) -> None:
    """Print who commanded what, when, from where, applied or refused."""
    from s7graph.web.cli.audit import audit_command

    raise typer.Exit(audit_command(state, since, summary=summary))


@functools.cache
def _command(name: str = "") -> Any:
    """``app`` as the click command typer makes of it, the credential options given to
    every command on the bus: built once per process, not per call. With ``name`` one of
    its commands, the group holds that command alone: typer reads each command's signature
    and builds its options (some 80 ms for all of them), and a process runs one."""
    _credentials_added()
    chosen = [info for info in app.registered_commands if _name_of(info) == name]
    if not chosen:  # --help, --version, a misspelled command: the whole group
        return get_command(app)
    one = typer.Typer(add_completion=False, help=app.info.help, pretty_exceptions_enable=False)
    one.registered_callback = app.registered_callback
    one.registered_commands = chosen
    return get_command(one)


@functools.cache
def _credentials_added() -> None:
    _credentials_everywhere()


def _name_of(info: Any) -> str:
    """The command's name on the command line (typer's rule: the function's, ``_`` → ``-``)."""
    callback = info.callback
    return str(info.name or (callback.__name__.lower().replace("_", "-") if callback else ""))


def _command_word(argv: list[str] | None) -> str:
    """The first word of the command line that is not an option: the command's name."""
    words = sys.argv[1:] if argv is None else argv
    return next((w for w in words if not w.startswith("-")), "")


def _doing(argv: list[str] | None) -> str:
    """Where an internal error happened, in words: ``while running s7graph watch``."""
    name = _command_word(argv)
    return f"while running s7graph {name}"[:120].rstrip() if name.isprintable() else ""


_AT = re.compile(r" - at `\$(?:\.args)?\.?([^`]*)`$")


def _usage_error(exc: Exception, message: str) -> str:
    """A usage error in words, pointing at the help of the command it is of (``s7graph mode
    --help``); a command group given no command (its help printed already: typer's empty
    message) asks for one."""
    ctx = getattr(exc, "ctx", None)
    where = str(getattr(ctx, "command_path", "") or "s7graph")
    if not message.strip():
        return f"give a command of {where}: one of those listed above"
    message = _missing(exc) or _not_a_number(exc) or message
    return f"{_argument_words(message)} (see {where} --help)"


def _missing(exc: Exception) -> str:
    """An argument or a required option not given, in words as the other usage errors:
    ``give CHART: a chart in .s7g source, or an .scl source`` (the argument named as the
    usage line names it, then its help), ``give --state: the CPU's SQLite state file``,
    not click's ``Missing argument 'chart'.``; "" for another error."""
    param = getattr(exc, "param", None)
    if type(exc).__name__ != "MissingParameter" or param is None:
        return ""
    if getattr(param, "param_type_name", "") == "argument":
        shown = getattr(param, "_usage_display_name", None)
        name = str(shown()) if callable(shown) else str(param.name).upper()
    else:
        name = str((getattr(param, "opts", None) or [param.name])[0])
    told = str(getattr(param, "help", "") or "").strip().removesuffix(".")
    if told[1:2].islower() or told[1:2] == " ":
        told = told[0].lower() + told[1:]
    return f"give {name}: {told}" if told else f"give {name}"


def _max_entries() -> int:
    """The most diagnostic entries one answer carries (imported only when asked)."""
    from s7graph.web.bus.protocol import MAX_DIAG_ENTRIES

    return MAX_DIAG_ENTRIES


def _range_of(option: str) -> str:
    """The range of a numeric option whose bound is another module's, imported only when
    asked: ``-n`` (``diag``), ``--interval-ms`` (checked by ``watch`` itself); "" for
    another."""
    if option == "-n":
        return f"from 1 to {_max_entries():,}"
    if option == "--interval-ms":
        from s7graph.web.cli.watch_table import MAX_INTERVAL_MS, MIN_INTERVAL_MS

        return f"from {MIN_INTERVAL_MS} to {MAX_INTERVAL_MS:,} ms"
    return ""


_NUMBER_WORDS = {"int_parsing": "a whole number", "float_parsing": "a number"}


def _not_a_number(exc: Exception) -> str:
    """A numeric option given no number (``--cycles abc``), worded as its range check words
    a number out of range: ``Invalid value for '--cycles': a whole number from 0 to
    100,000,000, not 'abc'``; "" for another error."""
    errors = getattr(exc.__cause__, "errors", None)  # typer's parsing: pydantic's error
    param = getattr(exc, "param", None)
    if not callable(errors) or param is None or not getattr(param, "opts", None):
        return ""
    first = (errors() or [{}])[0]
    kind = _NUMBER_WORDS.get(first.get("type", ""))
    if kind is None:
        return ""
    check = getattr(param.callback, "__wrapped__", param.callback)
    span = _RANGES.get(check) or _range_of(param.opts[0])
    takes = " ".join(filter(None, [kind, span]))
    return f"Invalid value for '{param.opts[0]}': {takes}, not {first.get('input')!r}"


_OPTION_SAID = re.compile(r"^Invalid value: (--?[a-z][\w-]*): ")


def _argument_words(message: str) -> str:
    """A refusal of an op's argument, in the vocabulary's words (``web.commands.explain``),
    without the place it names on the bus (`` - at `$.args.on```: the command line is no
    JSON); a command's own refusal without click's ``Invalid value: `` before it, or, when
    it names its option first (``--interval-ms: from 20 …``), worded as click words a range
    check's (``Invalid value for '--interval-ms': from 20 …``)."""
    at = _AT.search(message)
    if at is not None:
        return message[: at.start()].removeprefix("Invalid value: ")
    option = _OPTION_SAID.match(message)
    if option is not None:
        return f"Invalid value for '{option[1]}': {message[option.end() :]}"
    return message.removeprefix("Invalid value: ")


def main(argv: list[str] | None = None) -> int:
    """The commands' entry point (``main`` in ``web/cli/__init__.py`` calls it, once the
    supervisor of a ``run`` is not wanted); turns every known error into one stderr line.
    ``argv`` None: the program's command line."""
    try:
        rc = _command(_command_word(argv))(args=argv, prog_name="s7graph", standalone_mode=False)
    except S7Error as exc:
        print(f"s7graph: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:
        return _reader_gone()
    except typer.Exit as exc:
        return int(exc.exit_code or 0)
    except SystemExit as exc:  # click usage errors; click's end of a closed pipe: exit 1
        if isinstance(exc.__context__, BrokenPipeError):
            return _reader_gone()
        return int(exc.code or 0) if isinstance(exc.code, int) else 2
    except Exception as exc:
        message = getattr(exc, "format_message", None)
        if callable(message):  # a usage error of the command line (typer's click)
            print(f"s7graph: error: {_usage_error(exc, message())}", file=sys.stderr)
            code = getattr(exc, "exit_code", 2)
            return code if isinstance(code, int) else 2
        if type(exc).__name__ == "Abort":  # Ctrl-C at a prompt
            return 130
        from s7graph.web.bus.protocol import ProtocolError

        if isinstance(exc, ProtocolError):  # a peer's answer s7graph cannot take
            print(f"s7graph: error: {exc}", file=sys.stderr)
            return 2
        print(f"s7graph: {internal_error(_doing(argv), exc)}", file=sys.stderr)
        return 2
    try:  # what is still buffered: a closed pipe found here ends as one found before
        if sys.stdout is not None:
            sys.stdout.flush()
    except BrokenPipeError:
        return _reader_gone()
    return rc if isinstance(rc, int) else 0


SIGPIPE_EXIT = 128 + 13
"""The exit status of a command whose output's reader went away: a shell's for a process
killed by SIGPIPE (``yes | head``)."""


def _reader_gone() -> int:
    """The reader of stdout closed the pipe (``s7graph sim CHART | head -3``): end quietly,
    with :data:`SIGPIPE_EXIT`, as a Unix tool killed by SIGPIPE; what is still buffered
    goes to /dev/null, so the interpreter's last flush says nothing either."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError, AttributeError):  # no file descriptor: nothing buffered
        pass
    return SIGPIPE_EXIT


if __name__ == "__main__":
    sys.exit(main())
