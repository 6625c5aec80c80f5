"""``s7graph run PROGRAM.py``: a Python program of blocks on the system clock.

Program convention: a Python file whose module-level ``@ob``/``@fb``/``@fc`` blocks (and
``DB`` definitions) are loaded; an optional ``CPU = {...}`` dict passes keyword options to
``Cpu`` (``max_cycle_ms``, ``clock_memory``, ...; ``--max-cycle-ms`` overrides its
``max_cycle_ms``; its ``restart`` chooses the startup from a saved state); an optional
``setup(cpu)`` creates instance DBs and configures interrupts. The state file restores
retentive data and the CPU's message list (who acknowledged what, when; every message event
is also appended to its alarm log) and the CPU comes back by the chosen restart (warm by
default); on Ctrl-C, SIGTERM or ``--duration-s`` the CPU goes to STOP (outputs 0) and the
state is saved. A broken program or a state file it cannot trust is one line on stderr and
exit 2; a STOP by error or a state file that cannot be written ends the run, one line,
exit 1.
"""

from __future__ import annotations

import importlib.util
import signal
import sys
from collections.abc import Callable
from pathlib import Path
from types import ModuleType
from typing import Any

from s7graph import sfb
from s7graph.engine.blocks import DB, FB, FC, OB
from s7graph.engine.clock import SystemClock
from s7graph.engine.cpu import Cpu
from s7graph.engine.modes import CpuMode
from s7graph.engine.persistence import StateFileError
from s7graph.engine.record import ScanRecord
from s7graph.engine.restart import parse_restart
from s7graph.engine.runner import RT_PRIORITY, Runner, core_for, keep_small_pages
from s7graph.web.cli.supervisor import child_marks, recovered_cause
from s7graph.web.harness.persist import OpenedState, open_state, refusal


class ProgramLoadError(Exception):
    """A program file that cannot be imported or set up."""


def _fail(path: Path, message: str) -> int:
    print(f"s7graph: error: {path}: {message}", file=sys.stderr)
    return 2


def import_program(path: Path) -> ModuleType:
    """Import a program file as a fresh module (never cached under a real package name)."""
    if not path.is_file():
        raise ProgramLoadError("no such file")
    spec = importlib.util.spec_from_file_location(f"s7graph_program_{path.stem}", path)
    if spec is None or spec.loader is None:
        raise ProgramLoadError("not a Python program")
    module = importlib.util.module_from_spec(spec)
    try:
        spec.loader.exec_module(module)
    except SyntaxError as exc:
        raise ProgramLoadError(f"line {exc.lineno}: syntax error: {exc.msg}") from None
    except Exception as exc:
        raise ProgramLoadError(f"{type(exc).__name__}: {exc}") from None
    return module


def build_cpu(module: ModuleType, clock: Any, *, max_cycle_ms: float | None = None) -> Cpu:
    """A CPU with the module's blocks loaded and its ``setup(cpu)`` applied.

    ``max_cycle_ms`` (``--max-cycle-ms``) overrides the program's ``CPU`` option; None keeps
    it (S7's 150 ms when the program sets none). The ``restart`` option is the run's, not
    the CPU's (``program_restart``)."""
    blocks = [v for v in vars(module).values() if isinstance(v, OB | FB | FC | DB)]
    if not any(isinstance(b, OB) for b in blocks):
        raise ProgramLoadError("defines no OB (decorate a function with @ob(1) or @ob(35))")
    options = dict(_options(module))
    options.pop("restart", None)
    options.pop("core", None)
    if max_cycle_ms is not None:
        options = {**options, "max_cycle_ms": max_cycle_ms}
    try:
        cpu = Cpu(clock, **options)
        sfb.install(cpu)  # the system blocks belong to the CPU, as on S7: ctx.call("SFB41", 41)
        cpu.load(*blocks)
        setup: Callable[[Cpu], object] | None = getattr(module, "setup", None)
        if setup is not None:
            setup(cpu)
    except Exception as exc:
        raise ProgramLoadError(f"{type(exc).__name__}: {exc}") from None
    return cpu


def _options(module: ModuleType) -> dict[str, Any]:
    options = getattr(module, "CPU", {})
    if not isinstance(options, dict):
        raise ProgramLoadError("CPU must be a dict of Cpu options")
    return options


def program_restart(module: ModuleType) -> str | None:
    """The program's ``CPU = {"restart": "warm" | "hot" | "cold"}``, None if it sets none."""
    value = _options(module).get("restart")
    if value is None:
        return None
    try:
        return str(parse_restart(value))
    except ValueError as exc:
        raise ProgramLoadError(f"CPU option restart: {exc}") from None


def program_core(module: ModuleType) -> Any:
    """The program's ``CPU = {"core": "auto" | "off" | n}``, None if it sets none; what it
    may be is ``engine.cores.scan_core``'s to say (``run_program`` reports its refusal)."""
    return _options(module).get("core")


def _report(record: ScanRecord) -> None:
    for entry in record.diagnostics:
        if entry.event_id >> 8 in (0x25, 0x35):  # errors; a STOP is reported by the run
            print(f"s7graph: {entry}", file=sys.stderr)


def run_program(
    path: Path,
    *,
    state: Path | None,
    cycle_ms: float,
    duration_s: float | None,
    max_cycle_ms: float | None = None,
    restart: str | None = None,
    fresh: bool = False,
    rt_priority: int | None = RT_PRIORITY,
    core: str | int | None = None,
) -> int:
    """Run a program until Ctrl-C/SIGTERM/duration; 0 on a clean end, 1 when the CPU went
    to STOP by an error or the state could not be written, 2 on a broken program or a
    state file it cannot trust.

    ``max_cycle_ms``: the maximum cycle time; None keeps the program's (see ``build_cpu``).
    ``restart`` (``--restart``): the startup from a saved state; None: the program's
    ``CPU["restart"]``, else warm. ``rt_priority``: the scan thread's real-time priority
    (None: normal scheduling). ``core`` (``--core``): the processor kept for the scan
    (``engine.cores``); None: the program's ``CPU["core"]``, else auto."""
    if rt_priority is not None:
        keep_small_pages()  # before the view starts: it inherits it
    try:
        module = import_program(path)
        cpu = build_cpu(module, SystemClock(), max_cycle_ms=max_cycle_ms)
        restart = restart or program_restart(module) or "warm"
        choice = core if core is not None else program_core(module)
    except ProgramLoadError as exc:
        return _fail(path, str(exc))
    try:
        kept = core_for(choice, rt_priority)
    except ValueError as exc:
        if core is None:
            return _fail(path, f"CPU option core: {exc}")
        print(f"s7graph: error: --core: {exc}", file=sys.stderr)
        return 2
    recovered = recovered_cause()
    state_path = state if state is not None else path.with_suffix(".state.sqlite")
    try:
        fresh = fresh and recovered is None  # never anew after a hang: its last state
        opened = open_state(  # a recovered CPU stays in STOP until started
            state_path,
            cpu,
            fresh=fresh,
            hot=restart == "hot",
            restart=None if recovered else restart,
        )
    except StateFileError as exc:
        print(refusal(exc), file=sys.stderr)
        return 2
    except OSError as exc:
        return _fail(state_path, f"cannot use the state file: {exc.strerror or exc}")
    runner = Runner(
        cpu,
        cycle_ms=cycle_ms,
        store=opened.store,
        on_record=_report,
        end_on_stop=True,
        rt_priority=rt_priority,
        core=kept,
        marks=child_marks(),
    )
    return run_until_stopped(
        runner,
        opened,
        what=path.name,
        restart=restart,
        duration_s=duration_s,
        on_start=_report,
        recovered=recovered,
    )


def _recover(runner: Runner, opened: OpenedState, what: str, recovered: tuple[str, str]) -> None:
    runner.recover(*recovered)
    print(f"s7graph: error: {what}: the CPU went to STOP: {runner.stopped}", file=sys.stderr)
    how = "start it with 's7graph start'" if not runner.end_on_stop else "the run ends"
    print(
        f"s7graph: {what} in STOP (from its last durable state in {opened.store.path}; {how})",
        file=sys.stderr,
        flush=True,
    )


def run_until_stopped(
    runner: Runner,
    opened: OpenedState,
    *,
    what: str,
    restart: str,
    duration_s: float | None,
    on_start: Callable[[ScanRecord], object] | None = None,
    close: Callable[[], object] | None = None,
    recovered: tuple[str, str] | None = None,
) -> int:
    """Start the runner's CPU with ``restart`` (``on_start`` gets the startup record), say
    how on stderr with ``what``, and scan until Ctrl-C/SIGTERM/``duration_s`` (or, with the
    runner's ``end_on_stop``, a STOP by error). Always: the signal handlers back, the runner
    shut down, ``close()``, the store closed. Returns the exit status: 0 (saying so in one
    line on stderr), or 1 (with one line on stderr) when the CPU went to STOP by an error
    or the state was not written.

    ``recovered`` (place, cause): the supervisor killed the process before, whose scan hung
    (``web.cli.supervisor``): no startup; the CPU stays in STOP with the cause in its
    diagnostic buffer, and scans in STOP (without ``end_on_stop``) until an engineer's
    ``start``, or ends the run (exit 1)."""
    cpu = runner.cpu
    store = opened.store

    runner.on_stop = lambda reason: print(
        f"s7graph: error: {what}: the CPU went to STOP: {reason}", file=sys.stderr, flush=True
    )
    stop = runner.on_stop_signal
    previous = {sig: signal.signal(sig, stop) for sig in (signal.SIGTERM, signal.SIGINT)}
    try:
        if recovered is not None:
            _recover(runner, opened, what, recovered)
        else:
            record = runner.startup(restart)
            if on_start is not None:
                on_start(record)
            for note in opened.report.notes if opened.report is not None else ():
                print(f"s7graph: note: {note}", file=sys.stderr)
            done = str(cpu.last_restart or restart)
            print(f"s7graph: {what} in {cpu.mode} ({opened.describe(done)})", file=sys.stderr)
        if cpu.mode is CpuMode.RUN or (recovered is not None and not runner.end_on_stop):
            runner.run(duration_s=duration_s)
    finally:
        try:
            runner.shutdown("s7graph run ended")
        finally:
            for sig, handler in previous.items():
                signal.signal(sig, handler)
            if close is not None:
                close()
            store.close()
    if runner.write_error is not None:
        print(f"s7graph: error: {runner.write_error}; the CPU went to STOP", file=sys.stderr)
        return 1
    if runner.stopped:
        return 1
    print(f"s7graph: {what} stopped (state saved in {store.path})", file=sys.stderr)
    return 0
