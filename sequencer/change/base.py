"""What every edit of a chart shares: the refusal, the editor's limits, new numbers and
the surgery that replaces one step, transition or sequencer in an immutable chart.

An edit (``Edit``) is data — the element it names and the new values — and ``apply``
gives the edited chart and the element to select next, or raises ``EditRefused`` naming
the problem. The operations themselves live in ``sequencer.change.content`` (what a step,
transition or row holds) and ``sequencer.change.structure`` (inserting and deleting); the
table of them and the editing session in ``sequencer.change.edit``.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterable
from dataclasses import dataclass, replace
from typing import Final

from s7graph.engine.errors import S7Error
from s7graph.sequencer.checks.diagnostics import Diagnostic
from s7graph.sequencer.text.elements import Ref
from s7graph.sequencer.text.model import Chart, Sequence, Step, Transition

# ---------------------------------------------------------------- limits (docs/online-change.md)
# S7-GRAPH's own limits (docs/semantics.md, "Structure": 250 steps, 250 transitions, 8 sequencers)
# only warn
# (W110); the editor refuses beyond four times them, so that every edit and its validation
# stay in milliseconds and a hostile chart or paste cannot exhaust the view or the CPU.
MAX_STEPS: Final = 1_000
MAX_TRANSITIONS: Final = 1_000
MAX_SEQUENCES: Final = 32
MAX_ROWS: Final = 256  # action rows of one step
MAX_NUMBER: Final = 32_767  # step / transition / sequencer numbers: S_NO and S_SEL are INT
MAX_TEXT: Final = 10_000  # characters of one condition or action row (32 elements fit 30x)
MAX_NAME: Final = 128  # characters of a step, transition or sequencer name
MAX_MESSAGE: Final = 1_024  # characters of a step's message text
MAX_SOURCE: Final = 1_000_000  # characters of a whole chart given as text (source view)
MAX_DEPTH: Final = 100  # nesting of one condition or row (parentheses, operators)
MAX_UNDO: Final = 100  # edits kept for undo


class EditRefused(S7Error):
    """An edit that cannot be made: ``reason`` says why in one line; ``diagnostics`` are the
    syntax errors of a text it was given, located in that text."""

    def __init__(self, reason: str, diagnostics: Iterable[Diagnostic] = ()) -> None:
        self.reason = reason
        self.diagnostics = tuple(diagnostics)
        super().__init__(reason)


@dataclass(frozen=True, slots=True)
class Refusal:
    """Why an edit was not made (the chart stays as it was)."""

    reason: str
    diagnostics: tuple[Diagnostic, ...] = ()


class Edit:
    """One edit operation (a frozen dataclass per kind, listed in ``edit.OPERATIONS``)."""

    __slots__ = ()

    def apply(self, chart: Chart) -> tuple[Chart, Ref | None]:
        """The edited chart and the element to select, or raise ``EditRefused``."""
        raise NotImplementedError


# ---------------------------------------------------------------- texts

_CONTROL = re.compile(r"[\x00-\x1f\x7f]")


def checked_text(text: object, what: str, limit: int) -> str:
    """``text`` if it is a one-line string of at most ``limit`` characters (a ``.s7g``
    string holds no line break), else refuse naming ``what``."""
    if not isinstance(text, str):
        raise EditRefused(f"{what} must be text, not {type(text).__name__}")
    if len(text) > limit:
        raise EditRefused(f"{what} has {len(text):,} characters; at most {limit:,} are accepted")
    if _CONTROL.search(text):
        raise EditRefused(f"{what} holds a line break or control character")
    return text


def checked_number(n: object, what: str) -> int:
    if not isinstance(n, int) or isinstance(n, bool):
        raise EditRefused(f"{what} must be a whole number, not {type(n).__name__}")
    if not 1 <= n <= MAX_NUMBER:
        raise EditRefused(f"{what} {n} is out of range 1..{MAX_NUMBER}")
    return n


# ---------------------------------------------------------------- numbers


def next_number(used: Iterable[int]) -> int:
    """The number S7-GRAPH gives a new step, transition or sequencer: the next one after
    the highest in use (S7-GRAPH numbers steps and transitions itself and lets the user
    change the numbers, STEP7 comprehensive guide vol. 2, ch. 14); past ``MAX_NUMBER``, the lowest
    free one."""
    taken = set(used)
    top = max(taken, default=0) + 1
    if top <= MAX_NUMBER:
        return top
    free = next((n for n in range(1, MAX_NUMBER + 1) if n not in taken), None)
    if free is None:
        raise EditRefused(f"every number 1..{MAX_NUMBER} is in use")
    return free


def new_step_number(chart: Chart) -> int:
    return next_number(s.number for s in chart.all_steps())


def new_transition_number(chart: Chart) -> int:
    return next_number(t.number for t in chart.all_transitions())


# ---------------------------------------------------------------- lookup


def step_of(chart: Chart, n: int) -> Step:
    for s in chart.all_steps():
        if s.number == n:
            return s
    raise EditRefused(f"there is no step S{n}")


def transition_of(chart: Chart, n: int) -> Transition:
    for t in chart.all_transitions():
        if t.number == n:
            return t
    raise EditRefused(f"there is no transition T{n}")


def sequence_of(chart: Chart, n: int) -> Sequence:
    for q in chart.sequences:
        if q.number == n:
            return q
    raise EditRefused(f"there is no sequencer {n}")


def sequence_with_step(chart: Chart, n: int) -> Sequence:
    step_of(chart, n)
    return next(q for q in chart.sequences if any(s.number == n for s in q.steps))


def sequence_with_transition(chart: Chart, n: int) -> Sequence:
    transition_of(chart, n)
    return next(q for q in chart.sequences if any(t.number == n for t in q.transitions))


def leaving(chart: Chart, n: int) -> tuple[Transition, ...]:
    """The transitions leaving step ``Sn``, in priority (written) order."""
    return tuple(t for t in chart.all_transitions() if n in t.sources)


def entering(chart: Chart, n: int) -> tuple[Transition, ...]:
    return tuple(t for t in chart.all_transitions() if n in t.targets)


# ---------------------------------------------------------------- surgery


def with_sequence(chart: Chart, seq: Sequence) -> Chart:
    """``chart`` with the sequencer of ``seq``'s number replaced by ``seq``."""
    return replace(
        chart, sequences=tuple(seq if q.number == seq.number else q for q in chart.sequences)
    )


def with_step(chart: Chart, step: Step) -> Chart:
    """``chart`` with the step of ``step``'s number replaced by ``step``."""
    q = sequence_with_step(chart, step.number)
    steps = tuple(step if s.number == step.number else s for s in q.steps)
    return with_sequence(chart, replace(q, steps=steps))


def with_transition(chart: Chart, t: Transition) -> Chart:
    q = sequence_with_transition(chart, t.number)
    trans = tuple(t if x.number == t.number else x for x in q.transitions)
    return with_sequence(chart, replace(q, transitions=trans))


def with_transitions(chart: Chart, fn: Callable[[Transition], Transition | None]) -> Chart:
    """``chart`` with every transition passed through ``fn`` (None drops it)."""
    sequences = []
    for q in chart.sequences:
        kept = tuple(x for x in (fn(t) for t in q.transitions) if x is not None)
        same = len(kept) == len(q.transitions) and all(
            a is b for a, b in zip(kept, q.transitions, strict=True)
        )
        sequences.append(q if same else replace(q, transitions=kept))
    return replace(chart, sequences=tuple(sequences))


def linked(t: Transition, sources: tuple[int, ...], targets: tuple[int, ...]) -> Transition:
    """``t`` leading from ``sources`` to ``targets`` (their written places forgotten when
    they change: a place belongs to the text the transition was read from)."""
    if sources == t.sources and targets == t.targets:
        return t
    return replace(
        t,
        sources=sources,
        targets=targets,
        source_locs=t.source_locs if sources == t.sources else (),
        target_locs=t.target_locs if targets == t.targets else (),
    )
