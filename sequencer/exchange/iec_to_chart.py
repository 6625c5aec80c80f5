"""An IEC 61131-3 SFC (``IecChart``) as a GRAPH chart, by the rules of ``exchange.mapping``.

* Steps are numbered in the order written (s7graph's own export keeps its numbers); each
  chart of the POU (the steps its transitions connect, jumps aside) becomes a sequence.
* The transitions leaving one step are written in the order of their priority: IEC
  ``PRIORITY`` first (lower first, as matiec), then left to right, then as written. GRAPH
  switches exactly one path of an alternative where IEC without priority may switch all
  whose condition holds (matiec, GRAFCET rule 4): the GRAPH rule applies.
* Variables become FB variables; a located one a symbol at its S7 address, unless that
  would change what it does (an initial value on an I/Q location, an input the chart
  writes): then an FB variable, reported. A call of an instance of an IEC timer or counter
  (TON TOF TP CTU CTD CTUD) is ``CALL SFB n`` with an instance DB of its own (``SFB_OF``,
  ``instance_db``), its outputs written to FB variables: ``INST.Q`` reads ``INST_Q``; one
  of R_TRIG, F_TRIG, SR, RS the assignments of its body (``iec_blocks``). Other FB
  instances are not called, and a read of their outputs is reported.
* Action rows by qualifier and statement (``mapping``, ``iec_actions``); a bit assigned
  from an expression goes to PERMANENT AFTER, gated by the step (GRAPH writes bits from
  conditions only in permanent instructions); an S action of an initial step that nothing
  resets, and statements of a textual POU body beside its SFC elements, run every call
  (PERMANENT AFTER, BEFORE); a body with statements a row cannot hold is kept for the SCL
  block (``pending``).
* IEC's 1 and 0 are TRUE and FALSE where a condition expects a BOOL; a transition body
  of statements is its condition when it assigns the transition's name.
* Steps the chart can never leave are reported (``stalls``).

Everything left out is reported with its place. The chart is then validated: an action
row or instruction the validator refuses is left out and reported too, so the result is a
chart ``s7graph check`` accepts; a refused condition is an error (no chart).
"""

from __future__ import annotations

import dataclasses
from typing import Literal, TypeVar

from s7graph.engine.errors import SourceLocation
from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.checks.diagnostics import Diagnostic
from s7graph.sequencer.checks.validate import validate
from s7graph.sequencer.exchange.body_fc import BodyFc
from s7graph.sequencer.exchange.db_reads import user_fb_reads
from s7graph.sequencer.exchange.iec_actions import IecActions
from s7graph.sequencer.exchange.iec_expressions import S7_PIN, SFB_OF, _NoMap, const, iec_literal
from s7graph.sequencer.exchange.iec_model import (
    IecChart,
    IecStep,
    IecTransition,
    StatementBody,
    Unsupported,
)
from s7graph.sequencer.exchange.pending import PendingScl, first_other, written_by
from s7graph.sequencer.exchange.problems import Problems
from s7graph.sequencer.exchange.st import SAssign
from s7graph.sequencer.exchange.stalls import report_stalls
from s7graph.sequencer.text.model import (
    ActionRow,
    BlockCall,
    Chart,
    ChartOptions,
    Expr,
    Operand,
    Sequence,
    Step,
    Transition,
)

__all__ = ["S7_PIN", "SFB_OF", "const", "iec_literal", "iec_to_chart"]

_T = TypeVar("_T")


class _Convert(IecActions):
    """The chart of an IEC SFC: its structure, its actions, the chart itself."""

    # ------------------------------------------------------------ structure

    def number_steps(self) -> None:
        used = {s.graph_number for s in self.src.steps if s.graph_number is not None}
        n = 0
        for s in self.src.steps:
            if s.name.upper() in self.step_numbers:
                self.p.error("I010", f"step {s.name} is declared twice", s.loc)
                continue
            number = s.graph_number
            if number is None:
                n += 1
                while n in used:
                    n += 1
                number = n
            self.step_numbers[s.name.upper()] = number

    def transitions(self) -> list[tuple[IecTransition, Transition]]:
        out: list[tuple[IecTransition, Transition]] = []
        for t in self.src.transitions:
            sources = [self.step_ref(n, t.loc) for n in t.sources]
            targets = [self.step_ref(n, t.loc) for n in t.targets]
            if None in sources or None in targets:
                continue
            if not sources:
                self.p.error("I011", "a transition without a preceding step", t.loc)
                continue
            cond: Expr | None = None
            if isinstance(t.condition, Unsupported):
                self.p.error(
                    "I012",
                    f"{t.condition.what} is not imported; a transition needs its condition",
                    t.condition.loc,
                )
                continue
            if isinstance(t.condition, StatementBody):
                cond = self.statement_condition(t.condition)
                if cond is None:
                    continue
            elif t.condition is not None:
                try:
                    cond = self.condition(t.condition, t.cond_origin)
                except _NoMap as exc:
                    self.p.error("I012", f"condition not imported: {exc.message}", exc.loc)
                    continue
            tr = Transition(
                0,
                t.name,
                tuple(s for s in sources if s is not None),
                tuple(s for s in targets if s is not None),
                cond,
                t.loc,
                tuple(t.loc for _ in sources),
                tuple(t.loc for _ in targets),
            )
            out.append((t, tr))
        return out

    def statement_condition(self, t: StatementBody) -> Expr | None:
        """A transition body of statements: ``name := expr;`` alone is ``expr``; other
        statements are kept for the SCL block, which computes the FB variable the
        condition then reads (FALSE until it does)."""
        only = t.body[0] if len(t.body) == 1 else None
        if isinstance(only, SAssign) and only.target.text.upper() == t.name.upper():
            try:
                return self.condition(only.expr, t.origin)
            except _NoMap as exc:
                self.p.error("I012", f"condition not imported: {exc.message}", exc.loc)
                return None
        result = self.helper(t.name, "BOOL")
        found = first_other(t.body)
        why = found[0] if found else "statements"
        first = self.loc(found[1], t.origin) if found else t.loc
        writes = tuple(w for w in written_by(t.body) if w.upper() != t.name.upper())
        item = PendingScl(
            "transition", t.name, t.text, t.loc, "before", writes=writes, result=result, why=why
        )
        call = self.pending.keep(item, first, t.origin)
        if call is not None:
            self.result_calls.append(call)
        return Operand(result, False, t.loc)

    def step_ref(self, name: str, loc: SourceLocation) -> int | None:
        n = self.step_numbers.get(name.upper())
        if n is None:
            self.p.error("I010", f"unknown step {name}", loc)
        return n

    # ------------------------------------------------------------ the chart

    def build(self) -> Chart | None:
        self.number_steps()
        self.scan_writes()
        self.variables()
        self.stored = self.stored_for_good()
        self.made_permanent = set()
        pairs = self.transitions()
        steps: dict[int, tuple[IecStep, Step]] = {}
        for s in self.src.steps:
            number = self.step_numbers[s.name.upper()]
            if number in steps:
                continue
            rows = self.step_actions(s, number)
            steps[number] = (s, _step(s, number, rows))
        for number, texts in self.pending.step_comments.items():
            s, st = steps[number]
            steps[number] = (s, dataclasses.replace(st, comment="\n".join(texts)))
        for number, extra in self.rows.items():  # pulses of P gates go first
            s, st = steps[number]
            steps[number] = (s, dataclasses.replace(st, actions=(*extra, *st.actions)))
        self.prelude()
        self.uncalled_instances()
        self.check_shared_variables()
        used = {a.action.upper() for s in self.src.steps for a in s.associations}
        for name, act in self.src.actions.items():
            if name not in used:
                self.p.warn(
                    "I024", f"action {act.name} is not used by any step; not imported", act.loc
                )
        self.p.fail_if_errors()
        sequences = _sequences(self.src, steps, _ordered(pairs, self.step_numbers))
        chart = Chart(
            name=self.src.name,
            options=_options(self.src),
            vars=tuple(self.decls),
            symbols=tuple(self.symbols),
            before=(*self.before, *self.result_calls),
            sequences=sequences,
            after=tuple(self.after),
            file=self.file,
            loc=self.src.loc,
            end_comment="\n".join(self.pending.end_comments),
        )
        return chart

    def internal(self) -> set[str]:
        """The FB variables (upper case) only the chart could write: the importer's own
        (instance outputs and states, transition results), the constants, and the locals
        and outputs of a function block that only a body kept for the SCL block writes
        (the source writes them there); inputs, in-outs, externals, globals and the
        variables of a program may be written from outside."""
        graph = {n: v.graph.upper() for n, v in self.vars.items()}
        inner = set() if self.src.kind == "program" else {"local", "output", "temp"}
        declared = [v for v in self.src.vars if v.name.upper() in graph]
        own = {graph[v.name.upper()] for v in declared if v.kind in inner}
        constants = {graph[v.name.upper()] for v in declared if v.constant}
        by_pending = {g for g in self.stall_reasons() if g in own}
        return constants | {h.upper() for h in self.helpers} | by_pending

    def stall_reasons(self) -> dict[str, str]:
        """Why nothing writes an FB variable (upper case), where the import knows it."""
        out: dict[str, str] = {}
        for head, (member, graph) in self.members_read.items():
            if head not in self.instance_dbs and head not in self.called:
                name, fb_type, _ = self.instances[head]
                out[graph.upper()] = f"is {name}.{member}, and {name} : {fb_type} is never called"
        for var, where in self.pending.writes().items():
            graph = self.vars[var].graph if var in self.vars else var
            out.setdefault(graph.upper(), f"is written only by {where}, kept for the SCL block")
        return out

    def check_shared_variables(self) -> None:
        for name in sorted(self.bool_actions & set(self.body_writes)):
            self.p.warn(
                "I031",
                f"{self.vars[name].graph if name in self.vars else name} is a "
                "Boolean action and is also written by an action body: matiec writes "
                "it from the action's state every call, GRAPH only while a row "
                "acts on it",
                self.body_writes[name],
            )


def _step(s: IecStep, number: int, rows: list[ActionRow]) -> Step:
    g = s.graph
    return Step(number, s.name, s.initial, g.get("message", ""), actions=tuple(rows), loc=s.loc)


def _ordered(
    pairs: list[tuple[IecTransition, Transition]], numbers: dict[str, int]
) -> list[tuple[IecTransition, Transition]]:
    """Transitions in priority order per step (PRIORITY, left to right, as written), then
    numbered T1… (s7graph's own export keeps its numbers and order)."""
    if all(t.graph_number is not None for t, _ in pairs):
        return [(t, dataclasses.replace(tr, number=t.graph_number or 0)) for t, tr in pairs]
    inf = float("inf")
    pairs = sorted(
        pairs,
        key=lambda p: (
            min(p[1].sources),
            p[0].priority if p[0].priority is not None else inf,
            p[0].x if p[0].x is not None else inf,
            p[0].order,
        ),
    )
    return [(t, dataclasses.replace(tr, number=i)) for i, (t, tr) in enumerate(pairs, 1)]


def _sequences(
    src: IecChart,
    steps: dict[int, tuple[IecStep, Step]],
    pairs: list[tuple[IecTransition, Transition]],
) -> tuple[Sequence, ...]:
    """One sequence per chart: the steps connected by transitions (jumps aside), in the
    order of their first step."""
    parent = {n: n for n in steps}

    def find(n: int) -> int:
        while parent[n] != n:
            parent[n] = parent[parent[n]]
            n = parent[n]
        return n

    for t, tr in pairs:
        linked = list(tr.sources) + [
            n for n, name in zip(tr.targets, t.targets, strict=True) if name not in t.jumps
        ]
        for a in linked[1:]:
            parent[find(a)] = find(linked[0])
    order = list(steps)
    groups: dict[int, list[int]] = {}
    for n in order:
        groups.setdefault(find(n), []).append(n)
    seq_of = {n: i for i, members in enumerate(groups.values()) for n in members}
    out: list[Sequence] = []
    for i, members in enumerate(groups.values()):
        trs = tuple(tr for _, tr in pairs if seq_of[tr.sources[0]] == i)
        name = src.graph.get(f"sequence{i + 1}", "")
        out.append(
            Sequence(
                i + 1, name, tuple(steps[n][1] for n in members), trs, steps[members[0]][0].loc
            )
        )
    return tuple(out)


def _options(src: IecChart) -> ChartOptions:
    order: Literal["graph", "codesys"] = (
        "codesys" if src.dialect in ("codesys", "twincat") else "graph"
    )
    g = src.graph
    return ChartOptions(
        parameters=g.get("parameters", "STANDARD"),
        skip_steps=g.get("skip_steps") == "TRUE",
        ack_required=g.get("ack_required", "TRUE") == "TRUE",
        messages=g.get("messages") == "TRUE",
        ack_forces_switch=g.get("ack_forces_switch") == "TRUE",
        order=g.get("order", order),  # type: ignore[arg-type]
    )


# ---------------------------------------------------------------- validation


def _errors(
    chart: Chart, symbols: SymbolTable | None = None, unchecked: frozenset[object] = frozenset()
) -> list[Diagnostic]:
    """The validator's errors but E048 at a read of a user FB's instance DB (``unchecked``:
    the import has no program blocks to check it against)."""
    return [
        d
        for d in validate(chart, symbols)
        if d.is_error and not (d.code == "E048" and d.loc in unchecked)
    ]


def _probe(chart: Chart, calls: bool = False) -> Chart:
    """The chart without rows, interlocks, supervisions, conditions and instructions; with
    ``calls``, its CALLs kept (the instance DBs whose variables a condition reads)."""

    def kept(items: tuple[_T, ...]) -> tuple[_T, ...]:
        return tuple(i for i in items if calls and _is_call(i))

    seqs = tuple(
        dataclasses.replace(
            q,
            steps=tuple(
                dataclasses.replace(s, actions=kept(s.actions), interlock=None, supervision=None)
                for s in q.steps
            ),
            transitions=tuple(dataclasses.replace(t, condition=None) for t in q.transitions),
        )
        for q in chart.sequences
    )
    return dataclasses.replace(
        chart, before=kept(chart.before), after=kept(chart.after), sequences=seqs
    )


def _is_call(item: object) -> bool:
    return isinstance(item, BlockCall) or (
        isinstance(item, ActionRow) and isinstance(item.operand, BlockCall)
    )


def _plus(items: tuple[_T, ...], item: _T) -> tuple[_T, ...]:
    """``items`` with ``item`` (once)."""
    return items if item in items else (*items, item)


def accepted(chart: Chart, problems: Problems, symbols: SymbolTable | None = None) -> Chart:
    """``chart`` without the rows and instructions the validator refuses (each reported,
    located at its source); a refused condition, or a structural error, fails the import.
    A read of a user FB's instance DB is left for ``check --blocks`` (``db_reads``)."""
    skip = frozenset(user_fb_reads(chart, symbols))

    def _refused(c: Chart, table: SymbolTable | None = None) -> list[Diagnostic]:
        return _errors(c, table, skip)

    if not _refused(chart, symbols):
        return chart
    base = _probe(chart, calls=True)
    if _refused(base, symbols):  # a call refused: probe without them
        base = _probe(chart)
    for d in _refused(base, symbols):
        problems.error("I013", d.message, d.loc, d.element)
    problems.fail_if_errors()

    def ok(candidate: Chart, what: str, loc: SourceLocation, *, fatal: bool = False) -> bool:
        bad = _refused(candidate, symbols)
        for d in bad[:1]:
            if fatal:
                problems.error("I012", f"{what}: {d.message}", loc, d.element)
            else:
                problems.warn("I021", f"{what} not imported: {d.message}", loc, d.element)
        return not bad

    seqs: list[Sequence] = []
    for qi, q in enumerate(chart.sequences):
        steps: list[Step] = []
        for si, s in enumerate(q.steps):
            kept: list[ActionRow] = []
            for row in s.actions:
                probe_step = base.sequences[qi].steps[si]
                probe_step = dataclasses.replace(probe_step, actions=_plus(probe_step.actions, row))
                if ok(_with(base, qi, "steps", si, probe_step), f"step {s.name} row", row.loc):
                    kept.append(row)
            steps.append(dataclasses.replace(s, actions=tuple(kept)))
        for ti, t in enumerate(q.transitions):
            if t.condition is not None:
                probe = _with(base, qi, "transitions", ti, t)
                ok(probe, f"transition T{t.number}", t.loc, fatal=True)
        seqs.append(dataclasses.replace(q, steps=tuple(steps)))
    problems.fail_if_errors()
    before = [
        p
        for p in chart.before
        if ok(
            dataclasses.replace(base, before=_plus(base.before, p)), "permanent instruction", p.loc
        )
    ]
    after = [
        p
        for p in chart.after
        if ok(dataclasses.replace(base, after=_plus(base.after, p)), "permanent instruction", p.loc)
    ]
    out = dataclasses.replace(
        chart, sequences=tuple(seqs), before=tuple(before), after=tuple(after)
    )
    for d in _refused(out, symbols):
        problems.error("I013", d.message, d.loc, d.element)
    problems.fail_if_errors()
    return out


def _with(base: Chart, qi: int, field: str, i: int, item: Step | Transition) -> Chart:
    """``base`` with item ``i`` of sequence ``qi``'s ``steps`` or ``transitions`` replaced."""
    q = base.sequences[qi]
    items = list(getattr(q, field))
    items[i] = item
    seqs = list(base.sequences)
    seqs[qi] = dataclasses.replace(q, **{field: tuple(items)})  # type: ignore[arg-type]
    return dataclasses.replace(base, sequences=tuple(seqs))


def iec_to_chart(src: IecChart, problems: Problems) -> tuple[Chart, list[PendingScl], list[BodyFc]]:
    """The GRAPH chart of ``src``, the bodies it keeps for the SCL block and the SCL FCs it
    calls (raises ``ImportFailed`` with the located problems)."""
    conv = _Convert(src, problems)
    chart = conv.build()
    assert chart is not None
    chart = accepted(chart, problems)
    report_stalls(chart, problems, conv.internal(), conv.stall_reasons())
    return chart, conv.pending.items, conv.pending.functions
