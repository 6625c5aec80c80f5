"""The step details of a live GraphFB: a :class:`StepDetail` per active step, built only for
the steps whose state changed since the last scan.

A step's detail is a function of a few numbers of its ``GraphState``: its times to 0.1 s,
its interlock and supervision bits and CRIT words, and TT and CRIT of each valid leaving
transition. :class:`StepDetails` computes that key for every active step after each scan
and builds a detail only when the key differs from the one its last detail was built
from; an unchanged step keeps the very same (immutable) :class:`StepDetail`, so comparing
two scans' details costs an identity test per step. The contact lists of a detail are
shared as well, by (condition, CRIT word): a step entered again reuses what it showed the
last time its transitions stood that way.
"""

from __future__ import annotations

from typing import Any

from s7graph.sequencer.compiled import CompiledChart
from s7graph.sequencer.display import contact_bits
from s7graph.web.bus.protocol import Contact, StepDetail, TransitionCriteria

__all__ = ["StepDetails", "contacts"]

TENTH_NS = 100_000_000  # step times go out to 0.1 s
PER_STEP = 4  # details kept per step, by the state they show (then forgotten)
MAX_SHARED = 4096  # contact lists and transition criteria kept for reuse (then forgotten)

Negations = tuple[tuple[bool, ...], ...]


def contacts(labels: tuple[str, ...], word: int, negated: tuple[bool, ...]) -> list[Contact]:
    """Each contact as the operator reads it: ``NOT x`` for a negated one, ``ok`` when it
    lets the condition through (the CRIT bit is the operand's value)."""
    return [
        Contact(text=f"NOT {text}"[:4096] if neg else text[:4096], ok=value != neg)
        for (text, value), neg in zip(contact_bits(labels, int(word)), negated, strict=True)
    ]


class StepDetails:
    """The details of chart ``cc``'s active steps, scan after scan (one per chart version).

    ``tr_neg``/``il_neg``/``sv_neg``: which contacts of each transition condition, interlock
    and supervision are negated; ``checks``: whether a step has an interlock or a
    supervision (without, a step's key leaves out their bits and words, which never
    change). ``built`` counts the details built so far."""

    def __init__(
        self,
        cc: CompiledChart,
        tr_neg: Negations,
        il_neg: Negations,
        sv_neg: Negations,
        *,
        checks: bool = True,
    ) -> None:
        self.cc = cc
        self.checks = checks
        self._tr_neg, self._il_neg, self._sv_neg = tr_neg, il_neg, sv_neg
        self.built = 0
        self._seen: list[dict[tuple[Any, ...], StepDetail]] = [{} for _ in cc.step_numbers]
        self._shared: dict[tuple[Any, ...], Any] = {}
        # per step: its leaving transitions with one source (valid whenever it is active),
        # and those that also need other steps active (valid only when all are)
        self._single = tuple(
            tuple(j for j in leaving if cc.tr_src[j] == (i,))
            for i, leaving in enumerate(cc.leaving)
        )
        self._joins = tuple(
            tuple(j for j in leaving if cc.tr_src[j] and cc.tr_src[j] != (i,))
            for i, leaving in enumerate(cc.leaving)
        )
        # per step: its one leaving transition, if it has one and no other (-1: none or more)
        self._one = tuple(
            one[0] if len(one) == 1 and not joins else -1
            for one, joins in zip(self._single, self._joins, strict=True)
        )

    def of(self, st: Any) -> list[StepDetail]:
        """A :class:`StepDetail` per active step of ``st`` (a ``GraphState``), by step index."""
        if not self.checks:
            return self._plain(st)
        tt, crit = st.tt, st.crit
        t_ns, u_ns, il_ok, il_err, sv_err = st.t_ns, st.u_ns, st.il_ok, st.il_err, st.sv_err
        crit_loc, crit_sup = st.crit_loc, st.crit_sup
        single, joins, seen = self._single, self._joins, self._seen
        out = []
        for i in sorted(st.active):
            valid = self._valid(i, st.x) if joins[i] else single[i]
            if len(valid) == 1:
                j = valid[0]
                transitions: tuple[Any, ...] = (tt[j], crit[j])
            else:
                transitions = tuple([(tt[j], crit[j]) for j in valid])
            key = (
                t_ns[i] // TENTH_NS,
                u_ns[i] // TENTH_NS,
                il_ok[i],
                il_err[i],
                sv_err[i],
                crit_loc[i],
                crit_sup[i],
                valid,
                transitions,
            )
            known = seen[i]
            detail = known.get(key)
            if detail is None:
                if len(known) >= PER_STEP:
                    known.clear()
                detail = known[key] = self._build(i, key, tt, crit)
            out.append(detail)
        return out

    def _plain(self, st: Any) -> list[StepDetail]:
        """:meth:`of` for a chart without interlocks and supervisions: the same details,
        keyed by the times and the transitions alone (a step with one leaving transition:
        its TT and CRIT)."""
        tt, crit, t_ns, u_ns = st.tt, st.crit, st.t_ns, st.u_ns
        one, seen, tenth = self._one, self._seen, TENTH_NS
        out = []
        for i in sorted(st.active):
            j = one[i]
            if j >= 0:
                key: tuple[Any, ...] = (t_ns[i] // tenth, u_ns[i] // tenth, tt[j], crit[j])
            else:
                valid = self._valid(i, st.x) if self._joins[i] else self._single[i]
                transitions = tuple([(tt[k], crit[k]) for k in valid])
                key = (t_ns[i] // tenth, u_ns[i] // tenth, valid, transitions)
            detail = seen[i].get(key)
            if detail is None:
                detail = self._plain_new(i, key, st)
            out.append(detail)
        return out

    def _plain_new(self, i: int, key: tuple[Any, ...], st: Any) -> StepDetail:
        """The detail of active step ``i`` for a key of :meth:`_plain`, kept."""
        known = self._seen[i]
        if len(known) >= PER_STEP:
            known.clear()
        j = self._one[i]
        valid = (j,) if j >= 0 else key[2]
        full = (key[0], key[1], True, False, False, 0, 0, valid, None)
        detail = known[key] = self._build(i, full, st.tt, st.crit)
        return detail

    def _valid(self, i: int, x: list[bool]) -> tuple[int, ...]:
        """The valid leaving transitions of active step ``i``, in priority order."""
        tr_src, single = self.cc.tr_src, self._single[i]
        return tuple(
            j
            for j in self.cc.leaving[i]
            if j in single or (tr_src[j] and all(x[s] for s in tr_src[j]))
        )

    def _build(self, i: int, key: tuple[Any, ...], tt: list[bool], crit: list[int]) -> StepDetail:
        t, u, il_ok, il_err, sv_err, loc, sup, valid, _ = key
        cc = self.cc
        self.built += 1
        return StepDetail(
            number=cc.step_numbers[i],
            t_ms=t * 100,
            u_ms=u * 100,
            interlock_ok=bool(il_ok),
            interlock_error=bool(il_err),
            supervision_fault=bool(sv_err),
            interlock=self._contacts("C", i, cc.il_labels[i], loc, self._il_neg[i]),
            supervision=self._contacts("V", i, cc.sv_labels[i], sup, self._sv_neg[i]),
            transitions=[self._criteria(j, bool(tt[j]), crit[j]) for j in valid],
        )

    def _contacts(
        self, kind: str, i: int, labels: tuple[str, ...], word: int, negated: tuple[bool, ...]
    ) -> list[Contact]:
        if not labels:
            return []
        key = (kind, i, word)
        found = self._shared.get(key)
        if found is None:
            found = self._share(key, contacts(labels, word, negated))
        return found  # type: ignore[no-any-return]

    def _criteria(self, j: int, holds: bool, word: int) -> TransitionCriteria:
        key = ("T", j, holds, word)
        found = self._shared.get(key)
        if found is None:
            cc = self.cc
            found = self._share(
                key,
                TransitionCriteria(
                    number=cc.transition_numbers[j],
                    name=cc.transition_names[j],
                    holds=holds,
                    contacts=self._contacts("T", j, cc.crit_labels[j], word, self._tr_neg[j]),
                ),
            )
        return found  # type: ignore[no-any-return]

    def _share(self, key: tuple[Any, ...], value: Any) -> Any:
        if len(self._shared) >= MAX_SHARED:
            self._shared.clear()
        self._shared[key] = value
        return value
