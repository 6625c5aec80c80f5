"""``s7graph run PROGRAM.scl [--blocks MORE.scl …]``: a program of S7-SCL blocks on the
system clock (docs/cli.md, "s7graph run"; docs/scl.md, "On the command line").

The sources are compiled in order (``--blocks`` first, ``web.harness.scl``) with the system
blocks, loaded into one CPU (maximum cycle time ``--max-cycle-ms``, else S7's 150 ms) and
run as a Python program is (``web.cli.run_program``): the state file restores the retentive
data, the global DBs and every instance DB by number — an FB whose interface changed keeps
its variables by name — and the CPU starts by ``--restart`` (warm by default; cold: every
DB at its initial values). A source that does not compile is its diagnostics on stderr,
exit 2; a STOP by error ends the run, exit 1.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from pathlib import Path

from s7graph import sfb
from s7graph.engine.clock import SystemClock
from s7graph.engine.cpu import Cpu
from s7graph.engine.errors import S7Error
from s7graph.engine.persistence import StateFileError
from s7graph.engine.runner import RT_PRIORITY, Runner, core_for, keep_small_pages
from s7graph.engine.symbols import SymbolTable
from s7graph.web.cli.report import fail
from s7graph.web.cli.run_program import _report, run_until_stopped
from s7graph.web.cli.supervisor import child_marks, recovered_cause
from s7graph.web.harness.persist import open_state, refusal
from s7graph.web.harness.scl import compile_sources

DEFAULT_MAX_CYCLE_MS = 150.0  # S7's default maximum cycle time


def build_scl_cpu(
    paths: Sequence[Path], symbols: Path | None, clock: object, max_cycle_ms: float | None
) -> Cpu:
    """A CPU with the system blocks and the compiled sources ``paths`` loaded; ``S7Error``
    (``SclLoadError``: the diagnostics) when they do not compile or cannot be read."""
    table = SymbolTable.from_file(symbols) if symbols is not None else None
    sources = compile_sources(paths, table)
    for line in sources.warnings:
        print(line, file=sys.stderr)
    cpu = Cpu(clock, max_cycle_ms=max_cycle_ms or DEFAULT_MAX_CYCLE_MS)  # type: ignore[arg-type]
    cpu.mem.symbols = table
    sfb.install(cpu)
    sources.load(cpu)
    return cpu


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
) -> int:
    """Run the SCL program ``path`` until Ctrl-C/SIGTERM/``duration_s``; the exit status as
    ``run_program``'s."""
    if rt_priority is not None:
        keep_small_pages()
    try:
        cpu = build_scl_cpu([*blocks, path], symbols, SystemClock(), max_cycle_ms)
        kept = core_for(core if core is not None else "auto", rt_priority)
    except ValueError as exc:
        return fail(f"--core: {exc}")
    except S7Error as exc:  # SclLoadError included: its diagnostics
        return fail(exc)
    except OSError as exc:
        return fail(f"cannot read symbols {symbols}: {exc.strerror or exc}")
    restart = restart or "warm"
    recovered = recovered_cause()
    state_path = state if state is not None else path.with_suffix(".state.sqlite")
    try:
        opened = open_state(
            state_path,
            cpu,
            fresh=fresh and recovered is None,
            hot=restart == "hot",
            restart=None if recovered else restart,
        )
    except StateFileError as exc:
        print(refusal(exc), file=sys.stderr)
        return 2
    except OSError as exc:
        return fail(f"{state_path}: cannot use the state file: {exc.strerror or exc}")
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
