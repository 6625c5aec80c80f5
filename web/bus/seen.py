"""What the last update of a live GraphFB saw, for :meth:`~web.bus.live.LiveGraph.changed`
to tell at little cost whether the FB may have changed since.

A view sees of an FB: its active, disturbed and latched steps and its step events (every
switch, disturbance and acknowledgement raises an event into the scan record, which the
LiveGraph asks first), its mode and level pins, its output pins and watched operands, and
per active step the details — T and U to the whole second (``StepStateUpdate.changed_from``
compares them so), the TT and CRIT of its valid transitions, its interlock and supervision
words. :class:`Seen` keeps copies of those made with no bytecode per step (the CRIT list
whole, the interlock and supervision lists only for a chart that has them, the TT bits of
the transitions leaving the active steps — a transition that fired clears its TT in the
next scan, which no view sees — picked by one getter per set of active steps, made once,
:class:`Leaving`), and the T and U of the active steps, from which :func:`due_ns` gives the
clock time at which the first of them may reach a new whole second: T and U grow at most as
fast as the FB's clock (``GraphState.last_ns``). :func:`same` says whether the state still
matches; if not, the LiveGraph builds the update, and the bus publisher's whole-state
compare decides.
"""

from __future__ import annotations

import operator
from collections.abc import Callable, Sequence
from typing import Any, NamedTuple

__all__ = ["SECOND_NS", "Leaving", "Seen", "due_ns", "same", "seen"]

SECOND_NS = 1_000_000_000
_PART = SECOND_NS.__rmod__  # the part of a second of a time in ns
_new = tuple.__new__


class Seen(NamedTuple):
    """A copy of what a view sees of a GraphFB's state ``st`` (see the module docstring)."""

    st: Any
    last_ns: int
    times: list[int]
    active: list[int]
    pick: Callable[[list[bool]], Any] | None  # the TT bits of the transitions leaving them
    tt: Any
    crit: list[int]
    flags: tuple[Any, ...]
    checks: tuple[list[Any], ...] | None
    outs: tuple[Any, ...]
    watched: tuple[tuple[str, object], ...]


_MAX_PICKS = 256  # getters a Leaving keeps (sets of active steps seen)


class Leaving:
    """Per set of active steps, a getter of the TT bits of the transitions leaving them
    (None: none leaves them); ``leaving[i]`` are the transitions leaving step ``i``
    (``CompiledChart.leaving``). A getter is made once per set and kept."""

    __slots__ = ("_leaving", "_made")

    def __init__(self, leaving: Sequence[Sequence[int]]) -> None:
        self._leaving = leaving
        self._made: dict[tuple[int, ...], Callable[[list[bool]], Any] | None] = {}

    def __call__(self, active: list[int]) -> Callable[[list[bool]], Any] | None:
        key = tuple(active)
        made = self._made
        if key in made:
            return made[key]
        leaving = self._leaving
        js = sorted({j for i in key for j in leaving[i]})
        pick = operator.itemgetter(*js) if js else None
        if len(made) >= _MAX_PICKS:
            made.clear()
        made[key] = pick
        return pick


def seen(
    st: Any,
    checks: bool,
    outs: tuple[Any, ...],
    watched: tuple[tuple[str, object], ...],
    leaving: Leaving,
) -> Seen:
    """What a view sees of ``st`` now, given its output pins' values ``outs`` and the
    watched operands ``watched``; ``checks``: the chart has interlocks or supervisions;
    ``leaving``: the chart's :class:`Leaving`."""
    active = st.active
    levels = st.levels
    pick = leaving(active)
    return _new(  # a Seen without its Python __new__
        Seen,
        (
            st,
            st.last_ns,
            [*map(st.t_ns.__getitem__, active), *map(st.u_ns.__getitem__, active)],
            active[:],
            pick,
            pick(st.tt) if pick is not None else None,
            st.crit[:],
            (
                st.mode,
                st.halted,
                st.il_enabled,
                st.sv_enabled,
                st.ackreq_enabled,
                dict(levels) if levels else None,
            ),
            _checks(st) if checks else None,
            outs,
            watched,
        ),
    )


def due_ns(s: Seen) -> int:
    """The clock time at which an active step's T or U may have reached a new whole second."""
    return s.last_ns + SECOND_NS - max(map(_PART, s.times), default=0)


def same(s: Seen, st: Any, due: int) -> bool:
    """Whether ``st`` still shows what ``s`` saw (the output pins and watched operands aside),
    its clock before ``due`` (:func:`due_ns`)."""
    return (
        st is s.st
        and s.last_ns <= st.last_ns < due
        and st.active == s.active
        and st.crit == s.crit
        and (s.pick is None or s.pick(st.tt) == s.tt)
        and (st.mode, st.halted, st.il_enabled, st.sv_enabled, st.ackreq_enabled, st.levels or None)
        == s.flags
        and (
            s.checks is None
            or (st.il_ok, st.il_err, st.sv_err, st.crit_loc, st.crit_sup) == s.checks
        )
    )


def _checks(st: Any) -> tuple[list[Any], ...]:
    return (st.il_ok[:], st.il_err[:], st.sv_err[:], st.crit_loc[:], st.crit_sup[:])
