"""The trace of ``s7graph sim``, for a chart and for an S7-SCL program alike (docs/cli.md,
"s7graph sim").

Each cycle ``k`` (at ``t_ms = k * cycle_ms``): set the stimuli with ``at_ms <= t_ms``
(values stay until set again), run the cycle, write one JSON line — ``cycle``, ``t_ms``,
what the program reports (``active``, ``events``, ``mode``) and the ``--watch`` values —
then advance the virtual clock by ``cycle_ms``. A scan that ends in STOP ends the trace
with its line, the reason on stderr and exit status 1.
"""

from __future__ import annotations

import json
import math
import signal
import sys
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Protocol, TextIO

from s7graph.engine.clock import VirtualClock
from s7graph.engine.cpu import Cpu
from s7graph.engine.datatypes import real_shown
from s7graph.engine.errors import S7Error
from s7graph.engine.record import ScanRecord
from s7graph.engine.runner import stop_reason
from s7graph.web.harness.scl import read_source

Stimulus = list[tuple[float, dict[str, Any], str]]
"""The stimulus lines in time order: (at_ms, what they set, ``FILE:LINE``)."""
Cycle = Callable[[int, float], tuple[ScanRecord, dict[str, Any]]]
"""One cycle ``(k, t_ms)``: scan, and the fields the line reports of it besides the values."""


class Traced(Protocol):
    """A session a trace drives: names checked, set by stimuli and read for ``--watch``."""

    cpu: Cpu

    def check_name(self, name: str, *, writing: bool) -> None: ...

    def set(self, name: str, value: Any) -> None: ...

    def get(self, name: str) -> Any: ...


def read_stimulus(path: Path | None) -> Stimulus:
    """The JSONL stimulus ``{"at_ms": 0, "set": {...}}`` a line, in time order, each with
    its place (``FILE:LINE``); S7Error naming the file (and line) that cannot be read."""
    if path is None:
        return []
    out: Stimulus = []
    for n, line in enumerate(read_source(Path(path)).splitlines(), 1):
        if not line.strip():
            continue
        try:
            at, values = _stimulus_line(line)
        except RecursionError:
            raise S7Error(f"{path}:{n}: bad stimulus line: nested too deep") from None
        except ValueError as exc:
            raise S7Error(f"{path}:{n}: bad stimulus line: {exc}") from None
        out.append((at, values, f"{path}:{n}"))
    out.sort(key=lambda item: item[0])
    return out


def _stimulus_line(line: str) -> tuple[float, dict[str, Any]]:
    """``(at_ms, set)`` of one stimulus line; ValueError saying what is wrong, in words."""
    try:
        obj = json.loads(line)
    except json.JSONDecodeError as exc:
        raise ValueError(f"not JSON ({exc.msg}, column {exc.colno})") from None
    except ValueError:  # a number of more digits than Python converts
        raise ValueError("a number too long to read") from None
    if not isinstance(obj, dict):
        raise ValueError('a line is an object {"at_ms": 0, "set": {...}}')
    if not isinstance(obj.get("set"), dict):
        raise ValueError('"set" must be an object of names and values')
    at = obj.get("at_ms", 0)
    if isinstance(at, bool) or not isinstance(at, int | float) or not 0 <= at < math.inf:
        raise ValueError("at_ms must be a time in ms from 0 on")
    return float(at), obj["set"]


def checked_inputs(
    session: Traced, stimulus: Path | None, watch: str
) -> tuple[Stimulus, list[str]]:
    """The stimulus and the watched names, every name checked against ``session``: a name
    it cannot read, or a stimulus name it cannot write, raises S7Error."""
    stim = read_stimulus(stimulus)
    names = [w.strip() for w in watch.split(",") if w.strip()]
    for name in names:
        session.check_name(name, writing=False)
    for _, values, where in stim:
        for name in values:
            try:
                session.check_name(name, writing=True)
            except S7Error as exc:
                raise S7Error(f"{where}: {exc.message}") from None
    return stim, names


@contextmanager
def trace_out(trace: Path | None) -> Iterator[TextIO]:
    """The trace's file, or stdout without ``--trace``."""
    if trace is None:
        yield sys.stdout
        return
    try:
        out = open(trace, "w", encoding="utf-8")  # noqa: SIM115  (closed below)
    except OSError as exc:
        raise S7Error(f"cannot write the trace {trace}: {exc.strerror or exc}") from None
    with out:
        yield out


def ms(v: float) -> int | float:
    """A time in ms as the trace writes it: whole numbers as integers."""
    return int(v) if float(v).is_integer() else round(v, 6)


def traced(value: Any) -> Any:
    """A value as the trace writes it: a REAL (in an ARRAY or STRUCT too) as the CPU shows
    it (``engine.datatypes.real_shown``)."""
    if isinstance(value, float):
        return real_shown(value)
    if isinstance(value, list):
        return [traced(v) for v in value]
    if isinstance(value, dict):
        return {k: traced(v) for k, v in value.items()}
    return value


def run_trace(
    session: Traced,
    clock: VirtualClock,
    cycle: Cycle,
    stim: Stimulus,
    names: list[str],
    cycle_ms: float,
    cycles: int,
    out: TextIO,
) -> int:
    """Run ``cycles`` cycles writing one line each; the exit status (0, or 1 on STOP; 130
    when Ctrl-C ends it between two cycles, ``_interrupts``)."""
    with _interrupts() as asked:
        nxt = 0
        for k in range(cycles):
            if asked:
                done = f"cycles 0 to {k - 1}" if k else "no cycle"
                print(f"s7graph: sim stopped by Ctrl-C: the trace holds {done}", file=sys.stderr)
                return 130
            t_ms = k * cycle_ms
            nxt = _stimulate(session, stim, nxt, t_ms)
            record, fields = cycle(k, t_ms)
            line = {
                "cycle": k,
                "t_ms": ms(t_ms),
                **fields,
                "values": {name: traced(session.get(name)) for name in names},
            }
            out.write(json.dumps(line) + "\n")
            if record.mode.name == "STOP":
                why = stop_reason(session.cpu)
                print(f"s7graph: error: cycle {k}: the CPU went to STOP: {why}", file=sys.stderr)
                return 1
            clock.advance(cycle_ms)
        return 0


@contextmanager
def _interrupts() -> Iterator[list[int]]:
    """Ctrl-C (SIGINT) while a sim runs, noted for the loop to end between two cycles: as an
    interrupt inside a block it would be that block's programming error (a STOP, exit 1)."""
    asked: list[int] = []
    if threading.current_thread() is not threading.main_thread():
        yield asked
        return
    previous = signal.getsignal(signal.SIGINT)
    if previous is signal.SIG_IGN or previous is None:  # started in the background
        yield asked
        return
    signal.signal(signal.SIGINT, lambda signum, frame: asked.append(signum))
    try:
        yield asked
    finally:
        signal.signal(signal.SIGINT, previous)


def _stimulate(session: Traced, stim: Stimulus, nxt: int, t_ms: float) -> int:
    """Set what the stimulus lines from ``nxt`` due by ``t_ms`` set; the next line's index.
    A value a name cannot take raises S7Error naming the line and the name."""
    while nxt < len(stim) and stim[nxt][0] <= t_ms + 1e-9:
        _, values, where = stim[nxt]
        for name, value in values.items():
            try:
                session.set(name, value)
            except S7Error as exc:
                said = exc.message
                named = said if said.startswith(f"{name}: ") else f"{name}: {said}"
                raise S7Error(f"{where}: {named}") from None
        nxt += 1
    return nxt
