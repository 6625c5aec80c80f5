"""What a download changes: the running chart against the edited one (online
change, docs/online-change.md).

``summarize(running, edited, active)`` lists every change — the block, its options,
sequencers, steps, transitions, action rows, interlocks, supervisions, conditions,
variables, symbols, permanent instructions — added, removed or changed, as data and as
one readable line each. Steps and transitions are matched by number, since the CPU carries
its state over by step number: a renumbered step is one removed and one added. Places and
comments are ignored (a chart read again from its text compares equal). Given the active
steps of the running state, it also says which of them the edited chart removes (the user
chooses: keep the other steps, or initialize the sequencer) and which operands ``S`` rows
of removed steps or removed ``S`` rows may have set and nothing then resets (they stay
set).
"""

from __future__ import annotations

from collections.abc import Collection, Iterable
from dataclasses import dataclass, fields
from difflib import SequenceMatcher
from typing import Literal

from s7graph.sequencer.change.carry import initial_text, new_sequencers, restart_line
from s7graph.sequencer.compiled import CompiledChart
from s7graph.sequencer.state import GraphState
from s7graph.sequencer.text.elements import (
    DeclRef,
    Ref,
    RowRef,
    SequenceRef,
    StepRef,
    TransitionRef,
    label,
)
from s7graph.sequencer.text.model import (
    ActionRow,
    Assignment,
    BlockCall,
    Chart,
    Coil,
    Const,
    Operand,
    Step,
    StepTarget,
    Transition,
    VarDecl,
)
from s7graph.sequencer.text.walk import uncommented, unlocated
from s7graph.steps.conditions import contact_text

ChangeKind = Literal["added", "removed", "changed"]


@dataclass(frozen=True, slots=True)
class Change:
    """One change. ``element`` is keyed by number (the edited chart's for added and changed
    elements, the running chart's for removed ones; None for the block and its options);
    ``what`` names the part (``step``, ``row``, ``condition``, ``option SKIP_STEPS`` ...);
    ``before`` / ``after`` are the model values (None when absent)."""

    kind: ChangeKind
    element: Ref | None
    what: str
    text: str
    before: object = None
    after: object = None


@dataclass(frozen=True, slots=True)
class StaysSet:
    """An operand an ``S`` row of the running chart sets, gone from the edited chart (with
    its step, or the row alone): it keeps its value; ``reset_by`` lists the ``R`` rows and
    permanent ``R`` / ``=`` coils of the edited chart that write it (none: it stays set)."""

    operand: str
    step: int
    reset_by: tuple[Ref, ...]


@dataclass(frozen=True, slots=True)
class ChangeSummary:
    changes: tuple[Change, ...]
    removed_active: tuple[int, ...]
    stays_set: tuple[StaysSet, ...]

    @property
    def unchanged(self) -> bool:
        return not self.changes

    def lines(self) -> tuple[str, ...]:
        """The summary as the download dialog lists it, one line a change."""
        out = [c.text for c in self.changes]
        out += [removal_line(n) for n in self.removed_active]
        for s in self.stays_set:
            by = ", ".join(label(r) for r in s.reset_by)
            tail = f"reset by {by}" if by else "nothing in the edited chart resets it"
            out.append(f"{s.operand}, set by an S row of S{s.step}, may stay set: {tail}")
        return tuple(out)


def removal_line(step: int) -> str:
    """The line of a summary for active step ``step`` the change removes (the choice is the
    sender's: a download made says what it did instead, ``SwapReport``)."""
    return (
        f"S{step} is active and would be removed: keep the other steps, or initialize the sequencer"
    )


# ---------------------------------------------------------------- readable values


def _operand(op: object) -> str:
    if isinstance(op, Operand | Const):
        return contact_text(op)
    if isinstance(op, StepTarget):
        return "S_ALL" if op.step is None else f"S{op.step}"
    if isinstance(op, Assignment):
        return f"{contact_text(op.target)} := ..."
    if isinstance(op, BlockCall):
        return f"{op.kind} {op.block}".strip()
    return "..."


def row_text(r: ActionRow) -> str:
    """A short text of an action row (``S1 S "Clamp"``; expressions shown as ``...``)."""
    parts = [r.event or "", r.qualifier + ("C" if r.interlocked else ""), _operand(r.operand)]
    text = " ".join(p for p in parts if p)
    return f"{text}, {_operand(r.value)}" if r.value is not None else text


def _steps(numbers: Iterable[int]) -> str:
    shown = ", ".join(f"S{n}" for n in numbers)
    return shown or "STOP"


def _named(n: str, name: str) -> str:
    return f'{n} "{name}"' if name else n


def _bool(v: object) -> str:
    return ("TRUE" if v else "FALSE") if isinstance(v, bool) else str(v).upper()


# ---------------------------------------------------------------- comparing


class _Diff:
    def __init__(self) -> None:
        self.changes: list[Change] = []

    def add(
        self,
        kind: ChangeKind,
        ref: Ref | None,
        what: str,
        text: str,
        before: object = None,
        after: object = None,
    ) -> None:
        self.changes.append(Change(kind, ref, what, text, before, after))

    def part(self, ref: Ref, who: str, what: str, old: object, new: object) -> None:
        """An optional part (interlock, supervision, condition): added, removed, changed."""
        if old == new:
            return
        kind: ChangeKind = "added" if old is None else "removed" if new is None else "changed"
        self.add(kind, ref, what, f"{who}: {what} {kind}", old, new)

    def header(self, a: Chart, b: Chart) -> None:
        for what, x, y in (
            ("name", a.name, b.name),
            ("FB", a.fb_number, b.fb_number),
            ("DB", a.db_number, b.db_number),
        ):
            if x != y:
                self.add("changed", None, f"block {what}", f"block {what}: {x} → {y}", x, y)
        for f in fields(a.options):
            x, y = getattr(a.options, f.name), getattr(b.options, f.name)
            if x != y:
                key = f.name.upper()
                self.add(
                    "changed", None, f"option {key}", f"option {key}: {_bool(x)} → {_bool(y)}", x, y
                )

    def sequences(self, a: Chart, b: Chart, active: Collection[int]) -> None:
        """Sequencers added (saying which of their steps become active at the swap, by the
        carry-over's rule: ``carry.new_sequencers``), removed or renamed; ``active``: the
        step numbers active after the swap."""
        old = {q.number: q for q in a.sequences}
        new = {q.number: q for q in b.sequences}
        added = new_sequencers(
            old.keys(),
            {s.number for s in a.all_steps()},
            [
                (
                    q.number,
                    tuple(s.number for s in q.steps),
                    tuple(s.number for s in q.steps if s.initial),
                )
                for q in b.sequences
                if q.number not in old
            ],
            active,
        )
        said = {q.number: q.line() for q in added}
        for n in sorted(old.keys() | new.keys()):
            ref = SequenceRef(n)
            x, y = old.get(n), new.get(n)
            if x is None and y is not None:
                self.add("added", ref, "sequencer", said[n], None, y)
            elif y is None and x is not None:
                self.add("removed", ref, "sequencer", f"sequencer {n} removed", x, None)
            elif x is not None and y is not None and x.name != y.name:
                self.add(
                    "changed",
                    ref,
                    "name",
                    f'sequencer {n}: name "{x.name}" → "{y.name}"',
                    x.name,
                    y.name,
                )

    def steps(self, a: Chart, b: Chart) -> None:
        seq_a = {s.number: q.number for q in a.sequences for s in q.steps}
        seq_b = {s.number: q.number for q in b.sequences for s in q.steps}
        old = {s.number: s for s in a.all_steps()}
        new = {s.number: s for s in b.all_steps()}
        for n in sorted(old.keys() | new.keys()):
            x, y = old.get(n), new.get(n)
            if x is None and y is not None:
                self.add("added", StepRef(n), "step", f"{_named(f'S{n}', y.name)} added", None, y)
            elif y is None and x is not None:
                self.add(
                    "removed", StepRef(n), "step", f"{_named(f'S{n}', x.name)} removed", x, None
                )
            elif x is not None and y is not None and x != y:
                self.step(x, y)
            if n in seq_a and n in seq_b and seq_a[n] != seq_b[n]:
                self.add(
                    "changed",
                    StepRef(n),
                    "sequencer",
                    f"S{n}: moved to sequencer {seq_b[n]}",
                    seq_a[n],
                    seq_b[n],
                )
        for n in sorted(old.keys() & new.keys()):
            order_a = [t.number for t in a.all_transitions() if n in t.sources]
            order_b = [t.number for t in b.all_transitions() if n in t.sources]
            kept_a = [m for m in order_a if m in order_b]
            kept_b = [m for m in order_b if m in order_a]
            if kept_a != kept_b:
                shown = [", ".join(f"T{m}" for m in o) for o in (kept_a, kept_b)]
                self.add(
                    "changed",
                    StepRef(n),
                    "priority",
                    f"S{n}: priority of the transitions leaving it {shown[0]} → {shown[1]}",
                    tuple(kept_a),
                    tuple(kept_b),
                )

    def step(self, x: Step, y: Step) -> None:
        n, who = x.number, f"S{x.number}"
        ref = StepRef(n)
        if x.name != y.name:
            self.add("changed", ref, "name", f'{who}: name "{x.name}" → "{y.name}"', x.name, y.name)
        if x.initial != y.initial:
            text = f"{who}: {'now' if y.initial else 'no longer'} an initial step"
            self.add("changed", ref, "initial", text, x.initial, y.initial)
        if x.message != y.message:
            self.add(
                "changed", ref, "message", f"{who}: message text changed", x.message, y.message
            )
        self.part(StepRef(n, "interlock"), who, "interlock", x.interlock, y.interlock)
        self.part(StepRef(n, "supervision"), who, "supervision", x.supervision, y.supervision)
        matcher = SequenceMatcher(a=x.actions, b=y.actions, autojunk=False)
        for op, i1, i2, j1, j2 in matcher.get_opcodes():
            if op == "equal":
                continue
            pairs = min(i2 - i1, j2 - j1) if op == "replace" else 0
            for k in range(pairs):
                self.row("changed", n, j1 + k, x.actions[i1 + k], y.actions[j1 + k])
            for i in range(i1 + pairs, i2):
                self.row("removed", n, i, x.actions[i], None)
            for j in range(j1 + pairs, j2):
                self.row("added", n, j, None, y.actions[j])

    def row(
        self, kind: ChangeKind, n: int, i: int, old: ActionRow | None, new: ActionRow | None
    ) -> None:
        """Row ``i`` of ``Sn`` (the running chart's index when removed, else the edited's)."""
        shown = " → ".join(row_text(r) for r in (old, new) if r is not None)
        self.add(kind, RowRef(n, i), "row", f"S{n}: row {i + 1} {kind}: {shown}", old, new)

    def transitions(self, a: Chart, b: Chart) -> None:
        old = {t.number: t for t in a.all_transitions()}
        new = {t.number: t for t in b.all_transitions()}
        for n in sorted(old.keys() | new.keys()):
            x, y = old.get(n), new.get(n)
            ref = TransitionRef(n)
            if x is None and y is not None:
                self.add(
                    "added",
                    ref,
                    "transition",
                    f"{_named(f'T{n}', y.name)} added ({_steps(y.sources)} → {_steps(y.targets)})",
                    None,
                    y,
                )
            elif y is None and x is not None:
                self.add(
                    "removed", ref, "transition", f"{_named(f'T{n}', x.name)} removed", x, None
                )
            elif x is not None and y is not None and x != y:
                self.transition(x, y)

    def transition(self, x: Transition, y: Transition) -> None:
        ref, who = TransitionRef(x.number), f"T{x.number}"
        if x.name != y.name:
            self.add("changed", ref, "name", f'{who}: name "{x.name}" → "{y.name}"', x.name, y.name)
        for what, p, q in (("FROM", x.sources, y.sources), ("TO", x.targets, y.targets)):
            if p != q:
                self.add("changed", ref, what, f"{who}: {what} {_steps(p)} → {_steps(q)}", p, q)
        self.part(ref, who, "condition", x.condition, y.condition)

    def declarations(self, a: Chart, b: Chart) -> None:
        for kind, xs, ys, key in (
            ("variable", a.vars, b.vars, str.upper),
            ("symbol", a.symbols, b.symbols, str.casefold),
        ):
            old = {key(v.name): v for v in xs}
            new = {key(v.name): v for v in ys}
            for k in sorted(old.keys() | new.keys()):
                x, y = old.get(k), new.get(k)
                v = y if y is not None else x
                assert v is not None
                ref = DeclRef(kind, v.name)  # type: ignore[arg-type]
                shown = f'"{v.name}"' if kind == "symbol" else v.name
                kind_: ChangeKind = "added" if x is None else "removed" if y is None else "changed"
                if x != y:
                    text = f"{kind} {shown} {kind_}"
                    if isinstance(x, VarDecl) and isinstance(y, VarDecl):
                        text = _variable_change(x, y) or text
                    self.add(kind_, ref, kind, text, x, y)
        for place, p, q in (("before", a.before, b.before), ("after", a.after, b.after)):
            if p != q:
                self.add(
                    "changed",
                    DeclRef("permanent", place),
                    "permanent",
                    f"permanent instructions {place} changed",
                    x,
                    y,
                )


def _variable_change(x: VarDecl, y: VarDecl) -> str | None:
    """The line of a variable whose value the carry-over does not keep (``carry_over``: by
    its exact name and declared type): it restarts at its initial value."""
    start = initial_text(y)
    if x.name != y.name:
        return f"variable {x.name} → {y.name}: restarts at its initial value {start}"
    before, after = x.type.upper(), y.type.upper()
    return restart_line(y.name, before, after, start) if before != after else None


def _key(op: Operand) -> tuple[str, bool]:
    return (op.name if op.quoted else op.name.upper(), op.quoted)


def _s_operands(s: Step) -> list[Operand]:
    return [r.operand for r in s.actions if r.qualifier == "S" and isinstance(r.operand, Operand)]


def _stays_set(a: Chart, b: Chart) -> tuple[StaysSet, ...]:
    kept = {s.number: s for s in b.all_steps()}
    resets: dict[tuple[str, bool], list[Ref]] = {}
    for s in b.all_steps():
        for i, r in enumerate(s.actions):
            if r.qualifier == "R" and isinstance(r.operand, Operand):
                resets.setdefault(_key(r.operand), []).append(RowRef(s.number, i))
    for place, items in (("before", b.before), ("after", b.after)):
        for it in items:
            if isinstance(it, Coil) and it.kind in ("R", "="):
                resets.setdefault(_key(it.target), []).append(DeclRef("permanent", place))
    out: list[StaysSet] = []
    for s in a.all_steps():
        still = [_key(o) for o in _s_operands(kept[s.number])] if s.number in kept else []
        for op in _s_operands(s):
            k = _key(op)
            if k in still:
                still.remove(k)
                continue
            by = tuple(dict.fromkeys(resets.get(k, ())))
            out.append(StaysSet(contact_text(op), s.number, by))
    return tuple(out)


def summarize(running: Chart, edited: Chart, active: Iterable[int] = ()) -> ChangeSummary:
    """What a download of ``edited`` over ``running`` changes; ``active`` are the step
    numbers active in the running state (``active_steps``)."""
    active = tuple(active)
    a, b = uncommented(unlocated(running)), uncommented(unlocated(edited))
    d = _Diff()
    d.header(a, b)
    kept = {s.number for s in b.all_steps()}
    d.sequences(a, b, {n for n in active if n in kept})
    d.steps(a, b)
    d.transitions(a, b)
    d.declarations(a, b)
    had = {s.number for s in a.all_steps()}
    removed = tuple(sorted({n for n in active if n in had and n not in kept}))
    return ChangeSummary(tuple(d.changes), removed, _stays_set(a, b))


def active_steps(compiled: CompiledChart, state: GraphState) -> tuple[int, ...]:
    """The numbers of the steps active in ``state`` of ``compiled``."""
    return tuple(n for n, x in zip(compiled.step_numbers, state.x, strict=True) if x)
