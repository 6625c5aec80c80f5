"""``s7graph run PROGRAM.py``: a program of blocks on the system clock.

Program convention: a Python file whose module-level ``@ob``/``@fb``/``@fc`` blocks (and
``DB`` definitions) are loaded; an optional ``CPU = {...}`` dict passes keyword options to
``Cpu`` (``max_cycle_ms``, ``clock_memory``, ...; ``--max-cycle-ms`` overrides its
``max_cycle_ms``; its ``restart`` chooses the startup from a saved state); an optional
``setup(cpu)`` creates instance DBs and configures interrupts. Other kinds of program
plug in by their file's suffix (``PROGRAM_LOADERS``: a loader gives the CPU with its
blocks, and the program's restart and core). The state file (``--state``, else
``NAME.py.state.sqlite`` / ``NAME.scl.state.sqlite`` beside it, or an older
``NAME.state.sqlite`` of its own: ``state_path_of``; another program's is refused) restores
retentive data and the CPU's message list (who acknowledged what, when; every message event
is also appended to its alarm log) and the CPU comes back by the chosen restart (warm by
default); on Ctrl-C, SIGTERM or ``--duration-s`` the CPU goes to STOP (outputs 0) and the
state is saved. A broken program or a state file it cannot trust is one line on stderr and
exit 2; a STOP by error, a startup the CPU refuses or a state file that cannot be written
ends the run, one line, exit 1.

With ``--listen``/``--connect`` (``web.cli.net``, checked as for a chart) the CPU is on the
bus (``web.wiring.program_edge``): status, the diagnostic buffer, force jobs, the RUN/STOP
switch, the memory reset and the watch of addresses and DB variables, logins and the audit
in the state file; ``--web`` serves its page (status, diagnostics, watch table) from a
process of its own and keeps the CPU in STOP after an error, for the engineer to read why.
"""

from __future__ import annotations

import functools
import importlib.util
import signal
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any

from s7graph import sfb
from s7graph.engine.blocks import DB, FB, FC, OB
from s7graph.engine.clock import Clock, SystemClock
from s7graph.engine.cores import kept_free
from s7graph.engine.cpu import Cpu
from s7graph.engine.errors import S7Error
from s7graph.engine.modes import CpuMode
from s7graph.engine.persistence import StateFileError
from s7graph.engine.record import ScanRecord
from s7graph.engine.restart import parse_restart
from s7graph.engine.runner import COMM_LOAD_PCT, RT_PRIORITY, Runner, core_for, keep_small_pages
from s7graph.engine.state_identity import Program
from s7graph.engine.write_stop import stop_words
from s7graph.web.cli.report import fail, not_a_chart
from s7graph.web.cli.run_stop import Locate, RunStop
from s7graph.web.cli.supervisor import child_marks, recovered_cause
from s7graph.web.harness.persist import OpenedState, default_state, open_state, refusal

if TYPE_CHECKING:
    from s7graph.engine.persistence import StateStore
    from s7graph.web.cli.net import NetOptions
    from s7graph.web.cli.view_process import ViewProcess
    from s7graph.web.harness.scl import SclSources
    from s7graph.web.wiring.program_edge import ProgramEdge


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


MAX_CYCLE_MS = 3_600_000
"""The longest maximum cycle time a program's ``CPU`` option or ``--max-cycle-ms`` sets."""


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
    cycle = options.get("max_cycle_ms", 1)
    if not isinstance(cycle, int | float) or not 0 < cycle <= MAX_CYCLE_MS:  # NaN too
        raise ProgramLoadError(
            f"CPU option max_cycle_ms: from more than 0 to {MAX_CYCLE_MS:,} ms, not {cycle!r}"
        )
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


@dataclass(frozen=True, slots=True)
class LoadedProgram:
    """A program loaded into its CPU: the CPU, and the program's own restart and core
    (None: it sets none), and its S7-SCL sources."""

    cpu: Cpu
    restart: str | None = None
    core: Any = None
    sources: SclSources | None = None
    """The S7-SCL sources of its blocks (served on the bus as ``blocks``), if any."""


def load_python(path: Path, clock: Clock, *, max_cycle_ms: float | None) -> LoadedProgram:
    """A Python program of blocks (the convention above)."""
    module = import_program(path)
    cpu = build_cpu(module, clock, max_cycle_ms=max_cycle_ms)
    return LoadedProgram(cpu, program_restart(module), program_core(module))


ProgramLoader = Callable[..., LoadedProgram]
"""``loader(path, clock, *, max_cycle_ms)``: the program in its CPU, or ProgramLoadError."""
PROGRAM_LOADERS: dict[str, ProgramLoader] = {".py": load_python}
"""The kinds of program ``s7graph run`` runs, by their file's suffix (lower case)."""


def load_program(path: Path, clock: Clock, *, max_cycle_ms: float | None = None) -> LoadedProgram:
    """The program at ``path`` by its suffix's loader (``PROGRAM_LOADERS``)."""
    loader = PROGRAM_LOADERS.get(path.suffix.lower())
    if loader is None:
        kinds = ", ".join(sorted(PROGRAM_LOADERS))
        takes = f"not a program s7graph runs ({kinds}, an S7-SCL program .scl, or a chart .s7g)"
        foreign = not_a_chart(path, takes)
        raise ProgramLoadError(foreign.removeprefix(f"{path}: ") if foreign else takes)
    return loader(path, clock, max_cycle_ms=max_cycle_ms)


def state_path_of(source: Path, state: Path | None, cpu: Cpu) -> Path:
    """``--state``, else the default beside ``source`` (``web.harness.persist.default_state``:
    its note, a file of another program's passed over, said on stderr)."""
    if state is not None:
        return state
    path, note = default_state(source, cpu)
    if note is not None:
        print(f"s7graph: note: {note}", file=sys.stderr)
    return path


class _Errors:
    """A run's reporter of records: each programming or time error (a STOP is said by the
    run) on stderr once per event, block and message — one that OB121 or OB80 handles
    recurs every cycle, and the diagnostic buffer (``s7graph diag``) keeps every entry."""

    AT_MOST = 1000
    """Distinct errors remembered; past that, none more is said."""

    def __init__(self) -> None:
        self._said: set[tuple[int, str, str]] = set()

    def __call__(self, record: ScanRecord) -> None:
        for entry in record.diagnostics:
            if entry.event_id >> 8 not in (0x25, 0x35):
                continue
            key = (entry.event_id, entry.block, entry.message)
            if key in self._said or len(self._said) >= self.AT_MOST:
                continue
            self._said.add(key)
            print(f"s7graph: {entry} (said once; s7graph diag lists each)", file=sys.stderr)


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
    net: NetOptions | None = None,
    web: bool = False,
    port: int = 8080,
    comm_load_pct: float = COMM_LOAD_PCT,
    load: Callable[[Clock], LoadedProgram] | None = None,
) -> int:
    """Run a program until Ctrl-C/SIGTERM/duration; 0 on a clean end, 1 when the CPU went
    to STOP by an error, refused its startup or the state could not be written, 2 on a
    broken program or a state file it cannot trust.

    ``max_cycle_ms``: the maximum cycle time; None keeps the program's (see ``build_cpu``).
    ``restart`` (``--restart``): the startup from a saved state; None: the program's
    ``CPU["restart"]``, else warm. ``rt_priority``: the scan thread's real-time priority
    (None: normal scheduling). ``core`` (``--core``): the processor kept for the scan
    (``engine.cores``); None: the program's ``CPU["core"]``, else auto. ``net``: the bus
    (with endpoints, or ``web``: the CPU is on it); ``web``: serve its page on ``port``;
    ``comm_load_pct``: the share of the cycle commands may take at a scan boundary.
    ``load``: the program in its CPU on the clock given (an S7-SCL program's,
    ``web.cli.run_scl``; ``S7Error`` is its diagnostics); None: by ``path``'s suffix."""
    if rt_priority is not None:
        keep_small_pages()  # before the view starts: it inherits it
    try:
        if load is not None:
            loaded = load(SystemClock())
        else:
            loaded = load_program(path, SystemClock(), max_cycle_ms=max_cycle_ms)
    except ProgramLoadError as exc:
        return _fail(path, str(exc))
    except S7Error as exc:  # an S7-SCL program's diagnostics
        return fail(exc)
    choice = core if core is not None else loaded.core
    try:
        kept = core_for(choice, rt_priority)
    except ValueError as exc:
        if core is None:
            return _fail(path, f"CPU option core: {exc}")
        print(f"s7graph: error: --core: {exc}", file=sys.stderr)
        return 2
    restart = restart or loaded.restart or "warm"
    recovered = recovered_cause()
    state_path = state_path_of(path, state, loaded.cpu)
    try:
        fresh = fresh and recovered is None  # never anew after a hang: its last state
        opened = open_state(  # a recovered CPU stays in STOP until started
            state_path,
            loaded.cpu,
            fresh=fresh,
            hot=restart == "hot",
            restart=None if recovered else restart,
            program=Program.of(path),
        )
    except StateFileError as exc:
        print(refusal(exc), file=sys.stderr)
        return 2
    except OSError as exc:
        return _fail(state_path, f"cannot use the state file: {exc.strerror or exc}")
    with kept_free(kept):  # before the bus and the view start: they inherit it
        on_bus = web or (net is not None and net.on_bus)
        notes = start_notes(net, on_bus=on_bus, here=web)
        edges = _program_edges(loaded, opened.store, net, web, port) if on_bus else None
        if isinstance(edges, int):
            return edges
        edge, view = edges if edges is not None else (None, None)
        runner = _program_runner(
            loaded.cpu,
            opened.store,
            edge,
            report := _Errors(),
            cycle_ms=cycle_ms,
            end_on_stop=not (web or bool(recovered and edge is not None)),
            rt_priority=rt_priority,
            comm_load_pct=comm_load_pct,
            core=kept,
        )
        if edge is not None:
            edge.restart = restart
        if view is not None:
            view.start()
        return run_until_stopped(
            runner,
            opened,
            what=path.name,
            restart=restart,
            duration_s=duration_s,
            on_start=report,
            notes=notes,
            close=functools.partial(_close_edges, view, edge),
            recovered=recovered,
        )


def _program_runner(
    cpu: Cpu, store: StateStore, edge: ProgramEdge | None, report: _Errors, **options: Any
) -> Runner:
    """The runner of a program's CPU: each record reported (its errors on stderr:
    ``report``) and, on the bus, handed to ``edge`` in the scan thread."""
    runner: Runner

    def on_record(record: ScanRecord) -> None:
        report(record)
        if edge is not None:
            edge.on_record(record, stats=cpu.stats, runner=runner)

    runner = Runner(cpu, store=store, on_record=on_record, marks=child_marks(), **options)
    return runner


def _program_edges(
    loaded: LoadedProgram, store: StateStore, net: NetOptions | None, web: bool, port: int
) -> tuple[ProgramEdge, ViewProcess | None] | int:
    """The program's CPU on the bus (its logins and audit in the state file, its S7-SCL
    sources on ``blocks``) and, with ``web``, its page's process (not started yet); exit
    status 2 with one line when the bus or the page cannot be served (the state file
    closed then)."""
    from s7graph.web.bus.block_sources import serve_blocks
    from s7graph.web.bus.gate import cpu_gate  # zenoh and viser only when asked for
    from s7graph.web.cli.net import NetOptions
    from s7graph.web.cli.view_process import run_view
    from s7graph.web.view.port import check_port
    from s7graph.web.wiring.program_edge import ProgramEdge

    net = net or NetOptions()
    try:
        if web:
            check_port(net.host, port)
        gate = cpu_gate(net.users, store)
        edge = ProgramEdge(loaded.cpu, name=net.cpu, ends=net.ends, gate=gate)
        if edge.publisher is not None:
            sources = loaded.sources
            serve_blocks(edge.publisher, lambda: sources)
    except Exception as exc:
        from s7graph.web.cli.net import edge_error

        print(f"s7graph: error: {edge_error(exc, net, web=False)}", file=sys.stderr)
        store.close()
        return 2
    if not web:
        print(f"s7graph: CPU {net.cpu} on the bus {edge.endpoint}; Ctrl-C to stop", flush=True)
        return edge, None
    view = run_view(net, port, edge.endpoint)
    return edge, view


def _close_edges(view: ViewProcess | None, edge: ProgramEdge | None) -> None:
    if view is not None:
        view.stop()
    if edge is not None:
        edge.close()


def _recover(runner: Runner, opened: OpenedState, what: str, recovered: tuple[str, str]) -> None:
    runner.recover(*recovered)
    print(f"s7graph: error: {what}: the CPU went to STOP: {runner.stopped}", file=sys.stderr)
    how = "start it with 's7graph start'" if not runner.end_on_stop else "the run ends"
    print(
        f"s7graph: {what} in STOP (from its last durable state in {opened.store.path}; {how})",
        file=sys.stderr,
        flush=True,
    )


def _say_last_run(opened: OpenedState) -> None:
    """What the state file says of the last run: the notes of a carried-over state, and why
    it went to STOP when that was by an error (``LoadReport.stopped``)."""
    report = opened.report
    if report is None:
        return
    for note in report.notes:
        print(f"s7graph: note: {note}", file=sys.stderr)
    if report.stopped:
        print(f"s7graph: note: the last run went to STOP: {report.stopped}", file=sys.stderr)


UNREACHABLE = (
    "s7graph: on no bus: s7graph status, watch and the other commands of a shell reach a run "
    "started with --web, --listen or --connect"
)
"""Said as a run without a bus starts: a shell's ``status`` finds no CPU then."""


def start_notes(net: NetOptions | None, *, on_bus: bool, here: bool) -> list[str]:
    """What a run says after its ``in RUN`` line of the bus it is on: on none, how a shell
    would reach it (``UNREACHABLE``); on this machine's (``here``: a page or an OPC UA face,
    no ``--listen`` or ``--connect``) under the name of a CPU running here, that it takes
    that name (``web.cli.net.name_taken_note``). Asked before the run goes on the bus."""
    if not on_bus:
        return [UNREACHABLE]
    if not here:
        return []
    from s7graph.web.cli.net import NetOptions, name_taken_note

    taken = name_taken_note(net or NetOptions())
    return [taken] if taken else []


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
    locate: Locate | None = None,
    notes: Sequence[str] = (),
) -> int:
    """Start the runner's CPU with ``restart`` (``on_start`` gets the startup record), say
    how on stderr with ``what``, and scan until Ctrl-C/SIGTERM/``duration_s`` (or, with the
    runner's ``end_on_stop``, a STOP by error). Always: the runner shut down, ``close()``, the
    store closed, then the signal handlers back (a Ctrl-C pressed again meanwhile is one
    more stop request). Returns the exit status: 0 (saying so in one
    line on stderr), or 1 (with one line on stderr) when the CPU went to STOP by an error
    — in its startup too —, refused its startup, or the state was not written
    (``web.cli.run_stop``: a STOP the program requested, SFC46 STP, is said and ends the run
    with 0). ``locate``: where the program uses what a STOP's programming error names (a
    chart's, ``chart_locator``).

    ``recovered`` (place, cause): the supervisor killed the process before, whose scan hung
    (``web.cli.supervisor``): no startup; the CPU stays in STOP with the cause in its
    diagnostic buffer, and scans in STOP (without ``end_on_stop``) until an engineer's
    ``start``, or ends the run (exit 1). ``notes``: lines said after the ``in RUN`` line
    (``start_notes``)."""
    cpu = runner.cpu
    store = opened.store

    said = RunStop(what, locate)
    said.bind(runner)
    runner.on_note = lambda note: print(f"s7graph: warning: {note}", file=sys.stderr, flush=True)
    stop = runner.on_stop_signal
    previous = {sig: signal.signal(sig, stop) for sig in (signal.SIGTERM, signal.SIGINT)}
    try:
        if recovered is not None:
            _recover(runner, opened, what, recovered)
        else:
            record = runner.startup(restart)
            if on_start is not None:
                on_start(record)
            _say_last_run(opened)
            done = str(cpu.last_restart or restart)
            print(f"s7graph: {what} in {cpu.mode} ({opened.describe(done)})", file=sys.stderr)
            for note in notes:
                print(note, file=sys.stderr)
            said.after_startup(runner, record)
        if cpu.mode is CpuMode.RUN or not runner.end_on_stop:
            runner.run(duration_s=duration_s)
    finally:
        try:
            runner.shutdown("s7graph run ended")
        finally:
            try:  # a second Ctrl-C while closing is one more stop request, not an interrupt
                if close is not None:
                    close()
                store.close()
            finally:
                for sig, handler in previous.items():
                    signal.signal(sig, handler)
    error = runner.write_error
    if error is not None and runner.stopped != stop_words(error):  # else said at once
        print(f"s7graph: error: {runner.write_error}; the CPU went to STOP", file=sys.stderr)
    if runner.trace:
        print(f"s7graph: note: {runner.trace}", file=sys.stderr)
    if runner.write_error is not None or said.failed(runner):
        return 1
    print(f"s7graph: {what} stopped (state saved in {store.path})", file=sys.stderr)
    return 0
