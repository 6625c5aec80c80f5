"""A small driver for scenario tests: one GRAPH FB through the real cycle
(``sequencer.cycle.GraphRuntime``) on an engine ``Memory``, paced by a ``VirtualClock``.

FB input pins are held like the ``sim`` stimuli (SPEC §4): a value stays until set again.
After every call the driver runs ``sequencer.messages.sync_messages`` into its own
``MessageList`` — the integration the FB is meant to do (see messages.py).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from engine.clock import VirtualClock
from engine.memory import Memory
from engine.symbols import SymbolTable
from sequencer.compile import compile_chart
from sequencer.compiled import CompiledChart
from sequencer.cycle import GraphRuntime
from sequencer.messages import sync_messages
from sequencer.params import Direction, check_pin, is_pin
from sequencer.parse import parse_chart
from sequencer.state import EVENT_BITS, GraphState
from sfb import s5_counters, s5_timers
from sfb.alarms import MessageList

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[2]


def chart_text(name: str) -> tuple[str, str]:
    """The text and file name of ``tests/sequencer/scenarios/<name>.s7g``."""
    path = HERE / f"{name}.s7g"
    return path.read_text(encoding="utf-8"), str(path)


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
        cell = s5_counters.cell_of(self.mem.counters, number)
        if op == "CS":
            cell.s_edge = False
            s5_counters.set_preset(cell, True, int(value))
        elif op == "CU":
            cell.cu_edge = False
            s5_counters.count_up(cell, True)
        elif op == "CD":
            cell.cd_edge = False
            s5_counters.count_down(cell, True)
        else:
            s5_counters.reset(cell, True)

    def _timer(self, op: str, number: int, value: Any) -> None:
        cell = s5_timers.cell_of(self.mem.timers, number)
        if op == "TR":
            s5_timers.reset(cell)
            return
        fn = {"TL": "SE", "TD": "SS", "TF": "SF"}[op]
        cell.s_edge = False
        s5_timers.run(cell, fn, True, int(value), self.clock.now_ns())
