"""``s7graph check PROGRAM.scl`` and ``s7graph sim PROGRAM.scl``: an S7-SCL source checked,
or run on the virtual clock (docs/cli.md, "s7graph sim"; docs/scl.md, "On the command line").

``check`` prints the source's diagnostics one a line and a summary — exit 0 clean, 1
warnings only, 2 errors — as for a chart; an absolute operand (a symbol's too) beyond a
default CPU's memory warns, W140, as a chart's (``sequencer.checks.default_cpu``). ``sim``
compiles the source with the system blocks, loads it into a CPU on the virtual clock, starts
it (OB100) and runs ``cycles`` scans ``cycle_ms`` apart, one JSON line a cycle in the
chart's trace format: ``active`` and ``events`` are empty lists (no GRAPH FB runs), ``mode``
is the CPU's mode, ``values`` the ``--watch`` names — addresses, symbols and DB variables by
name (``DB10.CONTROL``, ``DB20.motor[2].on``: ``web.harness.dbvars``), their types kept.
Stimuli set addresses and symbols (an input on the module side) and elementary DB variables;
a plant (``--plant``) runs with a chart only. ``--blocks`` sources are compiled first, in
order, and the program calls their blocks (``web.harness.scl``). A source that does not
compile is its diagnostics on stderr, exit 2; a STOP ends the trace with that cycle, the
reason on stderr, exit 1.
"""

from __future__ import annotations

import json
import re
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from s7graph import sfb
from s7graph.engine.address import Address, Area
from s7graph.engine.blocks import FB, FC
from s7graph.engine.clock import VirtualClock
from s7graph.engine.cpu import Cpu
from s7graph.engine.errors import S7Error
from s7graph.engine.record import ScanRecord
from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.checks.default_cpu import scl_default_cpu_warnings
from s7graph.steps.diagnostics import sort_key
from s7graph.steps.scl import format_diagnostic
from s7graph.steps.scl.check import check_scl_source
from s7graph.web.cli.report import fail
from s7graph.web.cli.trace import checked_inputs, run_trace, trace_out
from s7graph.web.harness.dbvars import DbVariables
from s7graph.web.harness.operands import address_of, write_operand
from s7graph.web.harness.scl import (
    Loadable,
    SclLoadError,
    SclSources,
    compile_sources,
    compile_texts,
    read_source,
)

_SEVERITY = re.compile(r": (error|warning)[\[:]")


def _symbols(path: Path | None) -> SymbolTable | None:
    if path is None:
        return None
    try:
        return SymbolTable.from_file(path)
    except OSError as exc:
        raise S7Error(f"cannot read symbols {path}: {exc.strerror or exc}") from None
    except S7Error as exc:
        raise S7Error(f"cannot read symbols {path}: {exc}") from None


def check_scl_command(
    source: Path, symbols: Path | None = None, blocks: Sequence[Path] = ()
) -> int:
    """Print the diagnostics of an SCL source and a summary; return the exit status.
    ``blocks``: sources compiled before it whose FBs and FCs it may call (their errors are
    printed and counted, the source itself not checked then); a clean source is also refused
    as ``run`` refuses it beside them (a DB of theirs made an instance, a block twice)."""
    try:
        text, table = read_source(source), _symbols(symbols)
        known = compile_sources(blocks, table)
    except SclLoadError as exc:
        return _summary(source, exc.lines)
    except S7Error as exc:
        return fail(exc)
    found, parsed = check_scl_source(
        text, str(source), blocks=[*sfb.SYSTEM_BLOCKS, *_callable(known)], symbols=table
    )
    if not any(d.is_error for d in found):  # what a default CPU lacks (W140, as for a chart)
        beyond = scl_default_cpu_warnings(parsed, table)
        found = sorted([*found, *beyond], key=sort_key)
    lines = known.warnings + [format_diagnostic(d) for d in found]
    if blocks and not any(d.is_error for d in found):
        named = [*zip(known.files, known.texts, strict=True), (str(source), text)]
        try:  # what ``run`` refuses beside the sources: a DB written twice, a DB made an instance
            compile_texts(named, table)
        except SclLoadError as exc:
            lines += [line for line in exc.lines if ": warning" not in line]
    return _summary(source, lines)


def _callable(known: SclSources) -> list[FB | FC]:
    return [b for b in known.blocks if isinstance(b, FB | FC)]


def _summary(source: Path, lines: list[str]) -> int:
    """Print diagnostic ``lines`` and the summary of ``source``; the exit status."""
    for line in lines:
        print(line)
    errors = sum(_severity(line) == "error" for line in lines)
    warnings = len(lines) - errors
    print(f"{source}: {_plural(errors, 'error')}, {_plural(warnings, 'warning')}")
    return 2 if errors else 1 if warnings else 0


def _severity(line: str) -> str:
    """``error`` or ``warning``: the first severity a diagnostic line names."""
    found = _SEVERITY.search(line)
    return found[1] if found is not None else "error"


def _plural(n: int, word: str) -> str:
    return f"{n} {word}" if n == 1 else f"{n} {word}s"


class SclSession:
    """One CPU on the virtual clock running a compiled SCL program."""

    def __init__(self, program: Loadable, symbols: SymbolTable | None) -> None:
        self.clock = VirtualClock()
        self.cpu = Cpu(self.clock)
        self.cpu.mem.symbols = symbols
        self.symbols = symbols
        sfb.install(self.cpu)
        program.load(self.cpu)
        self.dbvars = DbVariables(self.cpu, getattr(program, "types", {}))

    def _address(self, name: str) -> tuple[Address, str] | None:
        return address_of(self.symbols, name)

    def check_name(self, name: str, *, writing: bool = False) -> None:
        found = self._address(name)
        if found is not None:
            if found[0].area in (Area.T, Area.C):
                self.cpu.mem.read_as(found[0], "BOOL")  # a cell beyond the CPU's: S7Error
            return
        unknown = f"unknown name {name}: not an address, symbol or DBn.variable"
        self.dbvars.check(name, writing=writing, unknown=unknown)

    def get(self, name: str) -> Any:
        found = self._address(name)
        if found is None:
            return self.dbvars.reader(name)()
        addr, type_name = found
        if addr.area in (Area.T, Area.C):
            return bool(self.cpu.mem.read_as(addr, "BOOL"))
        return _json(self.cpu.mem.read_as(addr, type_name))

    def set(self, name: str, value: Any) -> None:
        found = self._address(name)
        if found is None:
            self.dbvars.writer(name)(value)
            return
        write_operand(self.cpu.mem, *found, value)


def _json(v: Any) -> Any:
    if isinstance(v, bool | int | float | str) or v is None:
        return v
    if isinstance(v, list | dict):
        return json.loads(json.dumps(v, default=str))
    return str(v)


def sim_scl_command(
    source: Path,
    /,
    *,
    stimulus: Path | None = None,
    cycle_ms: float = 10.0,
    cycles: int = 100,
    watch: str = "",
    trace: Path | None = None,
    symbols: Path | None = None,
    plant: Path | None = None,
    blocks: Sequence[Path] = (),
) -> int:
    """Run the SCL program for ``cycles`` cycles; return the exit status. ``blocks``:
    sources compiled before it, whose blocks it calls (``web.harness.scl``)."""
    if plant is not None:
        return fail(f"{source}: a plant runs with a chart only, not with an SCL program")
    try:
        table = _symbols(symbols)
        program = compile_sources([*blocks, source], table)
    except S7Error as exc:  # SclLoadError included: its diagnostics
        return fail(exc)
    for line in program.warnings:
        print(line, file=sys.stderr)
    try:
        session = SclSession(program, table)
        stim, names = checked_inputs(session, stimulus, watch)
    except S7Error as exc:
        return fail(exc)

    def cycle(k: int, t_ms: float) -> tuple[ScanRecord, dict[str, Any]]:
        record = session.cpu.scan()
        return record, {"active": [], "events": [], "mode": record.mode.name}

    try:
        with trace_out(trace) as out:
            session.cpu.start("warm")
            return run_trace(session, session.clock, cycle, stim, names, cycle_ms, cycles, out)
    except S7Error as exc:
        return fail(exc)
