"""The live view of a running GraphFB: one :class:`StepStateUpdate` per scan, commands in.

:class:`LiveGraph` reads a ``GraphFB``'s ``GraphState`` after each scan (active steps,
disturbed = interlock error or supervision fault, latched = supervision fault waiting for
its acknowledgement, this scan's step events, the mode, the FB outputs and a few watched
operands) and turns operator :class:`Command` s into one-call edges of the FB.

Commands act like the "Control Sequencer" dialog of S7-GRAPH (the TIA "MOP" command
bits): they come from the operator's debugger, not from the FB's pins, so they act
whatever the chart's parameter set (a MINIMUM FB has no ACK_EF pin, yet can be
acknowledged) and whatever the program wires to the pins. Each is applied at the scan
boundary and acts in the FB's next call as a one-call rising edge (``GraphFB.command``):

- ``ack`` → ACK_EF; refused when no step waits for an acknowledgement;
- ``mode`` → SW_AUTO / SW_MAN / SW_TAP / SW_TOP;
- ``init`` → INIT_SQ; ``off`` → OFF_SQ for one call (the sequencer then stays off);
- ``step_on`` / ``step_off`` → S_ON / S_OFF on ``step`` (not S_NO); refused outside MAN,
  for an unknown step, an active step (on) or an idle one (off);
- ``t_push`` → T_PUSH; refused outside TAP and TOP.

Every command is refused while the CPU is not in RUN, and so is a second mode, step, or
init/off command at the same scan boundary (one call would see both edges at once and
resolve them by priority, not by order). An applied command goes to the audit log (who,
when, what) when a ``StateStore`` is given. :meth:`LiveGraph.apply` never raises: a
hostile command is refused with its reason, the scan loop goes on.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable
from typing import Any

from engine.modes import CpuMode
from engine.persistence import StateStore
from engine.record import ScanRecord
from sequencer.fb import GraphFB, StepEvent
from sequencer.modes import SELECTORS
from web.protocol import EVENTS, MODES, ChartLayout, Command, StepStateUpdate

__all__ = ["CONTROL_SEQUENCER", "MODE_PINS", "OP_PINS", "LiveGraph", "watch_names"]

CONTROL_SEQUENCER = "S7-GRAPH Control Sequencer"
OP_PINS: dict[str, str] = {
    "ack": "ACK_EF",
    "init": "INIT_SQ",
    "off": "OFF_SQ",
    "step_on": "S_ON",
    "step_off": "S_OFF",
    "t_push": "T_PUSH",
}
MODE_PINS: dict[str, str] = {mode: pin for pin, mode in SELECTORS}
MAX_WATCH = 64
# Commands of one group queued at the same scan boundary would act as simultaneous edges
# in one call (the FB resolves them by priority, not by order), so the second is refused.
_GROUPS = {"mode": "mode", "step_on": "step", "step_off": "step", "init": "init", "off": "init"}


def _scalar(value: object) -> bool | int | float | str | None:
    if value is None or isinstance(value, bool | int | float | str):
        return value
    return str(value)


class LiveGraph:
    """One GraphFB seen live: :meth:`update` after each scan, :meth:`apply` at the boundary.

    ``read(name)`` gives the value of a watched operand (``ChartSession.get``); ``store``
    receives the audit log; ``wall_ns`` stamps it (the wall clock: an audit says *when*)."""

    def __init__(
        self,
        graph: GraphFB,
        *,
        fb: str | None = None,
        read: Callable[[str], object] | None = None,
        watch: Iterable[str] = (),
        store: StateStore | None = None,
        wall_ns: Callable[[], int] = time.time_ns,
    ) -> None:
        self.graph = graph
        self.cc = graph.cc
        self.fb = fb or graph.cc.name
        self.layout = ChartLayout.from_chart(graph.cc.chart, fb=self.fb)
        self._read = read
        self.watch = tuple(dict.fromkeys(watch))[:MAX_WATCH]
        self.store = store
        self._wall_ns = wall_ns
        self.cpu_mode = CpuMode.STOP
        self.cycle = 0
        self._pending_mode: str | None = None  # a mode change queued for the next call
        self._pending: dict[str, str] = {}  # conflict group -> op queued for the next call

    # ------------------------------------------------------------ state out

    def update(self, record: ScanRecord) -> StepStateUpdate:
        """The FB's state after the scan ``record`` (call once per scan, in the scan thread)."""
        self.cpu_mode = record.mode
        self.cycle = record.cycle
        self._pending_mode = None  # the commands queued before this scan have acted
        self._pending.clear()
        st = self.graph.state
        numbers = self.cc.step_numbers
        active = sorted(numbers[i] for i in st.active)
        disturbed = sorted(numbers[i] for i in st.active if st.il_err[i] or st.sv_err[i])
        latched = sorted(numbers[i] for i in st.active if st.sv_err[i]) if st.ackreq_enabled else []
        db = self.graph.db_number
        events = [
            (e.event, e.step)
            for e in record.events
            if isinstance(e, StepEvent) and e.db == db and e.event in EVENTS
        ]
        mode = st.mode if st.mode in MODES else "AUTO"
        return StepStateUpdate(
            cycle=max(record.cycle, 0),
            t_ms=max(record.t_ns // 1_000_000, 0),
            mode=mode,  # type: ignore[arg-type]
            active=active,
            disturbed=disturbed,
            latched=latched,
            events=events,  # type: ignore[arg-type]
            values=self.values(),
        )

    def values(self) -> dict[str, bool | int | float | str | None]:
        """The FB outputs, then the watched operands (an unreadable one is left out)."""
        out = {name: _scalar(v) for name, v in self.graph.outputs.items()}
        if self._read is not None:
            for name in self.watch:
                try:
                    out[name] = _scalar(self._read(name))
                except Exception:  # a watch must never stop the scan
                    continue
        return out

    # ------------------------------------------------------------ commands in

    def apply(self, command: Command) -> tuple[bool, str]:
        """Queue ``command`` as a one-call edge of the next FB call; (applied, reason).

        Never raises: anything unexpected refuses the command with the reason."""
        try:
            applied, reason, detail = self._check(command)
            if applied:
                self._audit(command, detail)
            return applied, reason
        except Exception as exc:
            return False, f"command refused: {type(exc).__name__}: {exc}"[:4096]

    def _check(self, command: Command) -> tuple[bool, str, str]:
        op = getattr(command, "op", None)
        if self.cpu_mode is not CpuMode.RUN:
            return False, f"the CPU is in {self.cpu_mode}, not RUN", ""
        group = _GROUPS.get(op) if isinstance(op, str) else None
        queued = self._pending.get(group) if group else None
        if queued is not None:
            return False, f"{op} conflicts with {queued}, queued for the same scan; retry", ""
        applied, reason, detail = self._queue(command, op)
        if applied and group:
            self._pending[group] = f"{op} {detail}".strip()
        return applied, reason, detail

    def _queue(self, command: Command, op: object) -> tuple[bool, str, str]:
        st = self.graph.state
        mode = self._pending_mode or st.mode
        cc = self.cc
        if op == "mode":
            new = command.mode
            if new not in MODE_PINS:
                return False, f"mode must be one of {', '.join(MODES)}", ""
            self.graph.command(MODE_PINS[new])
            self._pending_mode = new
            return True, "", f"{mode} -> {new}"
        if op == "ack":
            waiting = [cc.step_numbers[i] for i in st.active if st.sv_err[i]]
            if not waiting:
                return False, "no supervision fault waits for an acknowledgement", ""
            self.graph.command(OP_PINS[op])
            return True, "", "steps " + ", ".join(f"S{n}" for n in sorted(waiting))
        if op in ("init", "off"):
            self.graph.command(OP_PINS[op])
            return True, "", ""
        if op == "t_push":
            if mode not in ("TAP", "TOP"):
                return False, f"t_push needs mode TAP or TOP ({CONTROL_SEQUENCER})", ""
            self.graph.command(OP_PINS[op])
            return True, "", ""
        if op in ("step_on", "step_off"):
            step = command.step
            if mode != "MAN":
                return False, f"{op} needs mode MAN ({CONTROL_SEQUENCER})", ""
            i = cc.step_index.get(step) if isinstance(step, int) else None
            if i is None:
                return False, f"no step S{step} in {self.fb}", ""
            if op == "step_on" and st.x[i]:
                return False, f"S{step} is already active", ""
            if op == "step_off" and not st.x[i]:
                return False, f"S{step} is not active", ""
            self.graph.command(OP_PINS[op], step=step)
            return True, "", f"S{step}"
        return False, f"unknown command {op!r}", ""

    def _audit(self, command: Command, detail: str) -> None:
        if self.store is None:
            return
        what = f"FB {self.fb} cycle {self.cycle}" + (f": {detail}" if detail else "")
        self.store.log_audit(self._wall_ns(), command.user or "?", command.op, what)


def watch_names(symbols: Iterable[Any], limit: int = 16) -> list[str]:
    """A few operands worth watching: the symbols on inputs and outputs (I/Q), in order."""
    names = [sym.name for sym in symbols if str(sym.address.area) in ("I", "Q")]
    return names[:limit]
