"""The ``s7graph`` command line: ``run``, ``sim``, ``check``, ``--version``.

Each command lives in its own module (``web/cli/*.py``) and is imported only when used, so
``s7graph check`` never pays for zenoh or viser. Errors are one line on stderr and a
non-zero exit, never a traceback.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Annotated

import typer

from s7graph import __version__
from s7graph.engine.errors import S7Error

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


def _positive_ms(value: float | None) -> float | None:
    if value is not None and not value > 0:
        raise typer.BadParameter("--max-cycle-ms must be more than 0 ms")
    return value


def _restart_type(value: str | None) -> str | None:
    if value is not None and value.lower() not in ("warm", "hot", "cold"):
        raise typer.BadParameter("--restart must be warm, hot or cold")
    return value.lower() if value is not None else None


@app.command()
def run(
    program: Annotated[
        Path, typer.Argument(help="A Python program of blocks (.py) or a chart (.s7g).")
    ],
    plant: Annotated[Path | None, typer.Option(help="A simulated plant (.py) for a chart.")] = None,
    symbols: Annotated[Path | None, typer.Option(help="A symbol table file for a chart.")] = None,
    state: Annotated[
        Path | None,
        typer.Option(help="SQLite file for retentive data (default: beside the program)."),
    ] = None,
    cycle_ms: Annotated[float, typer.Option(help="Minimum cycle time in ms.")] = 10.0,
    max_cycle_ms: Annotated[
        float | None,
        typer.Option(
            callback=_positive_ms,
            help="Maximum cycle time in ms; a longer scan is a time error (OB80, else STOP). "
            "Default: 150 (S7's), 1000 with --web (the view shares the process); "
            "for a program, its CPU dict's max_cycle_ms, else 150.",
        ),
    ] = None,
    duration_s: Annotated[
        float | None, typer.Option(help="Stop after this many seconds (default: until Ctrl-C).")
    ] = None,
    web: Annotated[bool, typer.Option(help="Serve the browser view (charts only).")] = False,
    port: Annotated[int, typer.Option(help="Port of the browser view.")] = 8080,
    record: Annotated[
        Path | None, typer.Option(help="Record the chart's run to a rerun .rrd file.")
    ] = None,
    restart: Annotated[
        str | None,
        typer.Option(
            callback=_restart_type,
            help="The startup from a saved state: warm (OB100, the sequencer initialized; "
            "the default), hot (OB101, it resumes where it was) or cold (OB102, everything "
            "to its initial values). For a program, its CPU dict's restart, else warm.",
        ),
    ] = None,
    fresh: Annotated[
        bool,
        typer.Option(help="Start anew: keep an existing state file as FILE.old-N."),
    ] = False,
) -> None:
    """Run a program or a chart on the system clock until Ctrl-C."""
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
                restart=restart or "warm",
                fresh=fresh,
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
        )
    )


@app.command()
def check(
    chart: Annotated[Path, typer.Argument(help="A chart in .s7g source.")],
    symbols: Annotated[Path | None, typer.Option(help="A symbol table file.")] = None,
) -> None:
    """Print a chart's diagnostics; exit 0 clean, 1 warnings only, 2 errors."""
    from s7graph.web.cli.check import check_command

    raise typer.Exit(check_command(chart, symbols=symbols))


@app.command()
def sim(
    chart: Annotated[Path, typer.Argument(help="A chart in .s7g source.")],
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
    """Run a chart on the virtual clock: stimulus in, one JSON line per cycle out (SPEC §4)."""
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


def main(argv: list[str] | None = None) -> int:
    """Entry point of the console script; turns every known error into one stderr line."""
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
