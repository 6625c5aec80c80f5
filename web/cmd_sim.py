"""``s7graph sim``: run a chart on the virtual clock — the black-box contract of SPEC §4.

Each cycle (``k`` = 0, 1, …, at ``t_ms = k * cycle_ms``): apply the stimuli with
``at_ms <= t_ms`` (values stay until set again), read inputs, call the FB from OB1, write
outputs, run the plant (if any), write one JSON line, advance the clock by ``cycle_ms``::

    {"cycle": 7, "t_ms": 70, "active": ["S1", "S3"], "events": [["S1", "S3"]],
     "mode": "AUTO", "values": {"Q0.0": true, "S_NO": 3, "ERR_FLT": false}}

``active``: the active steps sorted by number. ``events``: the transitions switched in this
cycle, in switching order, as ``[from, to]`` step pairs — one pair per preceding × following
step (a divergence from S1 to S2, S3 gives ``["S1","S2"], ["S1","S3"]``; a branch stop gives
``[from, "STOP"]``). The CPU's startup (OB100 with INIT_SQ) happens before cycle 0.
``values``: every ``--watch`` name — S7 addresses, symbols, FB pins of the chart's parameter
set, FB variables, ``Sn.X``/``Sn.T``/``Sn.U``, ``Tn.TT``.

Stimulus names: addresses, symbols, FB *input* pins of the parameter set, FB variables.
An input address (I…) is written on the module side (PI), so the CPU reads it at the start
of the cycle. A chart that does not compile, an unknown name or a pin outside the parameter
set: diagnostics on stderr, exit status 2.
"""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path
from typing import Any, TextIO

from engine.address import Address, Area, parse_address
from engine.clock import Clock, VirtualClock
from engine.cpu import Cpu
from engine.errors import AddressError, S7Error
from engine.symbols import SymbolTable, default_type
from sequencer.compile import ChartError, compile_chart
from sequencer.compiled import CompiledChart
from sequencer.fb import GraphFB, install_all
from sequencer.params import Direction, check_pin, is_pin
from sequencer.parse import ChartSyntaxError, parse_chart
from web.plant import LoadedPlant, PlantError, load_plant

_STEP_ATTR = re.compile(r"S(\d+)\.([XTU])", re.I)
_TRANS_ATTR = re.compile(r"T(\d+)\.TT", re.I)


class ChartLoadError(S7Error):
    """A chart (or symbol table) that does not load; ``lines`` are the diagnostics."""

    def __init__(self, lines: list[str]) -> None:
        self.lines = lines
        super().__init__("\n".join(lines))


def load_chart(path: Path, symbols: Path | None = None) -> tuple[CompiledChart, SymbolTable]:
    """Parse, validate and compile a chart file (with an optional symbol table file)."""
    try:
        text = Path(path).read_text(encoding="utf-8")
    except OSError as exc:
        raise ChartLoadError([f"s7graph: error: cannot read {path}: {exc.strerror}"]) from None
    table = SymbolTable()
    try:
        if symbols is not None:
            table = SymbolTable.from_file(symbols)
        chart = parse_chart(text, str(path))
        for s in chart.symbols:
            if table.lookup(s.name) is None:
                table.add(s.name, s.address, s.type, s.comment, where=s.loc)
        cc = compile_chart(chart, table)
    except (ChartSyntaxError, ChartError) as exc:
        raise ChartLoadError([_fmt(d) for d in exc.diagnostics]) from None
    except S7Error as exc:
        raise ChartLoadError([f"{exc}"]) from None
    return cc, table


def fail(error: object, status: int = 2) -> int:
    """Report ``error`` on stderr and return the exit ``status``: a ``ChartLoadError`` as its
    diagnostics, one a line, anything else as one ``s7graph: error:`` line."""
    lines = error.lines if isinstance(error, ChartLoadError) else [f"s7graph: error: {error}"]
    for line in lines:
        print(line, file=sys.stderr)
    return status


def _fmt(d: Any) -> str:
    try:
        from sequencer.diagnostics import Diagnostic, format_diagnostic

        if isinstance(d, Diagnostic):
            return format_diagnostic(d)
    except ImportError:  # pragma: no cover
        pass
    return str(d)


class ChartSession:
    """One CPU running one compiled chart as a GraphFB from OB1 (sim and run)."""

    def __init__(self, cc: CompiledChart, symbols: SymbolTable, clock: Clock) -> None:
        self.cc = cc
        self.symbols = symbols
        self.clock = clock
        self.cpu = Cpu(clock)
        self.cpu.mem.symbols = symbols
        self.graph = GraphFB(cc)
        install_all(self.cpu, [self.graph])

    @classmethod
    def load(cls, path: Path, symbols: Path | None, clock: Clock) -> ChartSession:
        """``load_chart`` (raises ``ChartLoadError``) and a session of it on ``clock``."""
        cc, table = load_chart(path, symbols)
        return cls(cc, table, clock)

    # ------------------------------------------------------------ names

    def _address(self, name: str) -> tuple[Address, str] | None:
        sym = self.symbols.lookup(name)
        if sym is not None:
            return sym.address, sym.type
        try:
            addr = parse_address(name)
        except AddressError:
            return None
        return addr, default_type(addr)

    def check_name(self, name: str, *, writing: bool) -> None:
        """Raise S7Error if ``name`` cannot be set (``writing``) or watched."""
        if _STEP_ATTR.fullmatch(name) or _TRANS_ATTR.fullmatch(name):
            if writing:
                raise S7Error(f"{name} cannot be set")
            return
        if name in self.cc.var_types:
            return
        if is_pin(name):
            check_pin(name, self.cc.parameters,
                      direction=Direction.IN if writing else None)  # fmt: skip
            return
        if self._address(name) is None:
            raise S7Error(f"unknown name {name}: not an address, symbol, FB pin or variable")

    def get(self, name: str) -> Any:
        """The current value of an address, symbol, FB pin, variable or step attribute."""
        st = self.graph.state
        if m := _STEP_ATTR.fullmatch(name):
            i = self.cc.step_index.get(int(m[1]))
            if i is None:
                raise S7Error(f"no step S{m[1]}")
            attr = m[2].upper()
            return st.x[i] if attr == "X" else st.step_t_ms(i) if attr == "T" else st.step_u_ms(i)
        if m := _TRANS_ATTR.fullmatch(name):
            j = self.cc.transition_index.get(int(m[1]))
            if j is None:
                raise S7Error(f"no transition T{m[1]}")
            return st.tt[j]
        if name in self.cc.var_types:
            return _json(st.vars[name])
        if is_pin(name):
            pin = check_pin(name, self.cc.parameters)
            assert self.graph.idb is not None
            return _json(self.graph.idb.values[pin.name])
        found = self._address(name)
        if found is None:
            raise S7Error(f"unknown name {name}")
        addr, type_name = found
        if addr.area in (Area.T, Area.C):
            cells = self.cpu.mem.timers if addr.area is Area.T else self.cpu.mem.counters
            return bool(cells[addr.byte].q)
        return _json(self.cpu.mem.read_as(addr, type_name))

    def set(self, name: str, value: Any) -> None:
        """Write an input: module-side inputs, memory, an FB input pin or an FB variable."""
        if name in self.cc.var_types:
            self.graph.state.vars[name] = value
            return
        if is_pin(name):
            pin = check_pin(name, self.cc.parameters, direction=Direction.IN)
            assert self.graph.idb is not None
            self.graph.idb.values[pin.name] = value
            return
        found = self._address(name)
        if found is None:
            raise S7Error(f"unknown name {name}")
        addr, type_name = found
        mem = self.cpu.mem
        mem.write_as(addr, type_name, value)
        if addr.area is Area.I:  # the module side, read into the PII at the next cycle
            n = addr.byte
            size = max(1, int(addr.width) // 8)
            mem.periph_in[n : n + size] = mem.inputs[n : n + size]

    # ------------------------------------------------------------ running

    def start(self) -> None:
        self.cpu.start("warm")

    def scan(self) -> Any:
        return self.cpu.scan()


def _json(v: Any) -> Any:
    if isinstance(v, (bool, int, float, str)) or v is None:
        return v
    return str(v)


def _read_stimulus(path: Path | None) -> list[tuple[float, dict[str, Any]]]:
    if path is None:
        return []
    out: list[tuple[float, dict[str, Any]]] = []
    for n, line in enumerate(Path(path).read_text(encoding="utf-8").splitlines(), 1):
        if not line.strip():
            continue
        try:
            obj = json.loads(line)
            at = float(obj.get("at_ms", 0))
            values = obj["set"]
            if not isinstance(values, dict):
                raise ValueError("'set' must be an object")
        except (ValueError, KeyError, TypeError, AttributeError) as exc:
            raise S7Error(f"{path}:{n}: bad stimulus line: {exc}") from None
        out.append((at, values))
    out.sort(key=lambda item: item[0])
    return out


def _events(cc: CompiledChart, fired: list[int]) -> list[list[str]]:
    pairs: list[list[str]] = []
    for j in fired:
        for s in cc.tr_src[j]:
            src = cc.step_label(s)
            if cc.tr_dst[j]:
                pairs.extend([src, cc.step_label(d)] for d in cc.tr_dst[j])
            else:
                pairs.append([src, "STOP"])
    return pairs


def _ms(v: float) -> int | float:
    return int(v) if float(v).is_integer() else round(v, 6)


def sim_command(
    chart: Path,
    *,
    stimulus: Path | None = None,
    cycle_ms: float = 10.0,
    cycles: int = 100,
    watch: str = "",
    trace: Path | None = None,
    symbols: Path | None = None,
    plant: Path | None = None,
) -> int:
    """Run ``chart`` for ``cycles`` cycles; return the exit status (SPEC §4)."""
    try:
        session = ChartSession.load(chart, symbols, VirtualClock())
        stim = _read_stimulus(stimulus)
        names = [w.strip() for w in watch.split(",") if w.strip()]
        for name in names:
            session.check_name(name, writing=False)
        for _, values in stim:
            for name in values:
                session.check_name(name, writing=True)
        loaded: LoadedPlant | None = load_plant(plant) if plant is not None else None
    except S7Error as exc:  # ChartLoadError included
        return fail(exc)
    out: TextIO = sys.stdout if trace is None else open(trace, "w", encoding="utf-8")  # noqa: SIM115
    try:
        return _run(session, stim, names, loaded, cycle_ms, cycles, out)
    except PlantError as exc:
        return fail(exc, 1)
    except S7Error as exc:
        return fail(exc)
    finally:
        if out is not sys.stdout:
            out.close()


def _run(
    session: ChartSession,
    stim: list[tuple[float, dict[str, Any]]],
    names: list[str],
    plant: LoadedPlant | None,
    cycle_ms: float,
    cycles: int,
    out: TextIO,
) -> int:
    cc = session.cc
    clock = session.clock
    assert isinstance(clock, VirtualClock)
    session.start()
    nxt = 0
    for k in range(cycles):
        t_ms = k * cycle_ms
        while nxt < len(stim) and stim[nxt][0] <= t_ms + 1e-9:
            for name, value in stim[nxt][1].items():
                session.set(name, value)
            nxt += 1
        record = session.scan()
        st = session.graph.state
        if plant is not None:
            plant.cycle(session, _ms(t_ms), _ms(cycle_ms))
        if record.mode.name != "RUN" and k == 0:
            pass
        line = {
            "cycle": k,
            "t_ms": _ms(t_ms),
            "active": [
                cc.step_label(i) for i in sorted(st.active, key=cc.step_numbers.__getitem__)
            ],
            "events": _events(cc, st.fired),
            "mode": st.mode,
            "values": {name: session.get(name) for name in names},
        }
        out.write(json.dumps(line) + "\n")
        clock.advance(cycle_ms)
    return 0
