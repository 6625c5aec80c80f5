"""The actions of an IEC SFC as GRAPH rows and permanent instructions, by the rules of
``exchange.mapping``: the middle part of ``exchange.iec_to_chart`` (expressions below it,
in ``exchange.iec_expressions``; the chart's structure above it).

* An association is a row by its qualifier (a Boolean action variable) or the rows of the
  action's body: a bit assigned from an expression goes to PERMANENT AFTER, gated by the
  step; a call of an IEC timer or counter is a CALL row, of an edge detector or bistable
  its body's gated assignments.
* An S action on an initial step that nothing resets runs every call for good:
  PERMANENT AFTER (Beremiz's ``COMPUTE_FUNCTION_BLOCKS``).
* Statements of a textual POU body beside its SFC are PERMANENT BEFORE.
* A body with statements a row cannot hold is kept whole for the SCL block
  (``exchange.pending``).
"""

from __future__ import annotations

from s7graph.engine.errors import LiteralError, S7Error, SourceLocation
from s7graph.sequencer.exchange.iec_expressions import (
    IecExpressions,
    _NoMap,
    _typed,
    const,
)
from s7graph.sequencer.exchange.iec_model import (
    IecAction,
    IecAssociation,
    IecStep,
    Unsupported,
)
from s7graph.sequencer.exchange.mapping import QUALIFIERS
from s7graph.sequencer.exchange.pending import PendingScl, first_other, written_by
from s7graph.sequencer.exchange.st import (
    SAssign,
    SCallStmt,
    SExpr,
    SLiteral,
    SName,
    SOther,
    SSetReset,
    SStmt,
)
from s7graph.sequencer.text.model import (
    ActionRow,
    Assignment,
    Binary,
    BlockCall,
    Coil,
    Const,
    Expr,
    Operand,
    PermanentInstruction,
    StepAttr,
    Unary,
)

__all__ = ["IecActions", "gated", "permanent_assignment"]


class IecActions(IecExpressions):
    """The rows and permanent instructions of a conversion's actions."""

    stored: set[str]
    """The actions stored for good (``stored_for_good``), set before the steps are read."""
    made_permanent: set[str]
    """Those of them already in PERMANENT AFTER."""

    def scan_writes(self) -> None:
        """What the chart writes (a located input written must stay an FB variable)."""
        self.written: set[str] = set()
        names = {v.name.upper() for v in self.src.vars}
        for s in self.src.steps:
            for a in s.associations:
                if a.inline is None and a.action.upper() in names:
                    self.written.add(a.action.upper())
                    self.bool_actions.add(a.action.upper())
        bodies = [a.body for a in self.src.actions.values()]
        bodies += [a.inline.body for s in self.src.steps for a in s.associations if a.inline]
        bodies.append(self.src.prelude)
        for body in bodies:
            if isinstance(body, Unsupported):
                continue
            for st in body:
                if isinstance(st, SAssign | SSetReset) and isinstance(st.target, SName):
                    self.written.add(st.target.parts[0].upper())
                elif isinstance(st, SCallStmt):
                    targets = [t for _, t in st.outputs if isinstance(t, SName)]
                    self.written.update(t.parts[0].upper() for t in targets)

    def step_actions(self, step: IecStep, number: int) -> list[ActionRow]:
        rows: list[ActionRow] = []
        for a in step.associations:
            rule = QUALIFIERS.get(a.qualifier.upper()) if not a.phase else None
            if a.phase:
                rows += self.phase_action(a, step, number)
                continue
            if rule is None:
                self.p.warn(
                    "I020",
                    f"qualifier {a.qualifier} is not an IEC action qualifier; "
                    f"{a.action} not imported",
                    a.loc,
                )
                continue
            if a.indicator:
                self.p.warn(
                    "I020",
                    f"indicator variable {a.indicator} not imported (GRAPH rows have no indicator)",
                    a.loc,
                )
            key = a.action.upper()
            action = a.inline or self.src.actions.get(key)
            if action is None and key in self.vars and self.vars[key].type == "BOOL":
                rows += self.variable_action(a, rule.iec, number)
                continue
            if action is None and key in self.src.sfc_actions:
                self.p.warn(
                    "I021",
                    f"action {a.action} is a chart (an SFC body), run while the step is "
                    "active; GRAPH does not nest charts: not imported here (it is imported "
                    f"on its own as {self.src.name.split('.')[0]}.{a.action}, with --pou)",
                    a.loc,
                )
                continue
            if action is None:
                self.p.warn(
                    "I021",
                    f"action {a.action} is neither an action nor a Boolean "
                    "variable of the POU; not imported",
                    a.loc,
                )
                continue
            if key in self.stored:
                if a.qualifier.upper() == "S" and step.initial:
                    self.permanent_action(action, key)
                else:
                    self.warn_once(
                        (key, "stored"),
                        "I031",
                        f"{a.qualifier} {a.action} adds nothing: an initial step stores "
                        f"{a.action} for good (it runs every call, in PERMANENT AFTER)",
                        a.loc,
                    )
                continue
            if rule.body is None:
                self.p.warn("I020", f"{a.qualifier} {a.action} not imported: {rule.why}", a.loc)
                continue
            rows += self.body(action, rule.body, rule.gate, step, number, a.loc)
        return rows

    def phase_action(self, a: IecAssociation, step: IecStep, number: int) -> list[ActionRow]:
        """A CODESYS entry/active/exit step action: its body once on entry (S1), every
        call (no event), once on exit (S0)."""
        action = self.src.actions.get(a.action.upper())
        if action is None:
            self.p.warn("I021", f"step action {a.action} is not in the POU; not imported", a.loc)
            return []
        event, gate = {"entry": ("S1", "P"), "active": ("", "X"), "exit": ("S0", "")}[a.phase]
        return self.body(action, event, gate, step, number, a.loc)

    def variable_action(self, a: IecAssociation, qualifier: str, number: int) -> list[ActionRow]:
        rule = QUALIFIERS[qualifier]
        var = self.vars[a.action.upper()]
        if rule.variable is None:
            self.p.warn("I020", f"{qualifier} {a.action} not imported: {rule.why}", a.loc)
            return []
        op = Operand(var.graph, var.symbol, a.loc)
        event, q = (None, rule.variable) if " " not in rule.variable else rule.variable.split()
        value: Expr | None = None
        if rule.timed:
            value = self.duration(a)
            if value is None:
                return []
        return [ActionRow(q, op, event, False, value, a.loc)]

    def duration(self, a: IecAssociation) -> Const | Operand | None:
        """The action time of a D or L row: a TIME constant, or a TIME variable."""
        text = a.duration.strip()
        if not text:
            self.p.warn("I020", f"{a.qualifier} {a.action} has no time; not imported", a.loc)
            return None
        var = self.vars.get(text.upper())
        if var is not None and var.type == "TIME":
            return Operand(var.graph, var.symbol, a.loc)
        if var is not None:
            self.p.warn(
                "I020",
                f"action time {text} is a {var.type}, not a TIME; "
                f"{a.qualifier} {a.action} not imported",
                a.loc,
            )
            return None
        if "#" not in text:
            self.p.warn("I031", f"duration {text!r} has no T#; read as T#{text}", a.loc)
            text = "T#" + text
        try:
            c = const(text, a.loc)
        except (LiteralError, S7Error):
            c = None
        if c is None or c.type != "TIME":
            self.p.warn(
                "I020",
                f"duration {a.duration!r} is not a constant TIME; "
                f"{a.qualifier} {a.action} not imported",
                a.loc,
            )
            return None
        return c

    def body(
        self,
        action: IecAction,
        event: str,
        gate_kind: str,
        step: IecStep,
        number: int,
        at: SourceLocation,
    ) -> list[ActionRow]:
        if isinstance(action.body, Unsupported):
            self.p.warn(
                "I021", f"action {action.name}: {action.body.what} not imported", action.body.loc
            )
            return []
        if not action.body:
            self.p.warn(
                "I021", f"action {action.name} has an empty body (a comment at most); no rows", at
            )
            return []
        found = first_other(action.body)
        if found is not None:
            item = PendingScl(
                "action",
                action.name,
                action.text,
                action.loc,
                "step",
                number,
                event,
                written_by(action.body),
                why=found[0],
            )
            fc = self.pending.keep(item, self.loc(found[1], action.origin), action.origin)
            if fc is None:
                return []
            return [ActionRow("CALL", fc, event or None, False, None, at)]
        rows: list[ActionRow] = []
        coils: list[PermanentInstruction] = []
        ev = event or None
        for st in action.body:
            loc = self.loc(st, action.origin)
            try:
                assert not isinstance(st, SOther)  # such bodies are pending (above)
                if isinstance(st, SCallStmt):
                    call = self.fb_call(st, action.origin, action=True)
                    if isinstance(call, BlockCall):
                        rows.append(ActionRow("CALL", call, ev, False, None, loc))
                    else:
                        gate = self.gate(gate_kind, step, number, loc)
                        coils += [gated(t, gate, v, loc) for t, v in call]
                    continue
                target = self.operand(st.target, action.origin)
                assert isinstance(target, Operand)
                ttype = self.type_of(target)
                if isinstance(st, SSetReset):
                    cond = self.expr(st.expr, action.origin)
                    if isinstance(cond, Const) and cond.value is True:
                        rows.append(ActionRow(st.kind, target, ev, False, None, loc))
                    else:
                        gate = self.gate(gate_kind, step, number, loc)
                        coils.append(Coil(st.kind, target, Binary("AND", gate, cond, loc), loc))  # type: ignore[arg-type]
                    continue
                value = self.assigned(st.expr, ttype, action.origin)
                if ttype == "BOOL" and isinstance(value, Const):
                    q = "S" if value.value else "R"
                    rows.append(ActionRow(q, target, ev, False, None, loc))
                elif ttype == "BOOL":
                    gate = self.gate(gate_kind, step, number, loc)
                    coils.append(gated(target, gate, value, loc))
                else:
                    rows.append(
                        ActionRow("N", Assignment(target, value, loc), ev, False, None, loc)
                    )
            except _NoMap as exc:
                self.p.warn("I021", f"action {action.name}: {exc.message}", exc.loc)
        if rows and coils:
            self.warn_once(
                (action.name, "mixed"),
                "I031",
                f"action {action.name}: its bit "
                "assignments from expressions run in PERMANENT AFTER, its other "
                "statements as rows of the step, so their order is not the "
                "body's",
                at,
            )
        self.after += coils
        for st in action.body:
            if isinstance(st, SAssign | SSetReset) and isinstance(st.target, SName):
                self.body_writes.setdefault(st.target.parts[0].upper(), self.loc(st, action.origin))
        return rows

    def assigned(self, e: SExpr, target_type: str | None, origin: tuple[int, int]) -> Expr:
        """The value of an assignment; IEC's 0/1 for a BOOL and integers for a REAL are
        the same constants in GRAPH."""
        if isinstance(e, SLiteral):
            e = SLiteral(_typed(e.text, target_type), e.line, e.col)
        return self.expr(e, origin)

    def gate(self, kind: str, step: IecStep, number: int, loc: SourceLocation) -> Expr:
        if kind == "X":
            return StepAttr(number, "X", loc)
        if kind == "P":
            name = self.helper(f"{step.name}_P1", "BOOL")
            rows = self.rows.setdefault(number, [])
            if not any(isinstance(r.operand, Operand) and r.operand.name == name for r in rows):
                rows.append(ActionRow("N", Operand(name, False, loc), "S1", False, None, loc))
            return Operand(name, False, loc)
        raise _NoMap(
            "a bit assigned from an expression on leaving the step has no exact "
            "GRAPH form (an S0 row cannot pulse)",
            loc,
        )

    def prelude(self) -> None:
        found = first_other(self.src.prelude)
        if found is not None:
            writes = written_by(self.src.prelude)
            loc = self.loc(self.src.prelude[0], (1, 1))
            item = PendingScl(
                "body",
                self.src.name,
                self.src.prelude_text,
                loc,
                "before",
                writes=writes,
                why=found[0],
            )
            call = self.pending.keep(item, self.loc(found[1], (1, 1)), (loc.line, loc.col))
            if call is not None:
                self.before.append(call)
            return
        self.permanent(self.src.prelude, (1, 1), self.before, "")

    def permanent(
        self,
        body: list[SStmt],
        origin: tuple[int, int],
        into: list[PermanentInstruction],
        action: str,
    ) -> None:
        """Statements that run every call, as permanent instructions: the POU body beside
        its SFC (PERMANENT BEFORE), an S action of an initial step that nothing resets
        (PERMANENT AFTER, ``action`` its name)."""
        for st in body:
            loc = self.loc(st, origin)
            try:
                if isinstance(st, SCallStmt):
                    call = self.fb_call(st, origin, action=False)
                    if isinstance(call, BlockCall):
                        into.append(call)
                    else:
                        into += [permanent_assignment(t, v, loc) for t, v in call]
                    continue
                assert not isinstance(st, SOther)  # such bodies are pending
                target = self.operand(st.target, origin)
                assert isinstance(target, Operand)
                value = self.assigned(st.expr, self.type_of(target), origin)
                if isinstance(st, SSetReset):
                    into.append(Coil(st.kind, target, value, loc))  # type: ignore[arg-type]
                else:
                    into.append(permanent_assignment(target, value, loc))
            except _NoMap as exc:
                if action:
                    self.p.warn("I021", f"action {action}: {exc.message}", exc.loc)
                else:
                    self.p.warn("I022", exc.message, exc.loc)

    def stored_for_good(self) -> set[str]:
        """The actions an S association of an initial step stores and nothing resets (no R
        association anywhere): active from the first call on, for good — which is what
        PERMANENT AFTER does (Beremiz stores the blocks of a chart's network so, as the
        action COMPUTE_FUNCTION_BLOCKS)."""
        reset = {
            a.action.upper()
            for s in self.src.steps
            for a in s.associations
            if a.qualifier.upper() == "R" and not a.phase
        }
        return {
            a.action.upper()
            for s in self.src.steps
            if s.initial
            for a in s.associations
            if a.qualifier.upper() == "S"
            and not a.phase
            and a.action.upper() not in reset
            and (a.inline is not None or a.action.upper() in self.src.actions)
        }

    def permanent_action(self, action: IecAction, key: str) -> None:
        """An action stored for good: its body in PERMANENT AFTER (once)."""
        if key in self.made_permanent:
            return
        self.made_permanent.add(key)
        if isinstance(action.body, Unsupported):
            self.p.warn(
                "I021", f"action {action.name}: {action.body.what} not imported", action.body.loc
            )
            return
        found = first_other(action.body)
        if found is not None:
            writes = written_by(action.body)
            item = PendingScl(
                "action", action.name, action.text, action.loc, "after", writes=writes, why=found[0]
            )
            call = self.pending.keep(item, self.loc(found[1], action.origin), action.origin)
            if call is not None:
                self.after.append(call)
            return
        self.permanent(action.body, action.origin, self.after, action.name)


def gated(target: Operand, gate: Expr, value: Expr, loc: SourceLocation) -> PermanentInstruction:
    """``target := gate AND (value) OR NOT gate AND target``: the body's assignment in the
    calls the gate holds, the old value otherwise."""
    expr = Binary(
        "OR",
        Binary("AND", gate, value, loc),
        Binary("AND", Unary("NOT", gate, loc), target, loc),
        loc,
    )
    return permanent_assignment(target, expr, loc)


def permanent_assignment(target: Operand, value: Expr, loc: SourceLocation) -> PermanentInstruction:
    """A coil on an absolute bit address, else an assignment (the parser's reading)."""
    from s7graph.sequencer.text.build import _BIT_ADDRESS

    if not target.quoted and _BIT_ADDRESS.fullmatch(target.name):
        return Coil("=", target, value, loc)
    return Assignment(target, value, loc)
