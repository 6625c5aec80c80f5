"""How ``s7graph run`` says that its CPU went to STOP by itself, and whether that is the
run's failure (docs/cli.md, "s7graph run").

A STOP by an error (a ``16#45xx`` STOP entry: a programming error without OB121, a time
error, an aborted block, the state file not written …) is one line on stderr at once, the
words of ``s7graph status``'s ``STOP:`` line (``engine.runner.stop_reason``: the error entry
of the diagnostic buffer — block, operand, message — and the STOP entry's message), in
startup too (``in its startup (OB100)``: before its first cycle), with where a chart uses the
operand an area length error names (``locate``); the run then ends with exit status 1.
A STOP the program requested (SFC46 STP: the STOP entry ``16#4304``, as a PG STOP) is said
without ``error:`` and is no failure: an S7 CPU shows it by its STOP LED alone, without the
SF (system fault) LED of a STOP by an error. A startup the CPU refuses (its entry
``16#4309``: the key switch in STOP, a startup OB loaded but deselected) leaves it in STOP
without a STOP entry: said the same way, the block the entry names first, and the run's
failure as a STOP by an error is.
"""

from __future__ import annotations

import sys
from collections.abc import Callable

from s7graph.engine.diag_events import stop_cause
from s7graph.engine.diagnostics import EventId
from s7graph.engine.modes import CpuMode
from s7graph.engine.record import DiagEntry, ScanRecord
from s7graph.engine.runner import Runner, refused_startup, stop_reason
from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.checks.default_cpu import default_cpu_warnings
from s7graph.sequencer.text.model import Chart

__all__ = ["RunStop", "chart_locator"]

Locate = Callable[[DiagEntry], str]
"""Where the program uses what an error entry names (``; I200.0: first used at …``), or ""."""


class RunStop:
    """The run's ``Runner.on_stop``: says each STOP by itself of ``what`` (its program's
    name) on stderr, and remembers whether the last one was requested (``requested``)."""

    def __init__(self, what: str, locate: Locate | None = None) -> None:
        self.what = what
        self.locate = locate
        self.requested = False
        """Whether the last STOP by itself was the program's request (SFC46 STP)."""
        self._runner: Runner | None = None

    def __call__(self, reason: str, *, where: str = "") -> None:
        """Say the STOP of ``reason`` (``Runner.on_stop``); ``where``: `` in its startup
        (OB100)`` for one before the first cycle."""
        cpu_stop = self._stop_entry
        self.requested = cpu_stop is not None and cpu_stop.event_id == EventId.STOP_BY_REQUEST
        if self.requested:
            line = f"s7graph: {self.what}: the CPU went to STOP{where}: {reason}"
            line += " (the program's request, not an error)"
        else:
            line = f"s7graph: error: {self.what}: the CPU went to STOP{where}: {reason}"
            line += self._located()
        print(line, file=sys.stderr, flush=True)

    def bind(self, runner: Runner) -> None:
        """Say ``runner``'s STOPs by itself from now on."""
        self._runner = runner
        runner.on_stop = self

    def after_startup(self, runner: Runner, record: ScanRecord) -> None:
        """When the startup of ``record`` ended in STOP by itself (its STOP entry among the
        startup's entries) or was refused (``engine.runner.refused_startup``): say it, and
        the run ends with it as with a STOP in a cycle (``Runner.stopped``)."""
        if runner.cpu.mode is not CpuMode.STOP:
            return
        stop = runner.cpu.stop_entry
        if stop is None or not any(entry is stop for entry in record.diagnostics):
            if refused_startup(runner.cpu) is not None:
                self.requested = False
                runner.stopped = stop_reason(runner.cpu)  # "the CPU refused its startup: …"
                print(f"s7graph: error: {self.what}: {runner.stopped}", file=sys.stderr, flush=True)
            return
        runner.stopped = stop_reason(runner.cpu)
        self(runner.stopped, where=f" in its startup (OB{stop.ob})" if stop.ob else "")

    def failed(self, runner: Runner) -> bool:
        """Whether ``runner``'s run ends by a STOP by an error (not a requested one)."""
        return bool(runner.stopped) and not self.requested

    @property
    def _stop_entry(self) -> DiagEntry | None:
        return self._runner.cpu.stop_entry if self._runner is not None else None

    def _located(self) -> str:
        """Where the program uses what the programming error behind a STOP without OB121
        names (``locate``), or ""."""
        stop = self._stop_entry
        if self.locate is None or self._runner is None or stop is None:
            return ""
        if stop.event_id != EventId.STOP_OB121_MISSING:
            return ""
        cause = stop_cause(self._runner.cpu.diagnostics, stop)
        return self.locate(cause) if cause is not None else ""


def chart_locator(chart: Callable[[], Chart], symbols: Callable[[], SymbolTable]) -> Locate:
    """Where ``chart()`` first uses the operand a programming error (``16#25xx``: an area
    length error) names, as ``s7graph check``'s W140 finds it for a default CPU's memory
    (``sequencer.checks.default_cpu``): ``; I200.0: first used at c.s7g:7:33 (transition
    T1)``; "" for another entry or an operand it does not find."""

    def locate(entry: DiagEntry) -> str:
        if entry.event_id >> 8 != 0x25:
            return ""
        said = entry.message.casefold()
        for warning in default_cpu_warnings(chart(), symbols()):
            name = warning.message.split(" is beyond ", 1)[0]
            names = {name, name.split(" (", 1)[0].strip('"')}
            if any(said.startswith((f"{n.casefold()} ", f"{n.casefold()}:")) for n in names):
                return f"; {name}: first used at {warning.loc} ({warning.element})"
        return ""

    return locate
