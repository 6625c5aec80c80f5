"""``s7graph run PROGRAM.py``: a Python program of blocks on the system clock.

Program convention: a Python file whose module-level ``@ob``/``@fb``/``@fc`` blocks (and
``DB`` definitions) are loaded; an optional ``CPU = {...}`` dict passes keyword options to
``Cpu`` (``max_cycle_ms``, ``clock_memory``, ...; ``--max-cycle-ms`` overrides its
``max_cycle_ms``); an optional ``setup(cpu)`` creates
instance DBs and configures interrupts. The state file restores retentive data and the
CPU's message list (who acknowledged what, when; every message event is also appended to
its alarm log) and the CPU comes back by warm restart; on Ctrl-C, SIGTERM or
``--duration-s`` the CPU goes to STOP (outputs 0) and the state is saved. A broken program
is one line on stderr and exit 2.
"""

from __future__ import annotations

import importlib.util
import signal
import sys
from collections.abc import Callable
from pathlib import Path
from types import FrameType, ModuleType
from typing import Any

from s7graph.engine.blocks import DB, FB, FC, OB
from s7graph.engine.clock import SystemClock
from s7graph.engine.cpu import Cpu
from s7graph.engine.modes import CpuMode
from s7graph.engine.persistence import StateStore
from s7graph.engine.record import ScanRecord
from s7graph.engine.runner import Runner
from s7graph.web.harness.persist import persist_messages


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
    it (S7's 150 ms when the program sets none)."""
    blocks = [v for v in vars(module).values() if isinstance(v, OB | FB | FC | DB)]
    if not any(isinstance(b, OB) for b in blocks):
        raise ProgramLoadError("defines no OB (decorate a function with @ob(1) or @ob(35))")
    options = getattr(module, "CPU", {})
    if not isinstance(options, dict):
        raise ProgramLoadError("CPU must be a dict of Cpu options")
    if max_cycle_ms is not None:
        options = {**options, "max_cycle_ms": max_cycle_ms}
    try:
        cpu = Cpu(clock, **options)
        cpu.load(*blocks)
        setup: Callable[[Cpu], object] | None = getattr(module, "setup", None)
        if setup is not None:
            setup(cpu)
    except Exception as exc:
        raise ProgramLoadError(f"{type(exc).__name__}: {exc}") from None
    return cpu


def _report(record: ScanRecord) -> None:
    for entry in record.diagnostics:
        if entry.event_id >> 8 in (0x45, 0x25, 0x35):
            print(f"s7graph: {entry}", file=sys.stderr)


def _terminate(signum: int, frame: FrameType | None) -> None:
    raise KeyboardInterrupt


def run_program(
    path: Path,
    *,
    state: Path | None,
    cycle_ms: float,
    duration_s: float | None,
    max_cycle_ms: float | None = None,
) -> int:
    """Run a program until Ctrl-C/SIGTERM/duration; 0 on a clean end, 2 on a broken program.

    ``max_cycle_ms``: the maximum cycle time; None keeps the program's (see ``build_cpu``)."""
    try:
        module = import_program(path)
        cpu = build_cpu(module, SystemClock(), max_cycle_ms=max_cycle_ms)
    except ProgramLoadError as exc:
        return _fail(path, str(exc))
    state_path = state if state is not None else path.with_suffix(".state.sqlite")
    try:
        store = StateStore(state_path)
    except Exception as exc:
        return _fail(state_path, f"cannot open state file: {exc}")
    try:
        persist_messages(store, cpu)
        restored = store.load(cpu)
    except Exception as exc:
        store.close()
        return _fail(state_path, f"state does not fit this program: {exc}")
    runner = Runner(cpu, cycle_ms=cycle_ms, store=store, on_record=_report)
    run_until_stopped(
        runner, store, what=path.name, restored=restored, state_path=state_path,
        duration_s=duration_s, on_start=_report,
    )  # fmt: skip
    return 0


def run_until_stopped(
    runner: Runner,
    store: StateStore,
    *,
    what: str,
    restored: bool,
    state_path: Path,
    duration_s: float | None,
    on_start: Callable[[ScanRecord], object] | None = None,
    close: Callable[[], object] | None = None,
) -> None:
    """Warm-start the runner's CPU (``on_start`` gets the startup record), say so on stderr
    with ``what``, save the state, and scan until Ctrl-C/SIGTERM/``duration_s``. Always:
    SIGTERM's handler back, the runner shut down, ``close()``, the store closed."""
    cpu = runner.cpu
    previous = signal.signal(signal.SIGTERM, _terminate)
    try:
        record = cpu.start("warm")
        runner.log_alarms(record)
        if on_start is not None:
            on_start(record)
        how = f"warm restart from {state_path}" if restored else "fresh start"
        print(f"s7graph: {what} in {cpu.mode} ({how})", file=sys.stderr)
        store.save(cpu)
        if cpu.mode is CpuMode.RUN:
            runner.run(duration_s=duration_s)
    except KeyboardInterrupt:
        pass
    finally:
        signal.signal(signal.SIGTERM, previous)
        runner.shutdown("s7graph run ended")
        if close is not None:
            close()
        store.close()
