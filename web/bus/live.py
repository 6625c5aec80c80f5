"""The live view of a running GraphFB: one :class:`StepStateUpdate` per scan, commands in.

:class:`LiveGraph` reads a ``GraphFB``'s ``GraphState`` after each scan (active steps,
disturbed = interlock error or supervision fault, latched = supervision fault waiting for
its acknowledgement, this scan's step events, the mode, the FB outputs, a few watched
operands and those the permanent instructions write) and turns operator :class:`Command` s
into one-call edges of the FB.

Commands act like the "Control Sequencer" dialog of S7-GRAPH (the TIA "MOP" command
bits): they come from the operator's debugger, not from the FB's pins, so they act
whatever the chart's parameter set (a MINIMUM FB has no ACK_EF pin, yet can be
acknowledged) and whatever the program wires to the pins. Each is applied at the scan
boundary and acts in the FB's next call as a one-call rising edge (``GraphFB.command``),
queued meanwhile in the FB's instance DB (``GraphState.to_command``): committed with the
boundary and its audit row, it outlives a kill before that call (a warm or hot restart
carries it out in its first call):

- ``ack`` → ACK_EF; refused when no step waits for an acknowledgement, or when each
  waiting fault's cause persists and the acknowledgement would not let its step switch
  (the fault would latch again in the same call, its message stay unacknowledged): the
  reason says so; steps that stay latched beside released ones are named in the reply;
- ``ack_step`` → ACK_S on ``step`` (not S_NO); refused unless that step waits, and, as
  ``ack``, when its cause persists;
- ``mode`` → SW_AUTO / SW_MAN / SW_TAP / SW_TOP;
- ``init`` → INIT_SQ; ``off`` → OFF_SQ for one call (the sequencer then stays off);
- ``halt`` → HALT_SQ held on (``{"on": true}``) or left to the pin again (``false``);
  ``en_il`` / ``en_sv`` with ``{"on": false}`` hold EN_IL / EN_SV off (interlocks or
  supervisions disabled), ``true`` leaves them to the pin again; these overrides live in
  the FB's instance DB (``GraphState.levels``): a warm or hot restart keeps them, a cold
  restart clears them, and each update shows them (``overrides``);
- ``step_on`` / ``step_off`` → S_ON / S_OFF on ``step`` (not S_NO); refused outside MAN,
  for an unknown step, an active step (on) or an idle one (off);
- ``t_push`` → T_PUSH; refused outside TAP and TOP; in TAP with no satisfied transition
  applied with a reason saying the push switches nothing unless one is satisfied;
- ``ack_msg`` → acknowledges one message of the CPU's message list as the command's user
  at once (``MessageList.acknowledge``); refused for an unknown or already acknowledged
  message and for the user name ``program`` (reserved for ACK_EF). A supervision message
  acknowledged while its fault is latched releases the step at the FB's next call as ACK_S
  would, whether or not its cause has gone (``sequencer.messages.remote_acks``); if it
  has not, the reply says the fault comes again as a new message.

Messages a command acknowledges (``ack``, ``ack_step``, ``init``) are acknowledged as the
command's user, never as ``program``.

Each update also carries a :class:`StepDetail` per active step (times to 0.1 s, interlock
and supervision contacts, the contacts of its valid transitions: the CRIT bits; built
only for the steps whose state changed, ``web.bus.step_details``), and
:meth:`LiveGraph.alarms_changed` gives the message list whenever it changed. The events
of a scan are grouped by instance DB once per scan record, for every LiveGraph of the CPU
(``web.bus.scan_events``).

:meth:`LiveGraph.changed` is the scan thread's cheap path: it builds the update only when
the FB may have changed, judged from what the FB itself says — its step events in the
scan record (every switch, disturbance and acknowledgement raises one), its mode and level
pins, its output pins, the watched operands, its transitions' CRIT words, the TT bits of
the transitions leaving its active steps (and interlock and supervision words), and the
clock time at which the first active step's T
or U reaches its next whole second (:class:`Seen`) — instead of building the whole state
and comparing it (``StepStateUpdate.changed_from``, which the bus publisher still does
for what ``changed`` builds).

Each op the FB carries out has one handler, found by the op's struct (:data:`HANDLERS`; a
test checks that every such op of ``web.commands`` has one). Every command is refused
while the CPU is not in RUN, and so is a second mode, step, or init/off command at the
same scan boundary (one call would see both edges at once and resolve them by priority,
not by order). Who may send what, and the audit, are the bus
gate's (``web.bus.gate``): :meth:`LiveGraph.apply` sees commands already checked, under
the established user's name, and returns ``(applied, reason, detail)``. It never raises: a
hostile command is refused with its reason, the scan loop goes on.
"""

from __future__ import annotations

import functools
import operator
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any, Final

from s7graph.engine.errors import internal_error
from s7graph.engine.modes import CpuMode
from s7graph.engine.record import ScanRecord
from s7graph.sequencer.compiled import CompiledChart
from s7graph.sequencer.fb import GraphFB
from s7graph.sequencer.messages import parse_message_id
from s7graph.sequencer.modes import SELECTORS
from s7graph.sequencer.placing import moves
from s7graph.sfb.alarms import MessageList
from s7graph.steps.conditions import contact_negations
from s7graph.web.bus.alarm_feed import AlarmFeed
from s7graph.web.bus.protocol import (
    MODES,
    AlarmList,
    ChartLayout,
    Command,
    Refusal,
    StepDetail,
    StepStateUpdate,
)
from s7graph.web.bus.scan_events import ScanEvents
from s7graph.web.bus.seen import Leaving, Seen, due_ns, same, seen
from s7graph.web.bus.step_details import StepDetails
from s7graph.web.commands import (
    COMMAND_TYPES,
    Ack,
    AckMsg,
    AckStep,
    EnIl,
    EnSv,
    Halt,
    Init,
    Off,
    SetMode,
    SetSteps,
    StepOff,
    StepOn,
    TPush,
    op_of,
)

__all__ = [
    "CONTROL_SEQUENCER",
    "HANDLERS",
    "MODE_PINS",
    "OP_PINS",
    "LiveChart",
    "LiveGraph",
    "prepare_chart",
    "watch_names",
]

CONTROL_SEQUENCER = "S7-GRAPH Control Sequencer"
# The pins the commands act as, read from the command vocabulary (web.commands): an edge
# op's pin; a level op's pin, and the value a command holds it at (the other value frees it).
OP_PINS: dict[str, str] = {op_of(c): c.pin for c in COMMAND_TYPES if c.kind == "edge"}
MODE_PINS: dict[str, str] = {mode: pin for pin, mode in SELECTORS}
LEVEL_PINS: dict[str, tuple[str, bool]] = {
    op_of(c): (c.pin, c.held) for c in COMMAND_TYPES if c.kind == "level"
}
MAX_WATCH = 64
WASTED = 4  # copies in a row that found the FB changed, after which none is kept ...
PROBE = 8  # ... but every PROBE-th scan's (``LiveGraph.changed``)
MAX_VALUES = 512  # outputs, watched operands and the active steps' action operands
# Commands of one group queued at the same scan boundary would act as simultaneous edges
# in one call (the FB resolves them by priority, not by order), so the second is refused.
_GROUPS = {op_of(c): c.group for c in COMMAND_TYPES if c.group}
Result = tuple[bool, str, str]
"""Applied, the reason (a refusal's a :class:`Refusal`, naming its kind), what it acted on
(for the audit)."""


@dataclass(frozen=True, slots=True)
class LiveChart:
    """One chart version as :class:`LiveGraph` describes it (``LiveGraph.prepare``)."""

    cc: CompiledChart
    layout: ChartLayout
    tr_neg: tuple[tuple[bool, ...], ...]
    il_neg: tuple[tuple[bool, ...], ...]
    sv_neg: tuple[tuple[bool, ...], ...]
    # per step index: the operands of its action rows, whose values go out while it is active
    operands: tuple[tuple[str, ...], ...] = ()
    # the operands the permanent instructions write and their coils' contacts read, whose
    # values go out every scan
    permanent: tuple[str, ...] = ()
    checks: bool = True
    """Whether a step has an interlock or a supervision (their words are watched)."""

    def step_details(self) -> StepDetails:
        """A fresh builder of this chart's step details."""
        return StepDetails(self.cc, self.tr_neg, self.il_neg, self.sv_neg, checks=self.checks)


def prepare_chart(cc: CompiledChart, *, fb: str, version: int) -> LiveChart:
    """What a view of FB ``fb`` needs of chart ``cc`` (its layout, which contacts are
    negated); made off the scan thread before an online change (``web.bus.compiler``
    makes it in the compiler's process)."""
    chart = cc.chart
    layout = ChartLayout.from_chart(chart, fb=fb, version=version)
    rows = {s.number: s.actions for s in layout.steps}
    return LiveChart(
        cc=cc,
        layout=layout,
        tr_neg=tuple(
            _negations(t.condition, n)
            for t, n in zip(chart.all_transitions(), cc.crit_labels, strict=True)
        ),
        il_neg=tuple(
            _negations(st.interlock, n)
            for st, n in zip(chart.all_steps(), cc.il_labels, strict=True)
        ),
        sv_neg=tuple(
            _negations(st.supervision, n)
            for st, n in zip(chart.all_steps(), cc.sv_labels, strict=True)
        ),
        operands=tuple(
            tuple(dict.fromkeys(a.watch for a in rows.get(n, ()) if a.watch))
            for n in cc.step_numbers
        ),
        permanent=tuple(
            dict.fromkeys(
                [p.watch for p in layout.permanent if p.watch]
                + [c.watch for p in layout.permanent for c in p.contacts if c.watch]
            )
        ),
        checks=any(
            st.interlock is not None or st.supervision is not None for st in chart.all_steps()
        ),
    )


_PLAIN = frozenset({bool, int, float, str, type(None)})
# Shared by every update that has none (messages are never changed, so they may share)
_NONE: list[int] = []
_NO_LEVELS: dict[str, bool] = {}


def _scalar(value: object) -> bool | int | float | str | None:
    if value is None or isinstance(value, bool | int | float | str):
        return value
    return str(value)


_Readers = tuple[tuple[str, Callable[[], object]], ...]


class LiveGraph:
    """One GraphFB seen live: :meth:`update` after each scan, :meth:`apply` at the boundary.

    ``read(name)`` gives the value of a watched operand (``ChartSession.get``), or
    ``reader(name)`` a function that gives it, the name resolved once
    (``ChartSession.reader``; resolved again after an online change, :meth:`switch`);
    ``wall_ns`` turns CPU times into wall-clock times for the alarm list;
    ``messages`` is the CPU's message list (``sfb.alarms.message_list(cpu)``) for
    ``ack_msg`` and :meth:`alarms_changed`; ``events`` groups each scan's events by
    instance DB — give every LiveGraph of a CPU the same one."""

    def __init__(
        self,
        graph: GraphFB,
        *,
        fb: str | None = None,
        read: Callable[[str], object] | None = None,
        reader: Callable[[str], Callable[[], object]] | None = None,
        watch: Iterable[str] = (),
        wall_ns: Callable[[], int] = time.time_ns,
        messages: MessageList | None = None,
        events: ScanEvents | None = None,
    ) -> None:
        self.graph = graph
        self.messages = messages
        self.events = events if events is not None else ScanEvents()
        self.fb = fb or graph.cc.name
        self._read = read
        self._reader = reader
        self.switch(self.prepare(graph.cc, version=1))
        self.watch = tuple(dict.fromkeys(watch))[:MAX_WATCH]
        self._alarms = AlarmFeed(messages, wall_ns=wall_ns) if messages is not None else None
        self.cpu_mode = CpuMode.STOP
        self.cycle = 0
        self._pending_mode: str | None = None  # a mode change queued for the next call
        self._pending: dict[str, str] = {}  # conflict group -> op queued for the next call
        self._t_ns = 0  # CPU time of the last scan
        self._pins: tuple[str, ...] | None = None  # the output pins _pick reads
        self._pick: Callable[[Any], tuple[Any, ...]] | None = None
        self._made: tuple[Any, Any, dict[str, Any]] | None = None  # outs, watched → values
        self._busy = False  # the last scan had events of this FB
        self._wasted = 0  # copies in a row that found the FB changed (``changed``)
        self._skipped = 0  # copies not kept since the last one (``changed``)
        self.copies = 0
        """Copies of what an update saw kept for :meth:`changed` (``Seen``)."""
        self.quiet = 0
        """Scans :meth:`changed` found nothing in (no update built)."""

    # ------------------------------------------------------------ the chart

    def prepare(self, cc: CompiledChart, *, version: int) -> LiveChart:
        """What this view of the FB needs of chart ``cc`` (:func:`prepare_chart`)."""
        return prepare_chart(cc, fb=self.fb, version=version)

    def switch(self, chart: LiveChart) -> None:
        """Describe ``chart`` from now on (at the scan boundary of an online change)."""
        self._chart = chart
        self.step_details = chart.step_details()
        self._seen: Seen | None = None  # what the last update saw (``changed``)
        self._leaving = Leaving(chart.cc.leaving)
        self._due: int | None = None  # and when a step time may reach a new second
        self._readers: tuple[tuple[str, ...], _Readers] | None = None
        """The watch list the readers were made for, and a reader per name."""
        self._step_readers: dict[int, _Readers] = {}
        """Per step index: a reader per operand of its action rows (made when first active)."""
        readable = self._reader is not None or self._read is not None
        self._operands = bool(chart.operands) and readable
        """Whether the active steps' action operands are read (they have some, and there
        is a way to read them)."""
        self._permanent: _Readers | None = None if chart.permanent and readable else ()
        """A reader per operand the permanent instructions write (made at the first read;
        empty: none, or no way to read them)."""

    @property
    def cc(self) -> CompiledChart:
        """The chart the FB runs (never a copy: read from the GraphFB)."""
        return self.graph.cc

    @property
    def layout(self) -> ChartLayout:
        """The layout of the chart described now."""
        return self._chart.layout

    def _follow(self) -> None:
        """The FB runs another chart than the one described (swapped without
        :meth:`switch`): describe it, as the next layout version."""
        self.switch(self.prepare(self.graph.cc, version=self._chart.layout.version + 1))

    # ------------------------------------------------------------ state out

    def changed(self, record: ScanRecord) -> StepStateUpdate | None:
        """:meth:`update` if the FB may have changed since the last update this built, else
        None (nothing a view sees differs: ``web.bus.seen``). Call once per scan, in the
        scan thread, instead of :meth:`update`. A copy (``Seen``) is kept only while it pays:
        not for an FB with events in this scan and the last, nor — but every
        ``PROBE``-th scan — for one whose last ``WASTED`` copies all found it changed."""
        graph = self.graph
        events = self.events.of(record, graph.db_number)
        busy, self._busy = self._busy, bool(events)
        last = self._seen
        if events or last is None or self._chart.cc is not graph.cc:
            if last is not None:
                self._wasted += 1
            return self._update(record, events, see=self._see(bool(events and busy)))
        due = self._due
        if due is None:
            due = self._due = due_ns(last)
        outs = self._outs()
        if not same(last, graph.state, due) or outs != last.outs:
            self._wasted += 1
            return self._update(record, events, see=self._see(False), outs=outs)
        if self.watch or self._operands or self._permanent != ():
            watched = self._watched()
            if watched != last.watched:
                self._wasted += 1
                see = self._see(False)
                return self._update(record, events, see=see, outs=outs, watched=watched)
        self._scan(record)
        self._wasted = 0
        self.quiet += 1
        return None

    def _see(self, busy: bool) -> bool:
        """Whether the update :meth:`changed` builds keeps its copy (see there)."""
        if busy:
            return False
        if self._wasted < WASTED:
            return True
        self._skipped += 1
        if self._skipped < PROBE:
            return False
        self._skipped = 0
        return True

    def _scan(self, record: ScanRecord) -> None:
        self.cpu_mode = record.mode
        self.cycle = record.cycle
        self._t_ns = record.t_ns
        self._pending_mode = None  # the commands queued before this scan have acted
        if self._pending:
            self._pending.clear()

    def update(self, record: ScanRecord) -> StepStateUpdate:
        """The FB's state after the scan ``record`` (call once per scan, in the scan thread)."""
        return self._update(record, self.events.of(record, self.graph.db_number), see=False)

    def _update(
        self,
        record: ScanRecord,
        events: list[tuple[str, int]],
        *,
        see: bool,
        outs: tuple[Any, ...] | None = None,
        watched: tuple[tuple[str, object], ...] | None = None,
    ) -> StepStateUpdate:
        """:meth:`update`; with ``see``, keep what it saw for :meth:`changed`; ``outs`` and
        ``watched``: the values :meth:`changed` read already in this scan."""
        self._scan(record)
        if self._chart.cc is not self.graph.cc:
            self._follow()
        st = self.graph.state
        numbers = self.graph.cc.step_numbers
        steps = st.active
        active = sorted(map(numbers.__getitem__, steps))
        il_err, sv_err = st.il_err, st.sv_err
        bad = [i for i in steps if il_err[i] or sv_err[i]]
        if bad:
            disturbed = sorted([numbers[i] for i in bad])
            latched = sorted([numbers[i] for i in bad if sv_err[i]]) if st.ackreq_enabled else []
        else:
            disturbed = latched = _NONE
        mode = st.mode
        if outs is None:
            outs = self._outs()
        if watched is None:
            watched = self._watched()
        values = self._values(outs, watched)
        if see:
            self._seen = seen(st, self._chart.checks, outs, watched, self._leaving)
            self.copies += 1
        else:
            self._seen = None
        self._due = None
        return StepStateUpdate(
            cycle=record.cycle if record.cycle > 0 else 0,
            t_ms=max(record.t_ns // 1_000_000, 0),
            mode=mode if mode in MODES else "AUTO",
            active=active,
            disturbed=disturbed,
            latched=latched,
            events=events,  # type: ignore[arg-type]
            values=values,
            details=self.step_details.of(st),
            halted=bool(st.halted),
            il_enabled=bool(st.il_enabled),
            sv_enabled=bool(st.sv_enabled),
            overrides=dict(st.levels) if st.levels else _NO_LEVELS,  # type: ignore[arg-type]
        )

    def details(self) -> list[StepDetail]:
        """A :class:`StepDetail` per active step (cost proportional to the active steps;
        only a step whose state changed since the last call gets a new one)."""
        if self._chart.cc is not self.graph.cc:
            self._follow()
        return self.step_details.of(self.graph.state)

    def alarms_changed(self) -> AlarmList | None:
        """The message list if it changed since the last call (first call: always), else
        None (``web.bus.alarm_feed``)."""
        if self._alarms is None:
            return None
        return self._alarms.changed(self._t_ns, self.cycle)

    def values(self) -> dict[str, bool | int | float | str | None]:
        """The FB outputs, then the watched operands, the operands the permanent
        instructions write, then those of the active steps' action rows (an unreadable one
        is left out)."""
        return dict(self._values(self._outs(), self._watched()))

    def _outs(self) -> tuple[Any, ...]:
        """The FB's output pins' values, in ``out_pins`` order."""
        graph = self.graph
        pins = graph.out_pins
        if pins is not self._pins:  # a chart with another parameter set (online change)
            self._pins = pins
            self._pick = operator.itemgetter(*pins) if len(pins) > 1 else None
        if graph.idb is None or self._pick is None:
            return tuple(graph.outputs.values())
        return self._pick(graph.idb.values)

    def _watched(self) -> tuple[tuple[str, object], ...]:
        """The watched operands, the operands the permanent instructions write, then the
        active steps' action operands, that could be read, with their values."""
        out: list[tuple[str, object]] = []
        if self.watch:
            made = self._readers
            if made is None or made[0] is not self.watch:
                made = self._readers = (self.watch, self._resolve(self.watch))
            for name, read in made[1]:
                try:
                    out.append((name, _scalar(read())))
                except Exception:  # a watch must never stop the scan
                    continue
        if self._permanent != ():
            readers = self._permanent
            if readers is None:
                readers = self._permanent = self._resolve(self._chart.permanent)
            self._read_into(out, readers, MAX_VALUES - len(self.graph.out_pins))
        if self._operands:
            self._step_values(out)
        return tuple(out)

    def _values(
        self, outs: tuple[Any, ...], watched: tuple[tuple[str, object], ...]
    ) -> dict[str, bool | int | float | str | None]:
        """The values of an update: the last update's own dict while they are the same
        (messages are never changed, so two may share it)."""
        made = self._made
        if made is not None and made[0] == outs and made[1] == watched:
            return made[2]
        out = dict(zip(self.graph.out_pins, outs, strict=False))  # no instance DB: none
        if not _PLAIN.issuperset(map(type, outs)):
            out = {name: _scalar(v) for name, v in out.items()}
        out.update(watched)
        self._made = (outs, watched, out)
        return out

    def _step_values(self, out: list[tuple[str, object]]) -> None:
        """Add the values of the active steps' action operands to ``out``."""
        operands, made = self._chart.operands, self._step_readers
        room = MAX_VALUES - len(self.graph.out_pins)
        for i in self.graph.state.active:
            readers = made.get(i)
            if readers is None:
                readers = made[i] = self._resolve(operands[i]) if i < len(operands) else ()
            if len(out) + len(readers) > room:
                self._read_into(out, readers, room)
                if len(out) >= room:
                    return
                continue
            for name, read in readers:
                try:
                    value = read()
                except Exception:  # a watch must never stop the scan
                    continue
                out.append((name, value if type(value) in _PLAIN else _scalar(value)))

    @staticmethod
    def _read_into(out: list[tuple[str, object]], readers: _Readers, room: int) -> None:
        """Add the values of ``readers`` to ``out`` until it holds ``room``."""
        for name, read in readers:
            if len(out) >= room:
                return
            try:
                out.append((name, _scalar(read())))
            except Exception:  # a watch must never stop the scan
                continue

    def _resolve(self, names: tuple[str, ...]) -> _Readers:
        """A reader per watched name (once, not per scan: a symbol's lookup and an
        address's parse cost more than the read); a name ``reader`` cannot resolve is read
        through ``read``, which leaves it out while it stays unreadable."""
        out: list[tuple[str, Callable[[], object]]] = []
        for name in names:
            fn: Callable[[], object] | None = None
            if self._reader is not None:
                try:
                    fn = self._reader(name)
                except Exception:  # unknown for now: through read, as before
                    fn = None
            if fn is None and self._read is not None:
                fn = functools.partial(self._read, name)
            if fn is not None:
                out.append((name, fn))
        return tuple(out)

    # ------------------------------------------------------------ commands in

    def apply(self, command: Command) -> tuple[bool, str, str]:
        """Queue ``command`` as a one-call edge of the next FB call, as ``command.user``;
        (applied, reason, detail: what it acted on, for the audit).

        Never raises: anything unexpected refuses the command with the reason."""
        try:
            applied, reason, detail = self._check(command)
            what = f"FB {self.fb}" + (f": {detail}" if detail else "")
            return applied, reason, what if applied else ""
        except Exception as exc:
            op = getattr(command, "op", None)
            doing = f"applying {op}" if isinstance(op, str) else "applying a command"
            where = f"in the CPU while {doing} to {self.fb}"
            return False, f"command refused: {internal_error(where, exc)}"[:4096], ""

    def _check(self, command: Command) -> Result:
        op = getattr(command, "op", None)
        if self.cpu_mode is not CpuMode.RUN:
            return False, Refusal("state", f"the CPU is in {self.cpu_mode}, not RUN"), ""
        group = _GROUPS.get(op) if isinstance(op, str) else None
        queued = self._pending.get(group) if group else None
        if queued is not None:
            why = f"{op} conflicts with {queued}, queued for the same scan; retry"
            return False, Refusal("busy", why), ""
        applied, reason, detail = self._queue(command, op)
        if applied and group:
            self._pending[group] = f"{op} {detail}".strip()
        return applied, reason, detail

    def _queue(self, command: Command, op: object) -> Result:
        """``command`` to its op's handler (:data:`HANDLERS`, by its struct)."""
        handler = HANDLERS.get(type(command))
        if handler is None:
            return False, Refusal("not_found", f"unknown command {op!r}"), ""
        return handler(self, command, self._pending_mode or self.graph.state.mode)

    def _mode(self, command: SetMode, mode: str) -> Result:
        new = command.mode
        if new not in MODE_PINS:
            return False, Refusal("argument", f"mode must be one of {', '.join(MODES)}"), ""
        self.graph.command(MODE_PINS[new])
        self._pending_mode = new
        return True, "", f"{mode} -> {new}"

    def _ack(self, command: Ack, mode: str) -> Result:
        st, cc = self.graph.state, self.cc
        waiting = [i for i in st.active if st.sv_err[i]]
        if not waiting:
            return False, Refusal("state", "no supervision fault waits for an acknowledgement"), ""
        stays = [i for i in waiting if self._relatches(i)]
        if len(stays) == len(waiting):
            return False, Refusal("state", _CAUSE_PERSISTS.format(_steps(cc, stays))), ""
        self.graph.command(OP_PINS[command.op], user=command.user or "?")
        note = f"{_steps(cc, stays)} stays latched: its cause persists" if stays else ""
        return True, note, "steps " + _steps(cc, [i for i in waiting if i not in stays])

    def _ack_step(self, command: AckStep, mode: str) -> Result:
        st, step = self.graph.state, command.step
        i = self.cc.step_index.get(step) if isinstance(step, int) else None
        if i is None:
            return False, Refusal("not_found", f"no step S{step} in {self.fb}"), ""
        if not (st.x[i] and st.sv_err[i]):
            return False, Refusal("state", f"S{step} waits for no acknowledgement"), ""
        if self._relatches(i):
            return False, Refusal("state", _CAUSE_PERSISTS.format(f"S{step}")), ""
        self.graph.command(OP_PINS[command.op], step=step, user=command.user or "?")
        return True, "", f"S{step}"

    def _edge(self, command: Init | Off, mode: str) -> Result:
        """INIT_SQ, OFF_SQ: one call, as the command's user."""
        self.graph.command(OP_PINS[command.op], user=command.user or "?")
        return True, "", ""

    def _level(self, command: Halt | EnIl | EnSv, mode: str) -> Result:
        """HALT_SQ, EN_IL, EN_SV held at the op's value, or left to the pin again."""
        op = command.op
        pin, held = LEVEL_PINS[op]
        on = command.args.get("on")
        if not isinstance(on, bool):
            return False, Refusal("argument", f"{op} needs on: true or false"), ""
        hold = on == held
        self.graph.set_level(pin, held if hold else None)
        return True, "", f"{pin} {'held at ' + str(int(held)) if hold else 'back to its pin'}"

    def _t_push(self, command: TPush, mode: str) -> Result:
        if mode not in ("TAP", "TOP"):
            why = f"t_push needs mode TAP or TOP ({CONTROL_SEQUENCER})"
            return False, Refusal("state", why), ""
        self.graph.command(OP_PINS[command.op])
        st, cc = self.graph.state, self.cc
        ready = any(st.tt[j] for i in st.active for j in cc.leaving[i])
        return True, "" if ready or mode == "TOP" else _NOT_SATISFIED, ""

    def _step(self, command: StepOn | StepOff, mode: str) -> Result:
        """S_ON / S_OFF on the command's step (not S_NO), in MAN."""
        op, step = command.op, command.step
        if mode != "MAN":
            return False, Refusal("state", f"{op} needs mode MAN ({CONTROL_SEQUENCER})"), ""
        i = self.cc.step_index.get(step) if isinstance(step, int) else None
        if i is None:
            return False, Refusal("not_found", f"no step S{step} in {self.fb}"), ""
        active = self.graph.state.x[i]
        if isinstance(command, StepOn) and active:
            return False, Refusal("state", f"S{step} is already active"), ""
        if isinstance(command, StepOff) and not active:
            return False, Refusal("state", f"S{step} is not active"), ""
        self.graph.command(OP_PINS[op], step=step)
        return True, "", f"S{step}"

    def _relatches(self, i: int) -> bool:
        """Whether step ``i``'s supervision fault, acknowledged now, would latch again at
        once (its condition still holds) without the step switching on: no forced switching
        (``ack_forces_switch``) and, in AUTO, no leaving transition satisfied."""
        st, cc = self.graph.state, self.cc
        if not st.sv_cond[i] or cc.options.ack_forces_switch:
            return False
        mode = self._pending_mode or st.mode
        return not (mode == "AUTO" and any(st.tt[j] for j in cc.leaving[i]))

    def _ack_msg(self, command: AckMsg, mode: str) -> Result:
        mid = command.msg_id
        if self._alarms is None:
            return False, Refusal("not_found", "this view has no message list"), ""
        msg, why = self._alarms.acknowledge(mid, command.user or "?", self._t_ns)
        if msg is None:
            return False, why, ""
        where = parse_message_id(msg.msg_id)
        ours = where is not None and where[:2] == (self.cc.name, self.graph.db_number)
        step = where[2] if where is not None and ours and where[3] == "SV" else None
        i = self.cc.step_index.get(step) if step is not None else None
        st = self.graph.state
        note = ""
        if i is not None and st.x[i] and st.sv_err[i] and self._relatches(i):
            note = f"acknowledged; the cause of S{step} persists: it comes again as a new message"
        return True, note, f"message {mid}: {msg.text}"


def _set_steps(live: LiveGraph, command: SetSteps, mode: str) -> Result:
    """The steps named the active ones of their sequences in one call, in MAN
    (``sequencer.placing``); refused when nothing would change."""
    if mode != "MAN":
        return False, Refusal("state", f"set_steps needs mode MAN ({CONTROL_SEQUENCER})"), ""
    cc, numbers = live.cc, command.args.steps
    unknown = [n for n in numbers if n not in cc.step_index]
    if unknown:
        why = f"no step {', '.join(f'S{n}' for n in unknown)} in {live.fb}"
        return False, Refusal("not_found", why), ""
    steps = list(dict.fromkeys(cc.step_index[n] for n in numbers))
    leave, enter = moves(cc.step_seq, live.graph.state.active, steps)
    if not leave and not enter:
        why = "already active, no other step active in their sequences"
        return False, Refusal("state", f"nothing to change: {_steps(cc, steps)} {why}"), ""
    live.graph.place(numbers)
    off, on = _steps(cc, leave) or "none", _steps(cc, enter) or "none"
    return True, "", f"{_steps(cc, steps)} (off: {off}; on: {on})"


# The FB's handler of each op the FB carries out (``where == "fb"``), by the op's struct:
# an op of the union without one is refused as unknown (a test checks that none is).
HANDLERS: Final[dict[type[Command], Callable[[LiveGraph, Any, str], Result]]] = {
    Ack: LiveGraph._ack,
    AckStep: LiveGraph._ack_step,
    AckMsg: LiveGraph._ack_msg,
    SetMode: LiveGraph._mode,
    Init: LiveGraph._edge,
    Off: LiveGraph._edge,
    Halt: LiveGraph._level,
    TPush: LiveGraph._t_push,
    StepOn: LiveGraph._step,
    StepOff: LiveGraph._step,
    SetSteps: _set_steps,
    EnIl: LiveGraph._level,
    EnSv: LiveGraph._level,
}


_CAUSE_PERSISTS = (
    "the cause of {}'s supervision fault persists (its condition still holds): "
    "acknowledged now the fault would latch again at once and its message stay "
    "unacknowledged; remove the cause, then acknowledge"
)


_NOT_SATISFIED = (
    "no transition of the active steps was satisfied in the last call: in TAP the push "
    "switches only one satisfied in the next"
)


def _steps(cc: CompiledChart, steps: Iterable[int]) -> str:
    return ", ".join(f"S{n}" for n in sorted(cc.step_numbers[i] for i in steps))


def _negations(condition: Any, labels: tuple[str, ...]) -> tuple[bool, ...]:
    """Which contacts of ``condition`` are negated; none if the walk does not match."""
    found = contact_negations(condition)
    return tuple(found) if len(found) == len(labels) else (False,) * len(labels)


def watch_names(symbols: Iterable[Any], limit: int = 16) -> list[str]:
    """A few operands worth watching: the symbols on inputs and outputs (I/Q), in order."""
    names = [sym.name for sym in symbols if str(sym.address.area) in ("I", "Q")]
    return names[:limit]
