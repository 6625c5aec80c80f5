"""``s7graph run CHART.s7g``: a chart as a GraphFB from OB1, on the system clock.

The chart is compiled (exit 2 with diagnostics on stderr if it does not), installed with
OB1/OB100/OB102 in one CPU, the state file restores the instance DB and the CPU's message
list (``web/harness/persist.py``: a file it cannot trust is refused, exit 2; ``--fresh``
starts anew) and the CPU starts by ``--restart``: warm (OB100 initializes the sequencer,
its position written to the diagnostic buffer first), hot (OB101: the sequencer resumes
where it was; refused, exit 2, when the saved state allows none) or cold (OB102);
``engine.runner.Runner`` paces the scans.
A plant (``--plant``) runs after every scan; a plant error ends the run with one line, a
plant still running at twice the maximum cycle time is aborted (STOP). A STOP by error,
in the startup too, is said at once on stderr (``web.cli.run_stop``: with where the chart
uses the operand an area length error names); without ``--web`` it ends the run, exit 1.
``--web`` puts the running FB on the zenoh bus (``web/bus/scan_edge.py``: one state update
per scan, operator commands applied between scans and answered once durable — an
engineer's force jobs too, ``web/bus/forcing.py``, and downloads, ``web/bus/online.py`` —
each audited in the state file) and serves its live browser view on ``--host:--port`` from
a process of its own (``web/cli/view_process.py``: ``s7graph web`` as a child, restarted
when it ends), so a page load never shares the scan's process. ``--record FILE.rrd``
records the same updates as a rerun timeline (extra ``[trace]``). ``--opcua URL`` serves
the CPU over OPC UA from a process of its own too (``web/cli/opcua.py``: ``s7graph opcua``
as a child, restarted when it ends; ``web.opcua``), so an OPC UA client never shares the
scan's process either. The maximum cycle time is
``--max-cycle-ms``, by default S7's 150 ms; ``view_in_process`` (for the jitter benchmark's
comparison) serves the view in the CPU's process as before, with 1 s.
"""

from __future__ import annotations

import functools
import sqlite3
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from s7graph.engine.clock import SystemClock
from s7graph.engine.cores import kept_free
from s7graph.engine.errors import S7Error, ScanAborted
from s7graph.engine.modes import CpuMode
from s7graph.engine.persistence import StateFileError, StateStore
from s7graph.engine.record import ScanRecord
from s7graph.engine.runner import COMM_LOAD_PCT, RT_PRIORITY, Runner, core_for, keep_small_pages
from s7graph.engine.state_identity import Program
from s7graph.engine.watchdog import Watchdog
from s7graph.sfb.alarms import message_list
from s7graph.web.cli.check import view_diagnostics
from s7graph.web.cli.report import fail
from s7graph.web.cli.run_program import run_until_stopped, start_notes, state_path_of
from s7graph.web.cli.run_stop import Locate, chart_locator
from s7graph.web.cli.supervisor import child_marks, recovered_cause
from s7graph.web.harness.persist import OpenedState, open_state, refusal
from s7graph.web.harness.plant import LoadedPlant, PlantError, load_plant
from s7graph.web.harness.scl import SclSources
from s7graph.web.harness.session import ChartSession

if TYPE_CHECKING:
    from s7graph.engine.cpu import Cpu
    from s7graph.web.cli.net import NetOptions
    from s7graph.web.cli.view_process import ViewProcess
    from s7graph.web.wiring.live_edge import LiveEdge

DEFAULT_MAX_CYCLE_MS = 150.0  # S7's default maximum cycle time


@dataclass(frozen=True)
class OpcuaFace:
    """``--opcua``: where the OPC UA child serves, with its certificate and key, and what
    a client's write of a symbol sends (``--opcua-writes``)."""

    url: str
    cert: Path | None = None
    key: Path | None = None
    writes: str = "force"


IN_PROCESS_VIEW_MAX_CYCLE_MS = 1000.0
"""With ``view_in_process``: sending the scene to a new page holds the scan's process."""


def run_chart(
    path: Path,
    *,
    plant: Path | None = None,
    symbols: Path | None = None,
    state: Path | None = None,
    cycle_ms: float = 10.0,
    max_cycle_ms: float | None = None,
    duration_s: float | None = None,
    web: bool = False,
    port: int = 8080,
    record: Path | None = None,
    net: NetOptions | None = None,
    restart: str = "warm",
    fresh: bool = False,
    view_in_process: bool = False,
    session: ChartSession | None = None,
    rt_priority: int | None = RT_PRIORITY,
    comm_load_pct: float = COMM_LOAD_PCT,
    core: str | int | None = "auto",
    blocks: Sequence[Path] = (),
    opcua: OpcuaFace | None = None,
) -> int:
    """Run ``path`` until Ctrl-C/SIGTERM/``duration_s``; 0 clean, 1 plant error, STOP by
    error or state not written, 2 bad chart or a state file it cannot trust.

    ``net``: the bus and page options (``web.cli.net``); with endpoints the CPU is on the
    bus even without ``web``.

    ``max_cycle_ms`` None: ``DEFAULT_MAX_CYCLE_MS`` (``IN_PROCESS_VIEW_MAX_CYCLE_MS`` with
    ``web`` and ``view_in_process``). ``restart``: the startup from a saved state
    (``--restart``); ``fresh``: keep the old state file aside and start anew (``--fresh``).
    ``view_in_process``: serve the view in this process (the benchmark's comparison);
    ``session``: ``path`` already loaded, on the system clock (the benchmark's).
    ``rt_priority``: the scan thread's real-time priority (None: normal scheduling).
    ``comm_load_pct``: the share of the cycle commands may take at a scan boundary.
    ``core``: the processor kept for the scan (``--core``: ``engine.cores``); the bus, the
    view and the writer start off it. ``blocks``: the S7-SCL sources the chart's calls reach
    (``--blocks``), loaded beside it; their instance DBs are kept in the state file.
    ``opcua``: the OPC UA server's child (``--opcua``)."""
    try:
        kept = core_for(core, rt_priority)
    except ValueError as exc:
        return fail(f"--core: {exc}", 2)
    if rt_priority is not None:
        keep_small_pages()  # before the view starts: it inherits it
    here = web or opcua is not None  # on this machine's bus, unless --listen or --connect
    notes = start_notes(net, on_bus=here or bool(net and net.on_bus), here=here)
    with kept_free(kept):  # before the bus and the view start: they inherit it
        return _run_chart(
            path,
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
            restart=restart,
            fresh=fresh,
            view_in_process=view_in_process,
            session=session,
            rt_priority=rt_priority,
            comm_load_pct=comm_load_pct,
            core=kept,
            blocks=blocks,
            opcua=opcua,
            notes=notes,
        )


def _run_chart(
    path: Path,
    *,
    plant: Path | None,
    symbols: Path | None,
    state: Path | None,
    cycle_ms: float,
    max_cycle_ms: float | None,
    duration_s: float | None,
    web: bool,
    port: int,
    record: Path | None,
    net: NetOptions | None,
    restart: str,
    fresh: bool,
    view_in_process: bool,
    session: ChartSession | None,
    rt_priority: int | None,
    comm_load_pct: float,
    core: int | None,
    blocks: Sequence[Path] = (),
    opcua: OpcuaFace | None,
    notes: Sequence[str],
) -> int:
    made = _load(path, symbols, plant, session, blocks, web=web)
    if isinstance(made, int):
        return made
    session, loaded = made
    clock, cpu = session.clock, session.cpu
    _watch(cpu, max_cycle_ms, inline=web and view_in_process)
    recovered = recovered_cause()  # never anew after a hang (--fresh): from its last state
    opened = _open_chart_state(
        path, state, session, fresh=fresh, recovered=recovered, restart=restart
    )
    if isinstance(opened, int):
        return opened
    store = opened.store
    live: LiveEdge | None = None
    children: list[ViewProcess] = []
    if web or opcua or record is not None or (net is not None and net.on_bus):
        edges = _edges(
            session,
            store,
            web=web,
            port=port,
            record=record,
            net=net,
            path=path,
            symbols=symbols,
            in_process=view_in_process,
            opcua=opcua,
        )
        if isinstance(edges, int):
            return edges
        live, children = edges
    failure: list[str] = []
    last = [clock.now_ns()]
    runner: Runner
    where = f"plant {plant.name}" if plant is not None else "plant"

    def on_record(record: ScanRecord) -> None:
        if loaded is not None and record.mode is CpuMode.RUN:
            now = record.t_ns
            try:
                with runner.abortable(where):
                    loaded.cycle(session, now // 1_000_000, (now - last[0]) // 1_000_000)
            except ScanAborted:
                cpu.abort(where)
            except PlantError as exc:
                failure.append(str(exc))
                runner.stop()
            last[0] = now
        if live is not None:
            live.on_record(record, stats=cpu.stats, runner=runner)

    stays = web or opcua is not None or bool(recovered and live is not None and live.endpoint)
    runner = Runner(
        cpu,
        cycle_ms=cycle_ms,
        store=store,
        on_record=on_record,
        end_on_stop=not stays,
        rt_priority=rt_priority,
        comm_load_pct=comm_load_pct,
        core=core,
        marks=child_marks(),
    )
    _wire(live, runner, restart, children)
    status = run_until_stopped(
        runner,
        opened,
        what=f"{path.name} ({session.cc.name})",
        restart=restart,
        duration_s=duration_s,
        close=functools.partial(_close, children, live),
        recovered=recovered,
        locate=_locator(session),
        notes=notes,
    )
    return fail(failure[0], 1) if failure else status


def _locator(session: ChartSession) -> Locate:
    """Where the chart the session runs now (an online change may swap it) uses the operand
    a STOP's programming error names (``web.cli.run_stop.chart_locator``)."""
    return chart_locator(lambda: session.cc.chart, lambda: session.symbols)


def _watch(cpu: Cpu, max_cycle_ms: float | None, *, inline: bool) -> None:
    """Cycle monitoring at ``max_cycle_ms``, by default longer with the view in the CPU's
    process (``inline``: a page load may hold a scan up)."""
    if max_cycle_ms is None:
        max_cycle_ms = IN_PROCESS_VIEW_MAX_CYCLE_MS if inline else DEFAULT_MAX_CYCLE_MS
    cpu.watchdog = Watchdog(max_cycle_ms, cpu.watchdog.min_cycle_ns / 1e6)


def _wire(live: LiveEdge | None, runner: Runner, restart: str, children: list[ViewProcess]) -> None:
    """The bus end learns what the RUN/STOP switch's start does, and that a download is
    applied once its state is on disk (the runner's durability); the children (the
    view's, the OPC UA server's process) start."""
    if live is not None:
        live.restart = restart
        if live.online is not None:
            live.online.durability = runner
    for child in children:
        child.start()


def _close(children: list[ViewProcess], live: LiveEdge | None) -> None:
    for child in children:
        child.stop()
    if live is not None:
        live.close()


def _load(
    path: Path,
    symbols: Path | None,
    plant: Path | None,
    session: ChartSession | None,
    blocks: Sequence[Path] = (),
    *,
    web: bool = False,
) -> tuple[ChartSession, LoadedPlant | None] | int:
    """The chart's session (on the system clock unless given) with the S7-SCL ``blocks``
    and its plant, the sources' warnings and the calls of blocks the CPU lacks printed as
    warnings; an exit status when either cannot load, or with ``web`` when the view cannot
    show the chart (``check``'s W110)."""
    try:
        if session is None:
            session = ChartSession.load(path, symbols, SystemClock(), blocks=blocks)
        loaded = load_plant(plant) if plant is not None else None
    except S7Error as exc:  # ChartLoadError and SclLoadError included
        return fail(exc)
    if web and (unshown := view_diagnostics(session.cc.chart)):
        return fail(f"{path}: {unshown[0].message}; run it without --web", 2)
    for line in session.warnings + session.missing:
        print(line, file=sys.stderr)
    return session, loaded


def _edges(
    session: ChartSession, store: StateStore, **options: Any
) -> tuple[LiveEdge | None, list[ViewProcess]] | int:
    """``_serve``, or exit status 2 with one line when the view cannot be served (a port in
    use, no rerun-sdk …) or the audit's tables cannot be set up in the state file (a full
    disk); the state file is closed then."""
    try:
        return _serve(session, store, **options)
    except sqlite3.Error as exc:  # the audit's tables in the state file: its disk, not the view
        print(
            f"s7graph: error: {store.path}: cannot set up the audit ({exc}); free space on "
            "its disk (or make it writable), then run again",
            file=sys.stderr,
        )
        store.close()
        return 2
    except Exception as exc:
        from s7graph.web.cli.net import edge_error

        why = edge_error(exc, options.get("net"), web=bool(options.get("web")))
        print(f"s7graph: error: {why}", file=sys.stderr)
        store.close()
        return 2


def _open_chart_state(
    chart: Path,
    state: Path | None,
    session: ChartSession,
    *,
    fresh: bool,
    recovered: tuple[str, str] | None,
    restart: str,
) -> OpenedState | int:
    """The chart's state file (``state``, else its default beside ``chart``) opened and the
    CPU restored from it, or the exit status when it cannot be used. A recovered CPU stays
    in STOP until started."""
    state_path = state_path_of(chart, state, session.cpu)
    try:
        return open_state(
            state_path,
            session.cpu,
            fresh=fresh and not recovered,
            hot=restart == "hot",
            restart=None if recovered else restart,
            program=Program.of(chart),
        )
    except StateFileError as exc:
        print(refusal(exc), file=sys.stderr)
        return 2
    except OSError as exc:
        return fail(f"{state_path}: cannot use the state file: {exc.strerror or exc}")


def _serve(
    session: ChartSession,
    store: StateStore,
    *,
    web: bool,
    port: int,
    record: Path | None,
    net: NetOptions | None = None,
    path: Path | None = None,
    symbols: Path | None = None,
    in_process: bool = False,
    opcua: OpcuaFace | None = None,
) -> tuple[LiveEdge, list[ViewProcess]]:
    """The CPU on the bus (and the recording) of the session's GraphFB, its online change
    (``path``: the chart file a download rewrites, with the session's S7-SCL source files
    it may bring changed), and the view's process (not started
    yet) when ``web``; prints where to look."""
    from s7graph.web.bus.block_sources import serve_blocks
    from s7graph.web.bus.forcing import Forcing
    from s7graph.web.bus.gate import cpu_gate  # zenoh and viser only when asked for
    from s7graph.web.bus.live import LiveGraph, watch_names
    from s7graph.web.bus.online import OnlineChange
    from s7graph.web.bus.operands import OperandFeed
    from s7graph.web.cli.net import NetOptions
    from s7graph.web.cli.view_process import run_view
    from s7graph.web.harness.scl import scl_of
    from s7graph.web.view.port import check_port
    from s7graph.web.wiring.live_edge import LiveEdge

    net = net or NetOptions()
    if web:
        check_port(net.host, port)
    live = LiveGraph(
        session.graph,
        read=session.get,
        reader=session.reader,
        watch=watch_names(session.symbols),
        messages=message_list(session.cpu),
    )
    gate = cpu_gate(net.users, store, cpu=session.cpu)
    table = symbols.read_text(encoding="utf-8-sig") if symbols is not None else ""
    blocks = [Path(f) for b in session.blocks if isinstance(b, SclSources) for f in b.files]
    online = OnlineChange(session, live, gate, path=path, symbols=table, blocks=blocks)
    inline = web and in_process
    edge = LiveEdge(
        live,
        port=port,
        record=record,
        serve=inline,
        bus=web or net.on_bus or opcua is not None,
        cpu=net.cpu,
        host=net.host,
        ends=net.ends,
        gate=gate,
        allowed_origins=tuple(net.origins),
        online=online,
        forcing=Forcing(session.cpu),
        operands=OperandFeed(session, fb=live.fb),
    )
    if edge.publisher is not None:  # the blocks of --blocks, as the CPU runs them now
        serve_blocks(edge.publisher, lambda: scl_of(session.blocks))
    view = None
    if inline:
        print(f"s7graph: view {edge.url} (bus {edge.endpoint}); Ctrl-C to stop", flush=True)
    elif web:
        view = run_view(net, port, edge.endpoint)
    elif edge.endpoint:
        print(f"s7graph: CPU {net.cpu} on the bus {edge.endpoint}; Ctrl-C to stop", flush=True)
    if record is not None:
        print(f"s7graph: recording to {record}", flush=True)
    children = [view] if view is not None else []
    if opcua is not None:
        children.append(_opcua_child(opcua, net, edge.endpoint))
    return edge, children


def _opcua_child(face: OpcuaFace, net: NetOptions, bus: str) -> ViewProcess:
    """The OPC UA server's process (``s7graph opcua`` as a child); prints where it serves
    the first time it does."""
    from s7graph.web.cli.opcua import OpcuaProcess
    from s7graph.web.cli.view_process import view_endpoints

    child = OpcuaProcess(
        connect=view_endpoints(net.listen, net.connect) or [bus],
        cpu=net.cpu,
        url=face.url,
        users=net.users,
        cert=face.cert,
        key=face.key,
        tls_ca=net.tls_ca,
        bus_args=net.credential_args(),
        writes=face.writes,
    )

    def served(url: str) -> None:
        if child.starts == 1:
            print(f"s7graph: opcua {url} (bus {bus}); Ctrl-C to stop", flush=True)

    child.on_url = served
    return child
