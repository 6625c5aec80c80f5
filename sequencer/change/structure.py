"""Edits of how steps and transitions connect, as S7-GRAPH's editor makes them (STEP7
comprehensive guide vol. 2, ch. 14; docs/semantics.md, "Structure"):

- *Step + Transition* after a selected transition: the transition leads to a new step,
  and a new transition from it leads where the selected one led.
- *Alternative branch* at a selected step: a new transition leaving it, to the right of
  (after, so with a lower priority than) those that already leave it; its path ends in a
  branch stop, or at the step given (a jump or the join of the branch).
- *Simultaneous branch* at a selected transition: one more step below it; the new path
  ends in a transition with a branch stop, or joins the transition given.
- *Jump* and *branch stop* end the path after a selected transition.
- *Sequencer*: a new sequencer with one initial step and a transition back to it.
- Deleting a step takes its following transition with it (or, when that transition joins
  several paths, its preceding one), reconnecting the chart around them; deleting a
  transition, a branch or a sequencer is refused, naming why, when it would cut a path or
  leave a reference to what it removes.

New elements get the next free number (``base.next_number``) and S7-GRAPH's default
names ``Step<n>`` / ``Trans<n>``; their conditions are empty (they hold, W120).
"""

from __future__ import annotations

from collections.abc import Set as AbstractSet
from dataclasses import dataclass, replace

from s7graph.sequencer.change.base import (
    MAX_NAME,
    Edit,
    EditRefused,
    checked_text,
    entering,
    leaving,
    linked,
    new_step_number,
    new_transition_number,
    next_number,
    sequence_of,
    sequence_with_step,
    sequence_with_transition,
    step_of,
    transition_of,
    with_sequence,
    with_transitions,
)
from s7graph.sequencer.text.elements import (
    Ref,
    SequenceRef,
    StepRef,
    TransitionRef,
    label,
    references,
)
from s7graph.sequencer.text.model import Chart, Sequence, Step, StepTarget, Transition
from s7graph.sequencer.text.walk import nodes


def new_step(n: int, *, initial: bool = False) -> Step:
    return Step(n, f"Step{n}", initial=initial)


def new_transition(m: int, sources: tuple[int, ...], targets: tuple[int, ...]) -> Transition:
    return Transition(m, f"Trans{m}", sources, targets)


def _after(items: tuple[Step | Transition, ...], numbers: AbstractSet[int]) -> int:
    """The index just after the last of ``items`` numbered in ``numbers`` (else the end)."""
    where = [i for i, x in enumerate(items) if x.number in numbers]
    return where[-1] + 1 if where else len(items)


def _insert(
    q: Sequence,
    *,
    step: Step | None = None,
    after_steps: AbstractSet[int] = frozenset(),
    transition: Transition | None = None,
    after_transitions: AbstractSet[int] = frozenset(),
) -> Sequence:
    """``q`` with ``step`` placed after the last of ``after_steps`` and ``transition``
    after the last of ``after_transitions`` (at the end when none is in ``q``)."""
    steps, trans = q.steps, q.transitions
    if step is not None:
        i = _after(steps, after_steps)
        steps = (*steps[:i], step, *steps[i:])
    if transition is not None:
        j = _after(trans, after_transitions)
        trans = (*trans[:j], transition, *trans[j:])
    return replace(q, steps=steps, transitions=trans)


def _one_next_step(t: Transition, what: str) -> None:
    if len(t.targets) > 1:
        shown = ", ".join(f"S{n}" for n in t.targets)
        raise EditRefused(
            f"T{t.number} opens a simultaneous branch to {shown}; {what} ends a "
            "path with one next step: delete the other paths first"
        )


def _retarget(chart: Chart, t: Transition, targets: tuple[int, ...]) -> Chart:
    return with_transitions(chart, lambda x: linked(x, x.sources, targets) if x is t else x)


# ---------------------------------------------------------------- inserting


@dataclass(frozen=True, slots=True)
class InsertStep(Edit):
    """Insert a step and a transition after transition ``transition`` (Insert > Step +
    Transition): it leads to the new step, the new transition where it led."""

    transition: int

    def apply(self, chart: Chart) -> tuple[Chart, Ref | None]:
        t = transition_of(chart, self.transition)
        q = sequence_with_transition(chart, t.number)
        n, m = new_step_number(chart), new_transition_number(chart)
        into = tuple(linked(x, x.sources, (n,)) if x is t else x for x in q.transitions)
        q = replace(q, transitions=into)
        q = _insert(
            q,
            step=new_step(n),
            after_steps=set(t.sources),
            transition=new_transition(m, (n,), t.targets),
            after_transitions={t.number},
        )
        return with_sequence(chart, q), StepRef(n)


@dataclass(frozen=True, slots=True)
class InsertAlternativeBranch(Edit):
    """Open an alternative branch at step ``step``: a new transition leaving it with the
    lowest priority, leading to step ``to`` (a jump or join) or, None, to a branch stop."""

    step: int
    to: int | None = None

    def apply(self, chart: Chart) -> tuple[Chart, Ref | None]:
        step_of(chart, self.step)
        if self.to is not None:
            step_of(chart, self.to)
        q = sequence_with_step(chart, self.step)
        m = new_transition_number(chart)
        t = new_transition(m, (self.step,), () if self.to is None else (self.to,))
        out = {x.number for x in leaving(chart, self.step)}
        q = _insert(q, transition=t, after_transitions=out)
        return with_sequence(chart, q), TransitionRef(m)


@dataclass(frozen=True, slots=True)
class InsertSimultaneousBranch(Edit):
    """Open a simultaneous branch at transition ``transition``: it also activates a new
    step, whose path joins transition ``join`` or, None, ends in a new transition to a
    branch stop."""

    transition: int
    join: int | None = None

    def apply(self, chart: Chart) -> tuple[Chart, Ref | None]:
        t = transition_of(chart, self.transition)
        if not t.targets:
            raise EditRefused(
                f"T{t.number} ends in a branch stop; insert a step after it "
                "before opening a simultaneous branch there"
            )
        q = sequence_with_transition(chart, t.number)
        own = {st.number for st in q.steps}
        away = [n for n in t.targets if n not in own]
        if away:  # a branch across sequencers does not compile (E015)
            raise EditRefused(
                f"T{t.number} jumps to S{away[0]} of another sequencer; only a jump to one "
                "step reaches another sequencer, a simultaneous branch forks in its own"
            )
        if self.join is not None:
            j = transition_of(chart, self.join)
            if j.number == t.number:
                raise EditRefused(f"a branch cannot join at T{t.number}, which opens it")
            if all(x.number != j.number for x in q.transitions):
                raise EditRefused(f"T{j.number} is in another sequencer; a branch joins in its own")
        n = new_step_number(chart)

        def link(x: Transition) -> Transition:
            if x.number == t.number:
                return linked(x, x.sources, (*x.targets, n))
            if x.number == self.join:
                return linked(x, (*x.sources, n), x.targets)
            return x

        q = replace(q, transitions=tuple(link(x) for x in q.transitions))
        if self.join is None:
            m = new_transition_number(chart)
            q = _insert(
                q,
                step=new_step(n),
                after_steps=set(t.targets),
                transition=new_transition(m, (n,), ()),
                after_transitions={t.number},
            )
        else:
            q = _insert(q, step=new_step(n), after_steps=set(t.targets))
        return with_sequence(chart, q), StepRef(n)


@dataclass(frozen=True, slots=True)
class Jump(Edit):
    """End the path after transition ``transition`` with a jump to step ``to`` (of any
    sequencer of the FB, docs/semantics.md, "Structure")."""

    transition: int
    to: int

    def apply(self, chart: Chart) -> tuple[Chart, Ref | None]:
        t = transition_of(chart, self.transition)
        step_of(chart, self.to)
        _one_next_step(t, "a jump")
        return _retarget(chart, t, (self.to,)), TransitionRef(t.number)


@dataclass(frozen=True, slots=True)
class BranchStop(Edit):
    """End the path after transition ``transition`` with a branch stop (``TO STOP``)."""

    transition: int

    def apply(self, chart: Chart) -> tuple[Chart, Ref | None]:
        t = transition_of(chart, self.transition)
        _one_next_step(t, "a branch stop")
        return _retarget(chart, t, ()), TransitionRef(t.number)


@dataclass(frozen=True, slots=True)
class InsertSequence(Edit):
    """Add a sequencer named ``name``: one initial step and a transition back to it (the
    shape of a new GRAPH block, Insert > Sequencer)."""

    name: str = ""

    def apply(self, chart: Chart) -> tuple[Chart, Ref | None]:
        name = checked_text(self.name, "the name of the sequencer", MAX_NAME)
        k = next_number(q.number for q in chart.sequences)
        n, m = new_step_number(chart), new_transition_number(chart)
        q = Sequence(k, name, (new_step(n, initial=True),), (new_transition(m, (n,), (n,)),))
        return replace(chart, sequences=(*chart.sequences, q)), SequenceRef(k)


# ---------------------------------------------------------------- deleting


def _without(chart: Chart, steps: set[int], transitions: set[int]) -> Chart:
    return replace(
        chart,
        sequences=tuple(
            replace(
                q,
                steps=tuple(s for s in q.steps if s.number not in steps),
                transitions=tuple(t for t in q.transitions if t.number not in transitions),
            )
            for q in chart.sequences
        ),
    )


def _swap(numbers: tuple[int, ...], n: int, by: tuple[int, ...]) -> tuple[int, ...]:
    """``numbers`` with ``n`` replaced by ``by``, each number once, in order."""
    out: list[int] = []
    for x in numbers:
        for y in by if x == n else (x,):
            if y not in out:
                out.append(y)
    return tuple(out)


def _missing(chart: Chart) -> set[tuple[Ref, StepRef | TransitionRef]]:
    steps = {s.number for s in chart.all_steps()}
    trans = {t.number for t in chart.all_transitions()}
    return {
        (owner, named)
        for owner, named in references(chart)
        if (named.number not in steps if isinstance(named, StepRef) else named.number not in trans)
    }


def _kept_consistent(before: Chart, after: Chart, what: str) -> Chart:
    """``after``, unless it names a step or transition that is gone (and ``before`` did
    not already): then refuse, naming what still refers to it."""
    new = _missing(after) - _missing(before)
    if not new:
        return after
    by: dict[str, list[str]] = {}
    for owner, named in sorted(new, key=lambda p: (label(p[1]), label(p[0]))):
        name = f"S{named.number}" if isinstance(named, StepRef) else f"T{named.number}"
        by.setdefault(name, []).append(label(owner))
    used = "; ".join(f"{n} is used by {', '.join(owners)}" for n, owners in by.items())
    raise EditRefused(f"cannot delete {what}: {used}; change those first")


def _on_targets(chart: Chart) -> set[int]:
    return {
        x.step
        for s in chart.all_steps()
        for x in nodes(s.actions)
        if isinstance(x, StepTarget) and x.step is not None
    }


def _ways_lost(before: Chart, after: Chart) -> list[str]:
    """Steps of ``after`` that had a way in (or out) in ``before`` and have none now."""

    def ways(c: Chart) -> tuple[set[int], set[int]]:
        into = {n for t in c.all_transitions() for n in t.targets} | _on_targets(c)
        into |= {s.number for s in c.all_steps() if s.initial}
        return into, {n for t in c.all_transitions() for n in t.sources}

    (in0, out0), (in1, out1) = ways(before), ways(after)
    lost = []
    for s in after.all_steps():
        if s.number in in0 and s.number not in in1:
            lost.append(f"S{s.number} would have no way in")
        if s.number in out0 and s.number not in out1:
            lost.append(f"S{s.number} would have no way out")
    return lost


@dataclass(frozen=True, slots=True)
class DeleteStep(Edit):
    """Delete step ``step`` with its following transition, the transitions that led to it
    leading where that one led; a step before a join goes with its preceding transition
    instead, and a step without a way out alone."""

    step: int

    def apply(self, chart: Chart) -> tuple[Chart, Ref | None]:
        n = step_of(chart, self.step).number
        q = sequence_with_step(chart, n)
        if len(q.steps) == 1:
            raise EditRefused(
                f"S{n} is the only step of sequencer {q.number}; delete the sequencer instead"
            )
        outs, ins = leaving(chart, n), entering(chart, n)
        if len(outs) == 1 and outs[0].sources == (n,) and n not in outs[0].targets:
            gone, by = outs[0], outs[0].targets  # S7-GRAPH's step + transition pair

            def fix(x: Transition) -> Transition | None:
                if x.number == gone.number:
                    return None
                return linked(x, x.sources, _swap(x.targets, n, by))

        elif len(ins) == 1 and ins[0].targets == (n,) and n not in ins[0].sources:
            gone, by = ins[0], ins[0].sources  # the last step of a path into a join

            def fix(x: Transition) -> Transition | None:
                if x.number == gone.number:
                    return None
                return linked(x, _swap(x.sources, n, by), x.targets)

        elif not outs:
            gone = None

            def fix(x: Transition) -> Transition | None:
                return linked(x, x.sources, _swap(x.targets, n, ()))

        else:
            shown = ", ".join(f"T{t.number}" for t in (*ins, *outs))
            raise EditRefused(
                f"S{n} joins or opens several paths ({shown}); delete its branches first"
            )
        edited = with_transitions(_without(chart, {n}, set()), fix)
        what = f"S{n}" + (f" with T{gone.number}" if gone is not None else "")
        kept = [t.number for t in (*ins, *outs) if gone is None or t.number != gone.number]
        return _kept_consistent(chart, edited, what), TransitionRef(kept[0]) if kept else None


@dataclass(frozen=True, slots=True)
class DeleteTransition(Edit):
    """Delete transition ``transition`` — an alternative path without steps, a jump or a
    branch stop — when every step keeps a way in and out; else refuse saying which not."""

    transition: int

    def apply(self, chart: Chart) -> tuple[Chart, Ref | None]:
        t = transition_of(chart, self.transition)
        edited = _kept_consistent(chart, _without(chart, set(), {t.number}), f"T{t.number}")
        lost = _ways_lost(chart, edited)
        if lost:
            raise EditRefused(
                f"cannot delete T{t.number}: {'; '.join(lost)} (delete the step "
                "with its transition instead)"
            )
        return edited, StepRef(t.sources[0]) if t.sources else None


def _path_refused(what: str, why: str) -> EditRefused:
    return EditRefused(f"cannot delete the branch {what}: {why}; delete that first")


@dataclass(frozen=True, slots=True)
class DeleteAlternativeBranch(Edit):
    """Delete the alternative path that starts with transition ``transition``: it and the
    steps and transitions after it up to where the path ends (a branch stop, a jump, or
    the step where it joins another path)."""

    transition: int

    def apply(self, chart: Chart) -> tuple[Chart, Ref | None]:
        t = transition_of(chart, self.transition)
        what = f"at T{t.number}"
        if len(t.sources) != 1 or len(leaving(chart, t.sources[0])) < 2:
            raise EditRefused(
                f"T{t.number} does not open an alternative branch: its step has no other way out"
            )
        start, on = t.sources[0], _on_targets(chart)
        steps: set[int] = set()
        trans: set[int] = set()
        cur: Transition | None = t
        while cur is not None:
            trans.add(cur.number)
            if len(cur.targets) > 1:
                raise _path_refused(what, f"T{cur.number} opens a simultaneous branch")
            if not cur.targets:
                break
            n = cur.targets[0]
            s = step_of(chart, n)
            if n == start or n in steps or s.initial or n in on or len(entering(chart, n)) > 1:
                break  # the path jumps or joins here
            steps.add(n)
            outs = leaving(chart, n)
            if len(outs) > 1:
                raise _path_refused(what, f"S{n} opens an alternative branch")
            if outs and len(outs[0].sources) > 1:
                raise _path_refused(
                    what, f"S{n} is in a simultaneous branch joined at T{outs[0].number}"
                )
            cur = outs[0] if outs else None
        edited = _kept_consistent(chart, _without(chart, steps, trans), f"the branch {what}")
        return edited, StepRef(start)


@dataclass(frozen=True, slots=True)
class DeleteSimultaneousBranch(Edit):
    """Delete the simultaneous path that starts with step ``step``: it and the steps and
    transitions after it up to the join (which then waits for one path fewer), a branch
    stop or a jump."""

    step: int

    def apply(self, chart: Chart) -> tuple[Chart, Ref | None]:
        n = step_of(chart, self.step).number
        what = f"at S{n}"
        opens = [t for t in entering(chart, n) if len(t.targets) > 1]
        if len(opens) != 1 or len(entering(chart, n)) != 1:
            raise EditRefused(
                f"S{n} does not start a simultaneous branch: no single transition "
                "activates it together with other steps"
            )
        on = _on_targets(chart)
        steps: set[int] = set()
        trans: set[int] = set()
        join: Transition | None = None
        cur: int | None = n
        while cur is not None:
            steps.add(cur)
            outs = leaving(chart, cur)
            if len(outs) > 1:
                raise _path_refused(what, f"S{cur} opens an alternative branch")
            if not outs:
                break
            o = outs[0]
            if len(o.sources) > 1:
                join = o
                break
            trans.add(o.number)
            if len(o.targets) > 1:
                raise _path_refused(what, f"T{o.number} opens a simultaneous branch")
            nxt = o.targets[0] if o.targets else None
            if (
                nxt is None
                or nxt in steps
                or nxt in on
                or len(entering(chart, nxt)) > 1
                or (step_of(chart, nxt).initial)
            ):
                break  # a branch stop, or a jump out of the path
            cur = nxt
        last = cur

        def fix(x: Transition) -> Transition:
            if x is opens[0]:
                return linked(x, x.sources, tuple(k for k in x.targets if k != n))
            if x is join:
                return linked(x, tuple(k for k in x.sources if k != last), x.targets)
            return x

        edited = with_transitions(_without(chart, steps, trans), fix)
        edited = _kept_consistent(chart, edited, f"the branch {what}")
        return edited, TransitionRef(opens[0].number)


@dataclass(frozen=True, slots=True)
class DeleteSequence(Edit):
    """Delete sequencer ``sequence`` with its steps and transitions (refused for the only
    one, or while other sequencers jump into it or name its steps)."""

    sequence: int

    def apply(self, chart: Chart) -> tuple[Chart, Ref | None]:
        q = sequence_of(chart, self.sequence)
        if len(chart.sequences) == 1:
            raise EditRefused(f"sequencer {q.number} is the only one; a GRAPH FB has at least one")
        edited = replace(chart, sequences=tuple(x for x in chart.sequences if x is not q))
        return _kept_consistent(chart, edited, f"sequencer {q.number}"), None
