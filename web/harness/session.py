"""A chart in a CPU: the harness that ``sim``, ``run`` and the tests share.

:func:`load_chart` parses, validates and compiles a chart file with its symbol table;
:class:`ChartSession` loads the compiled chart as a GraphFB called from OB1 of one CPU and
reads and writes it by name — S7 addresses, symbols, FB pins of the chart's parameter set,
FB variables, step/transition attributes (``Sn.X``, ``Sn.T``, ``Sn.U``, ``Tn.TT``) and DB
variables (``DB10.n``, ``DB3.motor[2].on``: ``web.harness.dbvars``).
"""

from __future__ import annotations

import contextlib
import functools
import re
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any

from s7graph import sfb
from s7graph.engine.address import Address, Area, Width
from s7graph.engine.clock import Clock
from s7graph.engine.cpu import Cpu
from s7graph.engine.errors import S7Error
from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.calls import prepare_calls
from s7graph.sequencer.checks.diagnostics import Diagnostic, format_diagnostic
from s7graph.sequencer.checks.interfaces import ProgramBlocks
from s7graph.sequencer.compile import ChartError, compile_chart
from s7graph.sequencer.compiled import CompiledChart
from s7graph.sequencer.fb import GraphFB, install_all
from s7graph.sequencer.params import Direction, check_pin, is_pin
from s7graph.sequencer.text.model import Chart
from s7graph.sequencer.text.parse import ChartSyntaxError, chart_text, parse_chart
from s7graph.steps.scl.access import parse_name
from s7graph.web.harness.dbvars import DbVariables
from s7graph.web.harness.operands import address_of, stimulus_value, write_operand
from s7graph.web.harness.scl import ChartBlocks, Loadable, SclSources, load_beside
from s7graph.web.harness.scl_reload import reload_sources

__all__ = [
    "ChartLoadError",
    "ChartSession",
    "add_chart_symbols",
    "compile_model",
    "compile_text",
    "load_chart",
]

Interfaces = Callable[[SymbolTable], ProgramBlocks]
"""The program's user blocks, made from a symbol table (``compile_model``)."""

_STEP_ATTR = re.compile(r"S(\d+)\.([XTU])", re.I)
_TRANS_ATTR = re.compile(r"T(\d+)\.TT", re.I)


class ChartLoadError(S7Error):
    """A chart (or symbol table) that does not load; ``lines`` are the diagnostics."""

    def __init__(self, lines: list[str]) -> None:
        self.lines = lines
        super().__init__("\n".join(lines))


def load_chart(
    path: Path,
    symbols: Path | None = None,
    *,
    table: SymbolTable | None = None,
    blocks: Interfaces | None = None,
) -> tuple[CompiledChart, SymbolTable]:
    """Parse, validate and compile a chart file (with an optional symbol table file, or the
    ``table`` read from it already; ``blocks`` as :func:`compile_model`)."""
    try:
        data = Path(path).read_bytes()
    except OSError as exc:
        raise ChartLoadError([f"s7graph: error: cannot read {path}: {exc.strerror}"]) from None
    with _as_load_error(str(path)):
        if table is None:
            table = _symbols(symbols) if symbols is not None else SymbolTable()
        text = chart_text(data, str(path))
    return compile_text(text, str(path), table, blocks=blocks)


def compile_text(
    text: str, file: str, table: SymbolTable | None = None, *, blocks: Interfaces | None = None
) -> tuple[CompiledChart, SymbolTable]:
    """Parse, validate and compile chart ``text`` (named ``file`` in diagnostics) with the
    symbol table ``table``, which gets the chart's own ``SYMBOLS`` added; ``ChartLoadError``
    with every diagnostic when it does not compile."""
    with _as_load_error(file):
        chart = parse_chart(text, file)
    return compile_model(chart, table, blocks=blocks)


def compile_model(
    chart: Chart, table: SymbolTable | None = None, *, blocks: Interfaces | None = None
) -> tuple[CompiledChart, SymbolTable]:
    """Validate and compile a parsed ``chart`` as :func:`compile_text` does. ``blocks``:
    the interfaces of the program's user blocks, made from the symbol table with the
    chart's ``SYMBOLS`` in it (``ChartSession.load`` compiles its S7-SCL sources so): the
    chart reads their FBs' variables by name."""
    table = table if table is not None else SymbolTable()
    with _as_load_error(chart.file):
        add_chart_symbols(chart, table)
    program = blocks(table) if blocks is not None else None
    with _as_load_error(chart.file):
        cc = compile_chart(chart, table, blocks=program)
    return cc, table


def add_chart_symbols(chart: Chart, table: SymbolTable) -> None:
    """Add the chart's ``SYMBOLS`` to ``table``, as the CPU's table holds them when it
    loads the chart: a name the table has keeps its meaning there (the chart resolves its
    own first)."""
    for s in chart.symbols:
        if table.lookup(s.name) is None and table.block(s.name) is None:
            table.add(s.name, s.address, s.type, s.comment, where=s.loc)


@contextlib.contextmanager
def _as_load_error(file: str) -> Iterator[None]:
    """Any problem reading or compiling a chart as one ``ChartLoadError`` with its lines."""
    try:
        yield
    except (ChartSyntaxError, ChartError) as exc:
        raise ChartLoadError([_fmt(d) for d in exc.diagnostics]) from None
    except S7Error as exc:
        raise ChartLoadError([f"{exc}"]) from None
    except RecursionError:
        raise ChartLoadError([f"{file}: the chart nests too deeply to compile"]) from None


def _symbols(path: Path) -> SymbolTable:
    try:
        return SymbolTable.from_file(path)
    except OSError as exc:
        raise S7Error(f"cannot read symbols {path}: {exc.strerror or exc}") from None


def _fmt(d: Any) -> str:
    return format_diagnostic(d) if isinstance(d, Diagnostic) else str(d)


class ChartSession:
    """One CPU running one compiled chart as a GraphFB from OB1 (sim and run); ``beside``:
    more charts called after it from the same OB1 (the jitter benchmark's 200 sequencers),
    their GraphFBs in ``others``; ``blocks``: the programs of blocks its calls reach
    (``--blocks``: compiled S7-SCL sources, ``web.harness.scl``), loaded before its calls
    are prepared — their OBs run too, OB1 after the chart's call."""

    def __init__(
        self,
        cc: CompiledChart,
        symbols: SymbolTable,
        clock: Clock,
        *,
        beside: Sequence[CompiledChart] = (),
        blocks: Sequence[Loadable] = (),
    ) -> None:
        self.clock = clock
        self.cpu = Cpu(clock, keep_outputs_on_hot_restart=True)  # a hot restart resumes the
        self.cpu.mem.symbols = symbols  # sequence: what its actions set stays set
        self.graph = GraphFB(cc)
        self.others = [GraphFB(c) for c in beside]
        install_all(self.cpu, [self.graph, *self.others])
        sfb.install(self.cpu)  # the operating system's blocks, as on S7
        if blocks:
            problems = load_beside(self.cpu, [self.graph, *self.others], blocks)
            if problems:
                raise ChartLoadError(problems)
        self.blocks = list(blocks)
        types = {k: v for b in blocks for k, v in getattr(b, "types", {}).items()}
        self.dbvars = DbVariables(self.cpu, types)
        """The DB variables by name (``DB10.n``, ``"Seq".S_NO``)."""
        self._var_keys: tuple[CompiledChart | None, dict[str, str]] = (None, {})
        self.warnings: list[str] = [w for c in (cc, *beside) for w in c.warnings]
        """The warnings of the charts and of the ``blocks``' sources (``load``), for ``sim``
        and ``run`` to print (as ``check`` does)."""
        self.missing: list[str] = []
        """Calls of blocks this CPU does not have (``sequencer.calls``): they stop it when
        reached; ``sim`` and ``run`` print them as warnings."""
        for c in (cc, *beside):
            plan = prepare_calls(self.cpu, c.chart)
            if plan.problems:
                raise ChartLoadError(list(plan.problems))
            self.missing += plan.missing

    @property
    def cc(self) -> CompiledChart:
        """The chart the GraphFB runs now (an online change swaps it there)."""
        return self.graph.cc

    @property
    def symbols(self) -> SymbolTable:
        """The CPU's symbol table (an online change may bring another)."""
        table = self.cpu.mem.symbols
        assert table is not None  # set by __init__
        return table

    @symbols.setter
    def symbols(self, table: SymbolTable) -> None:
        self.cpu.mem.symbols = table

    @classmethod
    def load(
        cls, path: Path, symbols: Path | None, clock: Clock, *, blocks: Sequence[Path] = ()
    ) -> ChartSession:
        """``load_chart`` (raises ``ChartLoadError``) and a session of it on ``clock``, with
        the S7-SCL sources ``blocks`` its calls reach (``SclLoadError`` when they do not
        compile; their warnings in ``warnings``)."""
        if not blocks:
            cc, table = load_chart(path, symbols)
            return cls(cc, table, clock)
        interfaces = ChartBlocks(blocks)  # the sources see the chart's SYMBOLS too
        cc, table = load_chart(path, symbols, blocks=interfaces)
        sources = interfaces.sources
        assert sources is not None  # the compile called it
        session = cls(cc, table, clock, blocks=[sources])
        session.warnings += sources.warnings
        return session

    # ------------------------------------------------------------ names

    def _own(self, name: str) -> str:
        """``DB1.count`` or ``"Seq_mix".count`` — a variable of the chart in its own
        instance DB, where S7-GRAPH keeps an FB's static variables — as the variable's own
        name (``count``); any other name as it is."""
        if name not in self.cc.var_types and name[:1] != '"':
            key = self._var_named(name)  # S7 names are not case-sensitive
            if key is not None:
                return key
        idb = self.graph.idb
        if idb is None or name[:1] not in ('"', "D", "d"):
            return name
        try:
            parsed = parse_name(name)
        except ValueError:
            return name
        if parsed is None or len(parsed[1]) != 1:
            return name
        db, (var,) = parsed
        if not isinstance(var, str):
            return name
        try:
            number = db if isinstance(db, int) else self.dbvars.number_of(db, name)
        except S7Error:
            return name
        key = self._var_named(var)
        return key if number == idb.number and key is not None else name

    def _var_named(self, name: str) -> str | None:
        """The chart's variable ``name`` as declared, in any case (None: no such variable);
        the names by their folded case kept per compiled chart (a download brings another)."""
        cc = self.cc
        if self._var_keys[0] is not cc:
            self._var_keys = (cc, {v.casefold(): v for v in cc.var_types})
        return self._var_keys[1].get(name.casefold())

    def _address(self, name: str) -> tuple[Address, str] | None:
        return address_of(self.symbols, name)

    def check_name(self, name: str, *, writing: bool) -> None:
        """Raise S7Error if ``name`` cannot be set (``writing``) or watched."""
        name = self._own(name)
        if _STEP_ATTR.fullmatch(name) or _TRANS_ATTR.fullmatch(name):
            if writing:
                raise S7Error(f"{name} cannot be set")
            return
        if name in self.cc.var_types:
            return
        if is_pin(name):
            try:
                check_pin(name, self.cc.parameters, direction=Direction.IN if writing else None)
            except S7Error as exc:
                if self.symbols.lookup(name) is None:
                    raise
                raise S7Error(f'{exc}; the symbol "{name}" is written with its quotes') from None
            return
        if self._address(name) is None:
            unknown = f"unknown name {name}: not an address, symbol, FB pin or variable"
            self.dbvars.check(name, writing=writing, unknown=unknown)

    def get(self, name: str) -> Any:
        """The current value of an address, symbol, FB pin, variable or step attribute."""
        name = self._own(name)
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
        return self._address_reader(name)()

    def reader(self, name: str) -> Callable[[], Any]:
        """A function that gives ``get(name)``, the name resolved now: an address or symbol
        to its address and type, once instead of at every read (the view's watch list, read
        every scan); anything else through ``get``. S7Error for an unknown name. Resolve
        again once the symbol table changes."""
        name = self._own(name)
        if (
            _STEP_ATTR.fullmatch(name)
            or _TRANS_ATTR.fullmatch(name)
            or name in self.cc.var_types
            or is_pin(name)
        ):
            return functools.partial(self.get, name)
        return self._address_reader(name)

    def _address_reader(self, name: str) -> Callable[[], Any]:
        """``reader`` of an address or symbol: a timer or counter's Q, else its value as its
        type (S7Error now for an unknown name or a type that does not fit the address)."""
        found = self._address(name)
        if found is None:
            if self.dbvars.is_db_name(name):
                return self.dbvars.reader(name)
            raise S7Error(f"unknown name {name}")
        addr, type_name = found
        mem = self.cpu.mem
        if addr.area in (Area.T, Area.C):
            mem.read_as(addr, "BOOL")  # a cell beyond the CPU's: S7Error now
            cells = mem.timers if addr.area is Area.T else mem.counters
            n = addr.byte
            return lambda: bool(cells[n].q)
        read_as = mem.read_as
        read_as(addr, type_name)  # a type that does not fit the address: S7Error now
        if addr.width is Width.BIT:  # a bit's type is BOOL: the memory's hot path
            read = mem.read
            return lambda: read(addr)
        return lambda: _json(read_as(addr, type_name))

    def set(self, name: str, value: Any) -> None:
        """Write an input: module-side inputs, memory, an FB input pin or an FB variable —
        a pin or variable in its declared type (S7Error naming it when the value does not
        fit: the chart never sees text where it counts an INT)."""
        name = self._own(name)
        if name in self.cc.var_types:
            self.graph.state.vars[name] = stimulus_value(self.cc.var_types[name], name, value)
            return
        if is_pin(name):
            pin = check_pin(name, self.cc.parameters, direction=Direction.IN)
            assert self.graph.idb is not None
            self.graph.idb.values[pin.name] = stimulus_value(pin.type, pin.name, value)
            return
        found = self._address(name)
        if found is None:
            if self.dbvars.is_db_name(name):
                self.dbvars.writer(name)(value)
                return
            raise S7Error(f"unknown name {name}")
        write_operand(self.cpu.mem, *found, value)

    def reload_blocks(self, new: SclSources) -> list[str]:
        """Download the changed S7-SCL sources ``new`` in place of the session's (between
        two scans: ``web.harness.scl_reload``); the notes of what their DBs did not keep."""
        old = next((b for b in self.blocks if isinstance(b, SclSources)), None)
        notes = reload_sources(self.cpu, [self.graph, *self.others], old, new)
        self.blocks = [new]
        self.dbvars.types = dict(new.types)
        return notes

    # ------------------------------------------------------------ running

    def start(self) -> None:
        self.cpu.start("warm")

    def scan(self) -> Any:
        return self.cpu.scan()


def _json(v: Any) -> Any:
    if isinstance(v, (bool, int, float, str)) or v is None:
        return v
    return str(v)
