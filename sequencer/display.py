"""Display outputs of a GRAPH FB: S_NO paging, step/transition status, group bits
(docs/semantics.md, "FB pins" and "Decisions").

S_PREV/S_NEXT and T_PREV/T_NEXT only page the step/transition *shown*; they never move the
sequence (docs/semantics.md, "FB pins" — STEP7 comprehensive guide vol. 2, ch. 14 says otherwise and
is wrong, TIA-V21 comments).

The cursor lives in the instance DB: ``GraphState.s_no``/``t_no`` and ``GraphState.display``
(``set``: "SACT" | "SEF" | "SALL"; ``pinned``: S_NO shows a step chosen with S_SEL even if
it is outside the display set; ``s_sel``: the S_SEL value of the previous call). The cycle
calls ``page`` once per call right after latching the inputs (so ACK_S, REG_S and MAN's
S_ON/S_OFF act on the step the operator sees), ``compute_outputs`` at the end and then
``settle`` to store what was shown.

Decisions (where S7-GRAPH's documentation is silent, pinned by tests/sequencer/test_display.py):
* DISP_SACT/DISP_SEF/DISP_SALL: a rising edge selects the display set, kept until another
  edge; default SACT (TIA start value of MOP.SACT_DISP).
* S_SEL applies when its value changes to an existing step number (or again on an S_SELOK
  edge); the chosen step stays shown (pinned) even outside the display set, until S_PREV or
  S_NEXT pages. S_SEL 0 leaves S_NO unchanged; a number the chart lacks is NO_SNO ("selected
  step does not exist", manual 15-18): S_NO shows 0, so S_ON, S_OFF and ACK_S act on no step,
  until S_SEL names a step or S_PREV/S_NEXT pages.
* In MAN, S_PREV/S_NEXT page through every step by number (the next lower or higher), so
  the operator can show an inactive step and activate it with S_ON; the step stays shown.
* Otherwise S_NO follows the display set: if the shown step leaves the set, S_NO moves to
  the first step of the set with a number ≥ the old one (else the first); 0 if the set is
  empty. Paging wraps around. T_NO does the same through the *valid* transitions (all
  preceding steps active), ordered by transition number.
* S_TIME = T, S_TIMEOK = U of the shown step (ms).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from functools import cache
from typing import Any, Final

from s7graph.sequencer.compiled import CompiledChart
from s7graph.sequencer.params import Direction, outputs_for
from s7graph.sequencer.state import GraphState

DISPLAY_SETS: Final = ("SACT", "SEF", "SALL")

# S_STATE (WORD) bit layout — engine-defined (Siemens publishes none; docs/semantics.md, "FB pins").
S_STATE_BITS: Final[tuple[tuple[int, str, str], ...]] = (
    (0, "X", "step active"),
    (1, "LA", "interlock error: active and interlock not held (C rows off, red)"),
    (2, "VA", "supervision fault latched (blocks the step's transitions)"),
    (3, "VS", "supervision condition true now (the fault's cause is present)"),
    (4, "LS", "interlock condition holds now"),
    (5, "DISTURBED", "interlock error or supervision fault (SERRX, shown red)"),
    (6, "ACK_WAIT", "fault latched although its cause has gone: awaits acknowledgement"),
    (7, "INIT", "initial step"),
    (8, "S1", "event S1 in this call (activated)"),
    (9, "S0", "event S0 in this call (deactivated)"),
    (10, "V1", "event V1 in this call (supervision fault came)"),
    (11, "V0", "event V0 in this call (supervision fault went / acknowledged)"),
    (12, "L1", "event L1 in this call (interlock lost)"),
    (13, "L0", "event L0 in this call (interlock returned)"),
    (14, "A1", "event A1 in this call (acknowledged)"),
    (15, "R1", "event R1 in this call (registered)"),
)
_EVENT_SHIFT: Final = 8  # GraphState.ev bits S1..R1 (EV_S1=1 … EV_R1=128) → bits 8..15


def s_state(chart: CompiledChart, state: GraphState, i: int) -> int:
    """The S_STATE word of step index ``i`` (layout ``S_STATE_BITS``)."""
    flags = (
        state.x[i],
        state.il_err[i],
        state.sv_err[i],
        state.sv_cond[i],
        state.il_ok[i],
        state.disturbed(i),
        state.sv_err[i] and not state.sv_cond[i],
        i in chart.initial,
    )
    word = sum(1 << k for k, on in enumerate(flags) if on)
    return word | (state.ev[i] & 0xFF) << _EVENT_SHIFT


# ---------------------------------------------------------------- the sets paged through


def display_set(state: GraphState) -> str:
    name = state.display.get("set", "SACT")
    return name if name in DISPLAY_SETS else "SACT"


def shown_steps(
    chart: CompiledChart, state: GraphState, active: Sequence[int] | None = None
) -> list[int]:
    """Step numbers S_NO pages through, ascending (DISP_SACT / DISP_SEF / DISP_SALL).

    ``active``: the active step indices (``state.active``) when the state is kept by the
    cycle — the work is then proportional to them; None walks every step's ``x``."""
    which = display_set(state)
    numbers = chart.step_numbers
    if which == "SALL":
        return sorted(numbers)
    idx: Iterable[int] = range(chart.n_steps) if active is None else active
    if which == "SACT":
        x = state.x
        return sorted([numbers[i] for i in idx if x[i]])
    il_err, sv_err = state.il_err, state.sv_err
    return sorted([numbers[i] for i in idx if il_err[i] or sv_err[i]])


def valid_transitions(
    chart: CompiledChart, state: GraphState, active: Sequence[int] | None = None
) -> list[int]:
    """Transition numbers whose preceding steps are all active (TVX), ascending.

    With ``active`` only the transitions leaving those steps are looked at."""
    x = state.x
    tr_src = chart.tr_src
    cand: Iterable[int]
    if active is None:
        cand = range(chart.n_transitions)
    else:
        leaving = chart.leaving
        cand = {j for i in active for j in leaving[i]}
    numbers = chart.transition_numbers
    return sorted([numbers[j] for j in cand if tr_src[j] and all(x[s] for s in tr_src[j])])


def _snap(current: int, members: list[int]) -> int:
    if not members:
        return 0
    if current in members:
        return current
    return next((n for n in members if n >= current), members[0])


def _step(current: int, members: list[int], delta: int) -> int:
    """The member ``delta`` (+1 next, -1 previous) from ``current``, by number, wrapping; from
    a number outside ``members`` (a step S_SEL chose) the nearest member above it (next) or
    below it (previous)."""
    if not members:
        return 0
    if current in members:
        return members[(members.index(current) + delta) % len(members)]
    if delta > 0:
        return next((n for n in members if n > current), members[0])
    return next((n for n in reversed(members) if n < current), members[-1])


def _shown_step(chart: CompiledChart, state: GraphState, members: Callable[[], list[int]]) -> int:
    if state.display.get("no_sno"):  # S_SEL chose a step the chart lacks: none shown
        return 0
    if state.display.get("pinned") and state.s_no in chart.step_index:
        return state.s_no
    return _snap(state.s_no, members())


def shown_step(chart: CompiledChart, state: GraphState, active: Sequence[int] | None = None) -> int:
    """The step number S_NO shows for this state (0 = none)."""
    return _shown_step(chart, state, lambda: shown_steps(chart, state, active))


def shown_transition(
    chart: CompiledChart, state: GraphState, active: Sequence[int] | None = None
) -> int:
    """The transition number T_NO shows for this state (0 = none)."""
    return _snap(state.t_no, valid_transitions(chart, state, active))


# ---------------------------------------------------------------- cursor update (per call)


def page(
    chart: CompiledChart,
    state: GraphState,
    inputs: Mapping[str, Any],
    edges: Iterable[str],
    active: Sequence[int] | None = None,
) -> None:
    """Move the display cursor for this call's inputs (call after latching inputs).

    Reads DISP_* / S_PREV / S_NEXT / T_PREV / T_NEXT / S_SELOK rising edges (``edges``) and
    the S_SEL value; writes ``state.s_no``, ``state.t_no`` and ``state.display``. Never
    touches a step bit. ``active`` as for ``shown_steps``."""
    rose = edges if isinstance(edges, (set, frozenset)) else set(edges)
    disp = state.display
    for name in DISPLAY_SETS:
        if f"DISP_{name}" in rose:
            disp["set"] = name
    disp.setdefault("set", "SACT")
    state.s_no = shown_step(chart, state, active)

    sel = int(inputs.get("S_SEL", 0) or 0)
    if sel != disp.get("s_sel", 0) or "S_SELOK" in rose:
        if sel in chart.step_index:
            state.s_no = sel
            disp["pinned"] = True
            disp.pop("no_sno", None)
        elif sel:  # NO_SNO: S_ON, S_OFF and ACK_S then act on no step
            state.s_no = 0
            disp["no_sno"] = True
    disp["s_sel"] = sel

    delta = ("S_NEXT" in rose) - ("S_PREV" in rose)
    if delta:
        disp.pop("no_sno", None)
        if state.mode == "MAN":  # every step, by number: the one S_ON activates
            state.s_no = _step(state.s_no, sorted(chart.step_numbers), delta)
            disp["pinned"] = True
        else:
            state.s_no = _step(state.s_no, shown_steps(chart, state, active), delta)
            disp["pinned"] = False

    state.t_no = shown_transition(chart, state, active)
    t_delta = ("T_NEXT" in rose) - ("T_PREV" in rose)
    if t_delta:
        state.t_no = _step(state.t_no, valid_transitions(chart, state, active), t_delta)


def settle(chart: CompiledChart, state: GraphState, active: Sequence[int] | None = None) -> None:
    """Store the S_NO/T_NO shown after this call (what ``compute_outputs`` reports)."""
    state.s_no = shown_step(chart, state, active)
    state.t_no = shown_transition(chart, state, active)


# ---------------------------------------------------------------- outputs

_GROUP_PINS: Final[dict[str, Callable[[GraphState], bool]]] = {
    "ERROR": lambda st: st.error,
    "FAULT": lambda st: st.fault,
    "ERR_FLT": lambda st: st.err_flt,
    "SQ_ISOFF": lambda st: not st.active,  # no step active: OFF_SQ until INIT_SQ / S_ON
    "SQ_HALTED": lambda st: st.halted,
    "TM_HALTED": lambda st: st.tm_halted,
    "OP_ZEROED": lambda st: st.zeroed,
    "IL_ENABLED": lambda st: st.il_enabled,
    "SV_ENABLED": lambda st: st.sv_enabled,
    "ACKREQ_ENABLED": lambda st: st.ackreq_enabled,
    "SSKIP_ENABLED": lambda st: st.sskip_enabled,
    "SACT_DISP": lambda st: display_set(st) == "SACT",
    "SEF_DISP": lambda st: display_set(st) == "SEF",
    "SALL_DISP": lambda st: display_set(st) == "SALL",
    "AUTO_ON": lambda st: st.mode == "AUTO",
    "TAP_ON": lambda st: st.mode == "TAP",
    "TOP_ON": lambda st: st.mode == "TOP",
    "MAN_ON": lambda st: st.mode == "MAN",
}
# Group pins step events can change (the others follow options, the mode, the set).
_SWITCH_GROUPS: Final = frozenset({"ERROR", "FAULT", "ERR_FLT", "SQ_ISOFF"})
# Pins of the shown step / transition that change from call to call without a step switch,
# fault change or display edge (times, criteria bits, events).
_STEP_PINS: Final = ("S_TIME", "S_TIMEOK", "S_CRITLOC", "S_CRITLOCERR", "S_CRITSUP", "S_STATE")
_TRANSITION_PINS: Final = ("T_CRIT", "T_CRITOLD", "T_CRITFLT")


@dataclass(frozen=True, slots=True)
class _Plan:
    """What the pins of one parameter set need: the shown step (and which of its per-call
    pins), the shown transition (and which pins), the group/option/mode pins."""

    wanted: tuple[str, ...]
    step: bool
    step_pins: tuple[str, ...]
    transition: bool
    transition_pins: tuple[str, ...]
    groups: tuple[tuple[str, Callable[[GraphState], bool]], ...]
    switch_groups: tuple[tuple[str, Callable[[GraphState], bool]], ...]
    switch_pins: tuple[str, ...]  # the pins ``Display._switched`` writes
    live_pins: tuple[str, ...]  # step_pins + transition_pins


@cache
def _plan(set_name: str) -> _Plan:
    wanted = tuple(p.name for p in outputs_for(set_name) if p.direction is Direction.OUT)
    step = ("S_NO", "S_MORE", "S_ACTIVE", *_STEP_PINS)
    return _Plan(
        wanted=wanted,
        step=bool(set(step) & set(wanted)),
        step_pins=tuple(n for n in _STEP_PINS if n in wanted),
        transition=bool({"T_NO", "T_MORE", *_TRANSITION_PINS} & set(wanted)),
        transition_pins=tuple(n for n in _TRANSITION_PINS if n in wanted),
        groups=tuple((n, _GROUP_PINS[n]) for n in wanted if n in _GROUP_PINS),
        switch_groups=tuple((n, _GROUP_PINS[n]) for n in wanted if n in _SWITCH_GROUPS),
        switch_pins=tuple(n for n in wanted if n in step or n in _SWITCH_GROUPS),
        live_pins=tuple(n for n in wanted if n in _STEP_PINS or n in _TRANSITION_PINS),
    )


def _step_pins(
    chart: CompiledChart,
    state: GraphState,
    i: int | None,
    names: Iterable[str],
    out: dict[str, object],
) -> None:
    for name in names:
        if i is None:
            out[name] = 0
        elif name == "S_TIME":
            out[name] = state.t_ns[i] // 1_000_000
        elif name == "S_TIMEOK":
            out[name] = state.u_ns[i] // 1_000_000
        elif name == "S_CRITLOC":
            out[name] = int(state.crit_loc[i])
        elif name == "S_CRITLOCERR":
            out[name] = int(state.crit_loc_err[i])
        elif name == "S_CRITSUP":
            out[name] = int(state.crit_sup[i])
        else:
            out[name] = s_state(chart, state, i)


def _transition_pins(
    state: GraphState, j: int | None, names: Iterable[str], out: dict[str, object]
) -> None:
    for name in names:
        if j is None:
            out[name] = 0
        elif name == "T_CRIT":
            out[name] = int(state.crit[j])
        elif name == "T_CRITOLD":
            out[name] = int(state.crit_old[j])
        else:
            out[name] = int(state.crit_flt[j])


def _outputs(
    chart: CompiledChart,
    state: GraphState,
    plan: _Plan,
    active: Sequence[int] | None,
    out: dict[str, object],
) -> tuple[int, int]:
    """Write the pins of ``plan`` into ``out``; return the S_NO and T_NO shown (T_NO only
    when the set has transition pins, else ``state.t_no``). Only what they need is computed."""
    steps = shown_steps(chart, state, active)
    s_no = _shown_step(chart, state, lambda: steps)
    if plan.step:
        i = chart.step_index.get(s_no)
        out["S_NO"] = s_no
        out["S_MORE"] = len(steps) > 1 or (len(steps) == 1 and steps[0] != s_no)
        out["S_ACTIVE"] = i is not None and state.x[i]
        _step_pins(chart, state, i, plan.step_pins, out)
    t_no = state.t_no
    if plan.transition:
        trans = valid_transitions(chart, state, active)
        t_no = _snap(t_no, trans)
        out["T_NO"] = t_no
        out["T_MORE"] = len(trans) > 1 or (len(trans) == 1 and trans[0] != t_no)
        _transition_pins(state, chart.transition_index.get(t_no), plan.transition_pins, out)
    for name, f in plan.groups:
        out[name] = f(state)
    return s_no, t_no


def compute_outputs(
    chart: CompiledChart,
    state: GraphState,
    inputs: Mapping[str, Any] | None = None,
    edges: Iterable[str] = (),
    *,
    set_name: str | None = None,
    active: Sequence[int] | None = None,
) -> dict[str, object]:
    """Every output pin of ``set_name`` (default: the chart's parameter set) for this state.

    Pure: reads the state (and the cursor left by ``page``), writes nothing. ``inputs`` and
    ``edges`` are accepted for symmetry with ``page``; the effective options of this call
    (EN_IL, HALT_SQ, …) are already in the state. ``active`` as for ``shown_steps``."""
    del inputs, edges
    plan = _plan(set_name or chart.parameters)
    out: dict[str, object] = {}
    _outputs(chart, state, plan, active, out)
    return {name: out[name] for name in plan.wanted}


class Display:
    """The display of one runtime (docs/semantics.md, "FB pins"), incremental: the cycle calls
    ``page`` after latching the inputs and ``update`` at the end of the call.

    The sets S_NO/T_NO page through are recomputed — from ``state.active`` and the leaving
    transitions, never all steps — only when the cycle reports a change (``dirty``: an
    input pin changed) or the call raised a step event (a step switched, a fault or
    interlock changed), and not even then while S_NO pages through the active steps
    (``_switched``); otherwise only the pins of the shown step/transition that move by
    themselves (times, criteria, S_STATE) are refreshed, and with the STANDARD set nothing
    is. ``update`` returns the pins it wrote. Results equal ``page`` + ``compute_outputs``
    + ``settle`` of the pure functions (tests/sequencer/test_display.py; the differential
    test compares with a runtime that recomputes everything on every call). T_NO is
    tracked only when the set shows it."""

    __slots__ = ("_by_switch", "_full", "chart", "dirty", "plan")

    def __init__(self, chart: CompiledChart) -> None:
        self.chart = chart
        self.plan = _plan(chart.parameters)
        self.dirty = True
        self._by_switch = False  # ``_switched`` applies (set by each full update)
        self._full = False  # the next update writes every pin (``cut_short``)

    def page(self, state: GraphState, inputs: Mapping[str, Any], rose: set[str]) -> None:
        """``page`` when a display input acts (an edge, a new S_SEL) or the state changed."""
        sel = int(inputs.get("S_SEL", 0) or 0)
        if not self.dirty and not rose and sel == state.display.get("s_sel", 0):
            return
        page(self.chart, state, inputs, rose, state.active)
        self.dirty = True

    def update(self, state: GraphState) -> tuple[str, ...]:
        """Write this call's output pins into ``state.outputs`` and settle S_NO/T_NO;
        return the names of the pins written (the others keep their values)."""
        plan = self.plan
        chart = self.chart
        if self.dirty or state.log or self._full:
            if not (self.dirty or self._full) and self._switched(state):
                return plan.switch_pins
            self.dirty = self._full = False
            state.s_no, state.t_no = _outputs(chart, state, plan, state.active, state.outputs)
            self._by_switch = not plan.transition and display_set(state) == "SACT"
            return plan.wanted
        if plan.step_pins:
            i = chart.step_index.get(state.s_no)
            _step_pins(chart, state, i, plan.step_pins, state.outputs)
        if plan.transition_pins:
            j = chart.transition_index.get(state.t_no)
            _transition_pins(state, j, plan.transition_pins, state.outputs)
        return plan.live_pins

    def cut_short(self) -> None:
        """The call was cut short (an exception escaped it) before it wrote its pins: the
        next ``update`` writes every pin, whatever that call changes."""
        self._full = True

    def _switched(self, state: GraphState) -> bool:
        """``update`` after a call in which no input pin changed (not ``dirty``) but step
        events were raised, while S_NO pages through the active steps (DISP_SACT) and
        T_NO is not shown (``_by_switch``, set by each full update: only a dirty call
        changes the display set). Events change the active steps, the shown step's pins
        and the group pins of ``_SWITCH_GROUPS``; the other pins follow inputs and
        commands only, which make the display ``dirty``. So: S_NO moves only if the shown
        step is no longer active (and not pinned by S_SEL) — to the first active step
        numbered at or above it, else the lowest, as ``_snap``, found in one pass over the
        active steps instead of sorting them — then S_MORE, S_ACTIVE, the shown step's
        pins and those group pins are written. False, and nothing done, when it does not
        apply."""
        if not self._by_switch or state.display.get("no_sno"):
            return False
        index = self.chart.step_index
        x = state.x
        active = state.active
        s_no = state.s_no
        i = index.get(s_no)
        if i is None or not (x[i] or state.display.get("pinned")):
            numbers = self.chart.step_numbers
            above = low = -1
            for a in active:
                n = numbers[a]
                if n >= s_no and (above < 0 or n < above):
                    above = n
                if low < 0 or n < low:
                    low = n
            s_no = above if above >= 0 else max(low, 0)
            state.s_no = s_no
            i = index.get(s_no)
        plan = self.plan
        out = state.outputs
        if plan.step:
            shown = i is not None and x[i]
            out["S_NO"] = s_no
            out["S_MORE"] = len(active) > shown  # others than the shown one are active
            out["S_ACTIVE"] = shown
            if plan.step_pins:
                _step_pins(self.chart, state, i, plan.step_pins, out)
        for name, f in plan.switch_groups:
            out[name] = f(state)
        return True


# ---------------------------------------------------------------- "why does it not switch?"


def criteria_by_name(
    chart: CompiledChart, state: GraphState, element: str
) -> list[tuple[str, bool]]:
    """Each contact of a condition with its truth in the last evaluation (CRIT bits).

    ``element``: a transition ``"T2"`` or its name, a step's interlock ``"S3.IL"`` /
    ``"S3.INTERLOCK"`` or supervision ``"S3.SV"`` / ``"S3.SUPERVISION"`` (case-insensitive).
    Raises ``KeyError`` naming the element when it does not exist."""
    up = element.strip().upper()
    if "." in up:
        head, _, what = up.partition(".")
        i = chart.step_index.get(_number(head, "S"))
        if i is not None and what in ("IL", "INTERLOCK", "C"):
            return contact_bits(chart.il_labels[i], int(state.crit_loc[i]))
        if i is not None and what in ("SV", "SUPERVISION", "V"):
            return contact_bits(chart.sv_labels[i], int(state.crit_sup[i]))
        raise KeyError(f"no interlock or supervision {element!r}")
    j = chart.transition_index.get(_number(up, "T"))
    if j is None:
        names = [n.upper() for n in chart.transition_names]
        j = names.index(up) if up in names else None
    if j is None:
        raise KeyError(f"no transition {element!r}")
    return contact_bits(chart.crit_labels[j], int(state.crit[j]))


def _number(text: str, prefix: str) -> int:
    if text.startswith(prefix) and text[1:].isdigit():
        return int(text[1:])
    return -1


def contact_bits(labels: tuple[str, ...], word: int) -> list[tuple[str, bool]]:
    """Each contact label with its bit of a criteria word (``crit``/``crit_loc``/``crit_sup``)."""
    return [(label, bool(word >> k & 1)) for k, label in enumerate(labels)]
