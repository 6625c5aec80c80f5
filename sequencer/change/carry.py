"""A GRAPH FB's state across versions of its chart (docs/semantics.md, "Structure";
docs/architecture.md, "The core is a function").

``fingerprint(cc)`` names a compiled chart — its steps, transitions, generated code,
variables, options and parameter set, not where things are written in the file; the state
file records it beside the FB's state. ``ChartShape`` is what a state needs to be read
without the chart that wrote it (step and transition numbers by index, variable types).

``carry_over(old, state, new)`` is the one function that takes the state of one chart
version to another — the state file of a changed chart, and the browser's online change
(download) alike. Pure: old shape + old state + new chart → new state + report. By step
number: an active step that still exists stays active with its times T and U, its fault
latches and criteria; active steps that are gone are reported; transitions by number;
variables by name (kept when their type is unchanged, else at their new initial value, and
reported: :func:`restart_line`); the mode, the options latched from the pins and the edge
memories as they were. A sequencer the old version did not have (:func:`new_sequencers`)
gets its initial steps active, as its first call after a start would activate them — unless
an active step carried over is in it (moved there): it goes on from that one.

``ChartFormat`` is the ``engine.blocks.StateFormat`` of a GraphFB: how
``engine/persistence.py`` recognises (and carries over) its instance data.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Collection, Iterable
from dataclasses import dataclass, field
from typing import Any

from s7graph.engine.blocks import default_value
from s7graph.engine.errors import S7Error
from s7graph.engine.literals import format_literal
from s7graph.sequencer.compiled import CompiledChart
from s7graph.sequencer.cycle import new_state
from s7graph.sequencer.state import STEP_LISTS, TRANSITION_LISTS, GraphState
from s7graph.sequencer.text.model import VarDecl

__all__ = [
    "CarryReport",
    "ChartFormat",
    "ChartShape",
    "NewSequencer",
    "carry_over",
    "fingerprint",
    "initial_text",
    "new_sequencers",
    "restart_line",
]

_SCALARS = (
    "mode",
    "calls",
    "last_ns",
    "off",
    "halted",
    "tm_halted",
    "zeroed",
    "il_enabled",
    "sv_enabled",
    "ackreq_enabled",
    "sskip_enabled",
    "ov_count",
)


def fingerprint(cc: CompiledChart) -> str:
    """``chart:`` and 16 hex digits of a hash of what the compiled chart does; computed
    once per compiled chart and kept with it (it goes with the chart when pickled, so the
    process that compiled it pays for it, not the scan boundary of an online change)."""
    known = cc.__dict__.get("_fingerprint")
    if isinstance(known, str):
        return known
    chart = cc.chart
    steps = [
        [n, name, s.message, i in cc.initial]
        for i, (n, name, s) in enumerate(
            zip(cc.step_numbers, cc.step_names, chart.all_steps(), strict=True)
        )
    ]
    described = {
        "fb": [cc.name, chart.fb_number, chart.db_number],
        "options": repr(cc.options),
        "parameters": cc.parameters,
        "steps": steps,
        "sequences": [list(cc.seq_numbers), list(cc.seq_names), [list(s) for s in cc.seq_steps]],
        "transitions": [
            [n, name, list(src), list(dst)]
            for n, name, src, dst in zip(
                cc.transition_numbers, cc.transition_names, cc.tr_src, cc.tr_dst, strict=True
            )
        ],
        "vars": sorted(cc.var_types.items()),
        "inits": repr(sorted(cc.var_inits.items())),
        "code": cc.source,
        "consts": repr(sorted(cc.consts.items())),
    }
    text = json.dumps(described, sort_keys=True, default=str)
    found = "chart:" + hashlib.sha256(text.encode()).hexdigest()[:16]
    object.__setattr__(cc, "_fingerprint", found)  # frozen: not a field, kept beside them
    return found


@dataclass(frozen=True, slots=True)
class ChartShape:
    """What a saved GraphState is read by: step and transition numbers by compiled index,
    the variables' types, the chart's name and its sequencers' numbers (None: a state saved
    before they were kept)."""

    name: str
    step_numbers: tuple[int, ...]
    transition_numbers: tuple[int, ...]
    var_types: dict[str, str] = field(default_factory=dict)
    sequences: tuple[int, ...] | None = None

    @classmethod
    def of(cls, cc: CompiledChart) -> ChartShape:
        return cls(
            cc.name, cc.step_numbers, cc.transition_numbers, dict(cc.var_types), cc.seq_numbers
        )

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "name": self.name,
            "steps": list(self.step_numbers),
            "transitions": list(self.transition_numbers),
            "vars": dict(self.var_types),
        }
        if self.sequences is not None:
            out["sequences"] = list(self.sequences)
        return out

    @classmethod
    def from_json(cls, data: object) -> ChartShape:
        """ValueError for anything but a ``to_json`` result."""
        if not isinstance(data, dict):
            raise ValueError("no chart shape saved with the state")
        steps, transitions = data.get("steps"), data.get("transitions")
        variables = data.get("vars", {})
        sequences = data.get("sequences")
        if not (
            isinstance(data.get("name"), str)
            and isinstance(steps, list)
            and isinstance(transitions, list)
            and all(isinstance(n, int) for n in steps + transitions)
            and isinstance(variables, dict)
            and (
                sequences is None
                or (isinstance(sequences, list) and all(isinstance(n, int) for n in sequences))
            )
        ):
            raise ValueError("malformed chart shape")
        return cls(
            str(data["name"]),
            tuple(steps),
            tuple(transitions),
            {str(k): str(v) for k, v in variables.items()},
            tuple(sequences) if sequences is not None else None,
        )


def initial_text(decl: VarDecl) -> str:
    """The value variable ``decl`` starts at, as the chart writes it: its declared initial
    value, else its type's zero as a literal of that type (``engine.blocks.default_value``,
    ``engine.literals.format_literal``: FALSE, 0, L#0, W#16#0000, 0.0, '', D#1990-01-01 …)."""
    if decl.init is not None:
        return decl.init.text
    try:
        return format_literal(decl.type, default_value(decl.type))
    except S7Error:  # a type with no literal of its own
        return "0"


def restart_line(name: str, before: str, after: str, initial: str) -> str:
    """A variable whose declared type changed: the carry-over's line, which a download's
    preview gives too (``sequencer.change.diff``)."""
    return f"variable {name}: {before} → {after}, restarts at its initial value {initial}"


@dataclass(frozen=True, slots=True)
class NewSequencer:
    """A sequencer a new chart version has and the running one had not: its number, the
    initial steps that become active at the swap, and the active steps carried into it
    (moved there from another sequencer: then it goes on from those, none is activated)."""

    number: int
    started: tuple[int, ...]
    carried: tuple[int, ...] = ()

    def line(self) -> str:
        """What a download's preview and its reply say of it."""
        head = f"new sequencer {self.number}"
        if self.carried:
            shown = ", ".join(f"S{n}" for n in self.carried)
            return f"{head}: active step {shown} goes on in it; its initial steps stay inactive"
        if not self.started:
            return f"{head}: it has no initial step; none of its steps becomes active"
        shown = ", ".join(f"S{n}" for n in self.started)
        if len(self.started) == 1:
            return f"{head}: its initial step {shown} becomes active"
        return f"{head}: its initial steps {shown} become active"


def new_sequencers(
    had: Collection[int] | None,
    old_steps: Collection[int],
    sequences: Iterable[tuple[int, tuple[int, ...], tuple[int, ...]]],
    active: Collection[int],
) -> list[NewSequencer]:
    """The sequencers of a new chart version that the running one, which had the sequencers
    numbered ``had`` (None: not known — a state saved before they were kept: then one none
    of whose steps it had), did not have. ``sequences``: (number, its step numbers, its
    initial step numbers) of the new version; ``active``: the step numbers active after the
    carry-over. The one rule of ``carry_over`` and of a download's preview."""
    out = []
    for number, steps, initial in sequences:
        new = number not in had if had is not None else not any(n in old_steps for n in steps)
        if new:
            carried = tuple(n for n in steps if n in active)
            out.append(NewSequencer(number, () if carried else tuple(initial), carried))
    return out


@dataclass(slots=True)
class CarryReport:
    """What ``carry_over`` kept and what it could not."""

    kept: list[int] = field(default_factory=list)
    """Numbers of the active steps that stay active."""
    gone: list[int] = field(default_factory=list)
    """Numbers of the active steps the new chart does not have (no longer active)."""
    faults_gone: list[int] = field(default_factory=list)
    """Steps with a latched supervision fault that no longer exist."""
    vars_reset: list[str] = field(default_factory=list)
    """Variables of a changed type (at their initial values); ``restarts`` says each so."""
    restarts: list[str] = field(default_factory=list)
    vars_dropped: list[str] = field(default_factory=list)
    vars_new: list[str] = field(default_factory=list)
    sequencers: list[NewSequencer] = field(default_factory=list)
    """The sequencers the old version did not have, and the steps that became active."""

    def lines(self) -> list[str]:
        """The report as the CLI prints it (and the diagnostic buffer records it)."""
        kept = ", ".join(f"S{n}" for n in self.kept) or "none"
        out = [f"chart changed; carried over by step number: active steps kept: {kept}"]
        if self.gone:
            out.append(
                "active steps gone (no longer active): " + ", ".join(f"S{n}" for n in self.gone)
            )
        if self.faults_gone:
            out.append(
                "latched supervision faults of steps gone: "
                + ", ".join(f"S{n}" for n in self.faults_gone)
            )
        out += self.restarts
        out += [q.line() for q in self.sequencers]
        if self.vars_dropped:
            out.append("variables no longer declared: " + ", ".join(self.vars_dropped))
        if self.vars_new:
            out.append("new variables, at their initial values: " + ", ".join(self.vars_new))
        return out


def carry_over(
    old: ChartShape, state: GraphState, new: CompiledChart
) -> tuple[GraphState, CarryReport]:
    """``state`` of the chart ``old`` describes, as a state of ``new`` (see the module
    docstring). Pure: ``state`` is not changed."""
    if state.n_steps != len(old.step_numbers) or state.n_transitions != len(old.transition_numbers):
        raise ValueError("the state does not fit the chart shape saved with it")
    report = CarryReport()
    st = new_state(new)
    _by_number(old.step_numbers, new.step_numbers, STEP_LISTS, state, st)
    for i, watched in enumerate(new.has_supervision):
        if not watched:  # its supervision removed: no cause left (a latched fault stays latched)
            st.sv_cond[i] = False
    for i in state.active:
        number = old.step_numbers[i]
        target = new.step_index.get(number)
        if target is None:
            report.gone.append(number)
        else:
            st.active.append(target)
            report.kept.append(number)
    for i, number in enumerate(old.step_numbers):
        if state.sv_err[i] and number not in new.step_index:
            report.faults_gone.append(number)
    _by_number(old.transition_numbers, new.transition_numbers, TRANSITION_LISTS, state, st)
    for name in _SCALARS:
        setattr(st, name, getattr(state, name))
    report.sequencers = _start_new_sequencers(old, new, st, report.kept)
    st.error = any(st.il_err[i] for i in st.active)
    st.fault = any(st.sv_err)
    st.err_flt = st.error or st.fault
    st.ov = False
    st.diag = list(state.diag)
    st.s_no = state.s_no if state.s_no in new.step_index else 0
    st.t_no = state.t_no if state.t_no in new.transition_index else 0
    for table in ("inputs", "outputs"):
        mine = getattr(st, table)
        for name, value in getattr(state, table).items():
            if name in mine:
                mine[name] = value
    st.prev = {k: v for k, v in state.prev.items() if k in st.inputs}
    declared = {v.name: v for v in new.chart.vars}
    for name, value in state.vars.items():
        if name not in new.var_types:
            report.vars_dropped.append(name)
        elif old.var_types.get(name) == new.var_types[name]:
            st.vars[name] = value
        else:
            report.vars_reset.append(name)
            was, now = old.var_types.get(name, "?"), new.var_types[name]
            start = initial_text(declared[name]) if name in declared else "?"
            report.restarts.append(restart_line(name, was, now, start))
    report.vars_new = sorted(set(new.var_types) - set(state.vars))
    st.display = _display(state.display, new)
    st.levels = dict(state.levels)
    return st, report


def _start_new_sequencers(
    old: ChartShape, new: CompiledChart, st: GraphState, kept: list[int]
) -> list[NewSequencer]:
    """Activate the initial steps of the sequencers ``old`` did not have in ``st`` (the
    state of ``new``), as the first call after a start activates them (times from 0, no
    error; their S1 event is the next call's: ``GraphFB.enter``); what was done."""
    numbers = new.step_numbers
    initial = set(new.initial)
    found = new_sequencers(
        old.sequences,
        set(old.step_numbers),
        [
            (q, tuple(numbers[i] for i in steps), tuple(numbers[i] for i in steps if i in initial))
            for q, steps in zip(new.seq_numbers, new.seq_steps, strict=True)
        ],
        set(kept),
    )
    for q in found:
        for n in q.started:
            i = new.step_index[n]
            if not st.x[i]:
                st.x[i] = True
                st.t_ns[i] = st.u_ns[i] = 0
                st.act_ns[i] = st.last_ns
                st.il_err[i] = st.sv_err[i] = False
                st.active.append(i)
    return found


def _by_number(
    old: tuple[int, ...],
    new: tuple[int, ...],
    fields: tuple[str, ...],
    source: GraphState,
    target: GraphState,
) -> None:
    """Copy the per-step (or per-transition) ``fields`` of ``source`` to ``target`` for every
    number both charts have (old index → new index)."""
    index = {n: i for i, n in enumerate(old)}
    for k, number in enumerate(new):
        i = index.get(number)
        if i is not None:
            for name in fields:
                getattr(target, name)[k] = getattr(source, name)[i]


def _display(display: dict[str, Any], new: CompiledChart) -> dict[str, Any]:
    """The display scratch, but for raised-message memories of steps that are gone."""
    out = dict(display)
    raised = display.get("msg")
    if isinstance(raised, dict):
        kept = {}
        for mid, event in raised.items():
            step = str(mid).rsplit("/", 2)[-2] if str(mid).count("/") >= 2 else ""
            if step[:1] == "S" and step[1:].isdigit() and int(step[1:]) in new.step_index:
                kept[mid] = event
        out["msg"] = kept
    return out


class ChartFormat:
    """The ``StateFormat`` of a GraphFB's instance DB: recognised by ``fingerprint(cc)``,
    carried over by ``carry_over`` (the STAT ``state_var`` holds the GraphState)."""

    def __init__(self, cc: CompiledChart, state_var: str) -> None:
        self.cc = cc
        self.state_var = state_var
        self._fingerprint = fingerprint(cc)
        self._shape = ChartShape.of(cc).to_json()

    @property
    def fingerprint(self) -> str:
        return self._fingerprint

    def shape(self) -> object:
        return self._shape

    def adapt(self, shape: object, data: dict[str, object]) -> tuple[dict[str, object], list[str]]:
        old = ChartShape.from_json(shape)
        raw = data.get(self.state_var)
        if not isinstance(raw, dict):
            raise ValueError(f"no {self.state_var} in the saved instance")
        state, report = carry_over(old, GraphState.from_state(raw), self.cc)
        names = {p for p in state.inputs} | {p for p in state.outputs}
        out: dict[str, object] = {k: v for k, v in data.items() if k in names}
        out[self.state_var] = state.to_state()
        return out, report.lines()
