"""``s7graph run PROGRAM.scl [--blocks MORE.scl …]``: a program of S7-SCL blocks on the
system clock (docs/cli.md, "s7graph run"; docs/scl.md, "On the command line").

The sources are compiled in order (``--blocks`` first, ``web.harness.scl``) with the system
blocks, loaded into one CPU (maximum cycle time ``--max-cycle-ms``, else S7's 150 ms) and
run as a Python program is (``web.cli.run_program``, whose run this is): the state file
restores the retentive data, the global DBs and every instance DB by number — an FB whose
interface changed keeps its variables by name — and the CPU starts by ``--restart`` (warm
by default; cold: every DB at its initial values). A source that does not compile is its
diagnostics on stderr, exit 2; a STOP by error ends the run, exit 1. With
``--listen``/``--connect`` the CPU is on the bus as a Python program's is (status, diag,
force, stop/start/mres, watch) and serves its sources on ``blocks``; ``--web`` serves its
page.
"""

from __future__ import annotations

import functools
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from s7graph import sfb
from s7graph.engine.clock import Clock
from s7graph.engine.cpu import Cpu
from s7graph.engine.errors import S7Error
from s7graph.engine.runner import COMM_LOAD_PCT, RT_PRIORITY
from s7graph.engine.symbols import SymbolTable
from s7graph.web.cli.run_program import LoadedProgram, run_program
from s7graph.web.harness.scl import compile_sources

if TYPE_CHECKING:
    from s7graph.web.cli.net import NetOptions

DEFAULT_MAX_CYCLE_MS = 150.0  # S7's default maximum cycle time


def load_scl(
    paths: Sequence[Path], symbols: Path | None, clock: Clock, *, max_cycle_ms: float | None
) -> LoadedProgram:
    """The sources ``paths`` in their CPU, for ``run_program``: ``S7Error`` when they do
    not compile (their diagnostics) or the symbols cannot be read."""
    try:
        table = SymbolTable.from_file(symbols) if symbols is not None else None
    except OSError as exc:
        raise S7Error(f"cannot read symbols {symbols}: {exc.strerror or exc}") from None
    sources = compile_sources(paths, table)
    for line in sources.warnings:
        print(line, file=sys.stderr)
    cpu = Cpu(clock, max_cycle_ms=max_cycle_ms or DEFAULT_MAX_CYCLE_MS)
    cpu.mem.symbols = table
    sfb.install(cpu)
    sources.load(cpu)
    return LoadedProgram(cpu, sources=sources)


def run_scl(
    path: Path,
    *,
    blocks: Sequence[Path] = (),
    symbols: Path | None = None,
    state: Path | None = None,
    cycle_ms: float = 10.0,
    duration_s: float | None = None,
    max_cycle_ms: float | None = None,
    restart: str | None = None,
    fresh: bool = False,
    rt_priority: int | None = RT_PRIORITY,
    core: str | int | None = None,
    net: NetOptions | None = None,
    web: bool = False,
    port: int = 8080,
    comm_load_pct: float = COMM_LOAD_PCT,
) -> int:
    """Run the SCL program ``path`` until Ctrl-C/SIGTERM/``duration_s`` as ``run_program``
    runs a program (on the bus with ``net``, its page with ``web``); its exit status."""
    return run_program(
        path,
        state=state,
        cycle_ms=cycle_ms,
        duration_s=duration_s,
        max_cycle_ms=max_cycle_ms,
        restart=restart,
        fresh=fresh,
        rt_priority=rt_priority,
        core=core,
        net=net,
        web=web,
        port=port,
        comm_load_pct=comm_load_pct,
        load=functools.partial(load_scl, [*blocks, path], symbols, max_cycle_ms=max_cycle_ms),
    )
