"""The shared drivers of the sequencer tests, imported as ``tests.sequencer.helpers``.

- ``Chart``: a chart from source text, called directly through ``GraphRuntime`` (no CPU,
  no S5 cells, no message list), 10 ms per call; ``active`` gives step labels.
- ``Run``: one GRAPH FB through the real cycle (``sequencer.cycle.GraphRuntime``) on an
  engine ``Memory``, paced by a ``VirtualClock``. FB input pins are held like the ``sim``
  stimuli (docs/cli.md, "s7graph sim"): a value stays until set again. After every call the driver
  runs
  ``sequencer.messages.sync_messages`` into its own ``MessageList`` — the integration the
  FB is meant to do (see messages.py). ``Run.scenario(name)`` loads
  ``tests/sequencer/scenarios/<name>.s7g``.
- ``source``/``seq``/``chart``/``two_steps``/``enter``/``leave``: the chart builders of the
  Conformance tests (``tests/sequencer/test_spec_*.py``), driven with ``Run``.
- ``write_sim_inputs``/``read_trace``: the files of one ``s7graph sim`` run (docs/cli.md, "s7graph
sim");
  ``sim_trace`` runs one and returns its exit status and trace.
- ``SCENARIOS``, ``CHARTS``, ``BROKEN``: the data folders beside this module, named here for
  the tests in the sub-folders (``text/``, ``checks/``, ``change/``) and elsewhere
  (``tests/web/cli/``), so that no test finds them relative to its own place.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from s7graph.engine.clock import VirtualClock
from s7graph.engine.memory import Memory
from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.compile import compile_chart
from s7graph.sequencer.compiled import CompiledChart
from s7graph.sequencer.cycle import GraphRuntime
from s7graph.sequencer.fb import counter_row, timer_row
from s7graph.sequencer.messages import sync_messages
from s7graph.sequencer.params import Direction, check_pin, is_pin
from s7graph.sequencer.state import GraphState
from s7graph.sequencer.text.parse import parse_chart
from s7graph.sfb.alarms import MessageList
from s7graph.steps.qualifiers import EVENT_BITS
from s7graph.web.cli.sim import sim_command

HERE = Path(__file__).resolve().parent
SCENARIOS = HERE / "scenarios"
CHARTS = HERE / "charts"  # valid charts of the parser, validator and editor tests
BROKEN = HERE / "broken"  # one broken chart per diagnostic, its expectation in its first line


# ---------------------------------------------------------------- chart source text


def source(sequences: str, *, header: str = "", params: str = "MAXIMUM", name: str = "Spec") -> str:
    """A ``FUNCTION_BLOCK "<name>"`` around ``sequences`` with ``PARAMETERS := params``."""
    return (
        f'FUNCTION_BLOCK "{name}"\n  PARAMETERS := {params};\n{header}\n{sequences}\n'
        "END_FUNCTION_BLOCK\n"
    )


def seq(body: str, number: int = 1) -> str:
    return f'SEQUENCE {number} "s{number}"\n{body}\nEND_SEQUENCE\n'


def chart_text(name: str) -> tuple[str, str]:
    """The text and file name of ``tests/sequencer/scenarios/<name>.s7g``."""
    path = SCENARIOS / f"{name}.s7g"
    return path.read_text(encoding="utf-8"), str(path)


# ---------------------------------------------------------------- Chart: the bare cycle


class Chart:
    """A chart from source text, called directly (no CPU), 10 ms per call."""

    def __init__(self, sequences: str, *, header: str = "", params: str = "MAXIMUM") -> None:
        text = source(sequences, header=header, params=params, name="T")
        self.cc = compile_chart(parse_chart(text, "t.s7g"))
        self.mem = Memory()
        self.clock = VirtualClock()
        self.rt = GraphRuntime(self.cc, self.cc.bind(self.mem))
        self.pins: dict[str, Any] = {}

    def set(self, **values: Any) -> None:
        for name, v in values.items():
            if is_pin(name):
                self.pins[name] = v
            else:
                self.mem.set(name.replace("_", "."), v)

    def call(self, n: int = 1, ms: int = 10) -> None:
        for _ in range(n):
            self.rt.execute(self.pins, self.clock.now_ns())
            self.clock.advance(ms)

    @property
    def active(self) -> list[str]:
        st = self.rt.st
        return [
            self.cc.step_label(i) for i in sorted(st.active, key=self.cc.step_numbers.__getitem__)
        ]

    @property
    def fired(self) -> list[str]:
        return [self.cc.transition_label(j) for j in self.rt.st.fired]

    def q(self, addr: str) -> bool:
        return bool(self.mem.get(addr))


# ---------------------------------------------------------------- Run: FB + messages + S5 cells
class Run:
    """One FB, its memory, its clock and its message list."""

    def __init__(
        self,
        source: str,
        *,
        file: str = "<scenario>",
        symbols: SymbolTable | None = None,
        cycle_ms: int = 10,
        db_number: int | None = None,
    ) -> None:
        self.cc: CompiledChart = compile_chart(parse_chart(source, file), symbols)
        self.symbols = symbols
        self.mem = Memory()
        self.clock = VirtualClock()
        self.cycle_ms = cycle_ms
        self.db_number = db_number or self.cc.chart.db_number or 1
        self.messages = MessageList()
        self.remote_acks: list[int] = []
        self.pins: dict[str, Any] = {}
        self.wires: dict[str, str] = {}
        self.rt = GraphRuntime(
            self.cc, self.cc.bind(self.mem), counter=self._counter, timer=self._timer
        )

    @classmethod
    def scenario(cls, name: str, **kw: Any) -> Run:
        text, file = chart_text(name)
        return cls(text, file=file, **kw)

    # ------------------------------------------------------------ stimuli and calls

    @property
    def st(self) -> GraphState:
        return self.rt.st

    def set(self, **values: Any) -> Run:
        """Hold FB input pins (``SW_TAP=True``) and memory operands (``I0_7=True`` for
        ``I0.7``: underscores stand for the dot)."""
        for name, value in values.items():
            if is_pin(name):
                check_pin(name, self.cc.parameters, "scenario", direction=Direction.IN)
                self.pins[name.upper()] = value
            else:
                self.mem.set(self._address(name), value)
        return self

    def wire(self, **pins: str) -> Run:
        """Connect FB input pins to operands, as ``CALL FB 1, DB 1 (SW_TAP := M0.0)`` does:
        before each call the pin reads the operand."""
        for name, operand in pins.items():
            check_pin(name, self.cc.parameters, "scenario", direction=Direction.IN)
            self.wires[name.upper()] = self._address(operand)
        return self

    def call(self, n: int = 1) -> GraphState:
        """``n`` FB calls, the clock advancing ``cycle_ms`` after each."""
        for _ in range(n):
            for name, address in self.wires.items():
                self.pins[name] = self.mem.get(address)
            if self.remote_acks:
                self.rt.acknowledge(self.remote_acks)
            self.rt.execute(dict(self.pins), self.clock.now_ns())
            self.remote_acks = sync_messages(
                self.cc, self.st, self.messages, self.cc.name, self.db_number, self.clock.now_ns()
            )
            self.clock.advance(ms=self.cycle_ms)
        return self.st

    def pulse(self, pin: str, **also: Any) -> GraphState:
        """One call with ``pin`` = 1 (a rising edge), then one with 0."""
        self.set(**{pin: True}, **also)
        self.call()
        self.set(**{pin: False})
        return self.call()

    def wait_ms(self, ms: int) -> GraphState:
        return self.call(max(1, ms // self.cycle_ms))

    # ------------------------------------------------------------ observations

    @property
    def active(self) -> list[int]:
        st = self.st
        return sorted(self.cc.step_numbers[i] for i in range(st.n_steps) if st.x[i])

    def out(self, pin: str) -> Any:
        return self.st.outputs[pin]

    def get(self, name: str) -> Any:
        return self.mem.get(self._address(name))

    def idx(self, step: int) -> int:
        return self.cc.step_index[step]

    def events(self, step: int) -> set[str]:
        """The events of ``step`` in the last call."""
        bits = self.st.ev[self.idx(step)]
        return {name for name, bit in EVENT_BITS.items() if bits & bit}

    def _address(self, name: str) -> str:
        if self.symbols is not None and self.symbols.lookup(name) is not None:
            return str(self.symbols.resolve(name))
        for sym in self.cc.chart.symbols:
            if sym.name.upper() == name.upper():
                return sym.address
        return name.replace("_", ".")

    # ------------------------------------------------------------ S5 cells for CS/TL rows

    def _counter(self, op: str, number: int, value: Any) -> None:
        counter_row(self.mem.counters, op, number, value)

    def _timer(self, op: str, number: int, value: Any) -> None:
        timer_row(self.mem.timers, op, number, value, self.clock.now_ns())


# ---------------------------------------------------------------- Conformance builders


def chart(sequences: str, *, header: str = "", params: str = "MAXIMUM") -> Run:
    return Run(source(sequences, header=header, params=params), file="spec.s7g")


def chart_on_path(sequences: str, fast: bool) -> Run:
    """:func:`chart` whose cycle takes the fast path (``fast``) where it may, or always the
    general one: a rule pinned on both."""
    run = chart(sequences)
    run.rt = GraphRuntime(
        run.cc, run.cc.bind(run.mem), counter=run._counter, timer=run._timer, fast=fast
    )
    return run


def two_steps(rows: str, *, header: str = "", interlock: str = "", params: str = "MAXIMUM") -> Run:
    """S1 (initial) -T1 I0.0-> S2 (``rows``) -T2 I0.1-> S3 -T3 I0.2-> S1."""
    il = f"INTERLOCK := {interlock};" if interlock else ""
    return chart(
        seq(f"""
      INITIAL_STEP S1 "a": END_STEP
      STEP S2 "b": {il} {rows} END_STEP
      STEP S3 "c": END_STEP
      TRANSITION T1 FROM S1 TO S2 := I0.0;
      TRANSITION T2 FROM S2 TO S3 := I0.1;
      TRANSITION T3 FROM S3 TO S1 := I0.2;
    """),
        header=header,
        params=params,
    )


def enter(run: Run) -> None:
    """First call (S1), then a call that switches T1 into S2; I0.0 is released again."""
    run.call()
    run.set(I0_0=True).call()
    run.set(I0_0=False)
    assert run.active == [2]


def leave(run: Run) -> None:
    """One call that switches T2 out of S2 into S3."""
    run.set(I0_1=True).call()
    run.set(I0_1=False)
    assert run.active == [3]


# ---------------------------------------------------------------- ``s7graph sim`` files


def write_sim_inputs(tmp_path: Path, chart: str, stim: list[dict]) -> tuple[Path, Path, Path]:
    """``c.s7g`` and ``s.jsonl`` (one stimulus a line) in ``tmp_path``; returns their paths
    and the path of the trace ``out.jsonl``."""
    (tmp_path / "c.s7g").write_text(chart, encoding="utf-8")
    (tmp_path / "s.jsonl").write_text("".join(json.dumps(s) + "\n" for s in stim))
    return tmp_path / "c.s7g", tmp_path / "s.jsonl", tmp_path / "out.jsonl"


def read_trace(out: Path) -> list[dict]:
    """The trace lines of a sim run; none if the run wrote no trace."""
    return [json.loads(x) for x in out.read_text().splitlines()] if out.exists() else []


def sim_trace(
    tmp_path: Path,
    chart: str,
    stim: list[dict],
    *,
    cycles: int,
    watch: str = "",
    cycle_ms: float = 10,
) -> tuple[int, list[dict]]:
    """One ``s7graph sim`` run of ``chart`` with the stimuli ``stim``: (exit status, trace)."""
    c, s, out = write_sim_inputs(tmp_path, chart, stim)
    rc = sim_command(c, stimulus=s, cycle_ms=cycle_ms, cycles=cycles, watch=watch, trace=out)
    return rc, read_trace(out)
