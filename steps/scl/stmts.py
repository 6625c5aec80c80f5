"""Statements → Python source (docs/scl.md, "Statements"; the guide ch. 13, control
statements).

Loops become Python loops; each pass counts on the CPU's loop meter (``runtime.Meter``).
``FOR v := a TO b BY s`` evaluates ``b`` and ``s`` once, tests before each pass (``v <= b``
for a positive step, ``v >= b`` for a negative one) and adds ``s`` after it — in the
variable's type, so ``FOR i := 0 TO 32767`` on an INT wraps and runs until the cycle
monitoring ends it, as on the CPU. ``CASE`` values are integer literals, the names of
integer constants of the block and ranges of these (``steps/scl/cases.py``).

**GOTO.** A statement list holding labels runs as a dispatch loop: its statements are cut
into segments at the labels, and a jump sets the segment to go on with and starts the
loop again. A jump may leave loops and statement lists towards an enclosing one, never
enter one (E219). EXIT and CONTINUE that must leave a dispatch loop first, and a GOTO that
must leave loops, pass through a flag checked after each loop they cross.
"""

from __future__ import annotations

import bisect
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import partial

from s7graph.engine.errors import SourceLocation
from s7graph.steps.scl import model as m
from s7graph.steps.scl import types as ty
from s7graph.steps.scl.calls import S5_COUNTERS, S5_TIMERS
from s7graph.steps.scl.diagnostics import Problem
from s7graph.steps.scl.exprs import checked
from s7graph.steps.scl.gen import HOLE, Block, Place, Target

S5_FUNCTIONS = frozenset(S5_TIMERS) | frozenset(S5_COUNTERS)
_CALLS = ("_invoke(", "_fcall(", "_s5_")
"""What generated code calls other blocks (or the operating system's cells) with."""
CHAIN = 100
"""Arms of IF or CASE in one Python ``if``/``elif`` chain: CPython's compiler nests each
``elif`` a level deeper and fails past about 2,900 (RecursionError, then MemoryError)."""
MAX_PYTHON_LOOPS = 18
"""Python allows 20 nested loops in a function; loops and dispatch loops stay below."""


@dataclass
class Frame:
    """A Python loop being generated: an SCL loop or a dispatch loop of labels."""

    kind: str
    id: int
    cont: list[str] = field(default_factory=list)
    """An SCL loop's lines before ``continue`` (a FOR's step, a REPEAT's test)."""
    pending: list[tuple[str, Frame]] = field(default_factory=list)
    """Signals to pass on after this loop: (kind of jump, target frame)."""


class Stmts:
    """The statement translator of one block."""

    def __init__(self, b: Block, declared: dict[str, SourceLocation], epilogue: list[str]) -> None:
        self.b = b
        self.frames: list[Frame] = []
        self.labels: list[dict[str, tuple[Frame, int]]] = []
        self.declared = declared
        self.placed: dict[str, SourceLocation] = {}
        self.jumped: set[str] = set()
        self.flags: set[str] = set()
        self.epilogue = epilogue
        self._ids = 0

    # ---- lists

    def run(self, stmts: tuple[m.Stmt, ...]) -> None:
        """The block's statements (labels collected first: a GOTO may jump forward)."""
        self._collect(stmts)
        self.body(stmts)

    def _collect(self, stmts: tuple[m.Stmt, ...]) -> None:
        for s in m.every_stmt(stmts):
            if isinstance(s, m.Labeled):
                key = s.label.upper()
                if key in self.placed:
                    self.b.report(Problem("E219", f"label {s.label} is placed twice", s.loc))
                if key not in self.declared:
                    self.b.report(
                        Problem("E218", f"label {s.label} is not declared in LABEL", s.loc)
                    )
                self.placed[key] = s.loc

    def body(self, stmts: tuple[m.Stmt, ...]) -> None:
        """A statement list (``pass`` when empty; a dispatch loop when it holds labels)."""
        if not stmts:
            self.b.emit("pass")
            return
        if any(isinstance(s, m.Labeled) for s in stmts):
            self._dispatch(stmts)
            return
        for s in stmts:
            self.stmt(s)

    def _dispatch(self, stmts: tuple[m.Stmt, ...]) -> None:
        b = self.b
        segments: list[list[m.Stmt]] = [[]]
        names: dict[str, tuple[Frame, int]] = {}
        frame = self._frame("dispatch")
        for s in stmts:
            if isinstance(s, m.Labeled):
                if segments[-1]:
                    segments.append([])
                while isinstance(s, m.Labeled):
                    names[s.label.upper()] = (frame, len(segments) - 1)
                    s = s.stmt
            segments[-1].append(s)
        pc = f"_pc{frame.id}"
        b.emit(f"{pc} = 0")
        first = next(s for s in stmts if isinstance(s, m.Labeled))
        self._open(frame, "while True:", first.loc)
        self.labels.append(names)
        for k, segment in enumerate(segments):
            b.emit(f"if {pc} <= {k}:")
            b.indent += 1
            for s in segment:
                self.stmt(s)
            if not segment:
                b.emit("pass")
            b.indent -= 1
        b.emit("break")
        self.labels.pop()
        self._close(frame)

    # ---- loops and their frames

    def _frame(self, kind: str) -> Frame:
        self._ids += 1
        return Frame(kind, self._ids)

    def _open(self, frame: Frame, head: str, where: SourceLocation) -> None:
        """Open ``frame``'s Python loop; each pass counts on the loop meter, which names
        ``where`` (the SCL loop, or the first label of a list) when it aborts the scan."""
        b = self.b
        if len(self.frames) >= MAX_PYTHON_LOOPS or b.indent > 60:
            raise Problem("E204", "loops and labelled statement lists nested too deeply", b.loc)
        b.emit(head)
        b.indent += 1
        self.frames.append(frame)
        b.emit("_M.left -= 1")
        b.emit(f"if _M.left < 0: _M.over(ctx, {b.label!r}, {b.where(where)})")

    def _close(self, frame: Frame) -> None:
        """End ``frame``'s loop; pass on the jumps that crossed it."""
        b = self.b
        self.frames.pop()
        b.indent -= 1
        parent = self.frames[-1] if self.frames else None
        done: set[tuple[str, int]] = set()
        for kind, target in frame.pending:
            if (kind, target.id) in done:
                continue
            done.add((kind, target.id))
            flag, test = self._flag(kind, target)
            if parent is not target:
                b.emit(f"if {test}: break")
                assert parent is not None
                parent.pending.append((kind, target))
            elif kind == "exit":
                b.emit(f"if {test}: {flag} = 0; break")
            elif kind == "goto":
                b.emit(f"if {test}: {flag} = False; continue")
            else:
                b.emit(f"if {test}:")
                b.emit(f"    {flag} = 0")
                for line in target.cont:
                    b.emit(f"    {line}")
                b.emit("    continue")

    def _flag(self, kind: str, target: Frame) -> tuple[str, str]:
        if kind == "goto":
            flag = f"_g{target.id}"
            self.flags.add(flag)
            return flag, flag
        flag = f"_s{target.id}"
        self.flags.add(flag)
        return flag, f"{flag} == {1 if kind == 'exit' else 2}"

    def _jump_out(self, kind: str, target: Frame) -> None:
        """Leave the loops above ``target`` with a flag they pass on."""
        b = self.b
        crossed = self.frames[self.frames.index(target) + 1 :]
        flag, _ = self._flag(kind, target)
        if kind == "goto":
            b.emit(f"{flag} = True")
        else:
            b.emit(f"{flag} = {1 if kind == 'exit' else 2}")
        b.emit("break")
        crossed[-1].pending.append((kind, target))

    # ---- statements

    def stmt(self, s: m.Stmt) -> None:
        b = self.b
        b.loc = s.loc
        try:
            self._stmt(s)
        except Problem as p:
            b.report(p)
            b.emit("pass")

    def _stmt(self, s: m.Stmt) -> None:
        b = self.b
        if isinstance(s, m.Assign):
            self._assign(s)
        elif isinstance(s, m.CallStmt):
            got = b.places.resolve(s.call)
            if not isinstance(got, Target):
                raise Problem("E232", "a statement is an assignment or a call", s.loc)
            b.calls.statement(got)
        elif isinstance(s, m.If):
            self._if(s)
        elif isinstance(s, m.Case):
            self._case(s)
        elif isinstance(s, m.For):
            self._for(s)
        elif isinstance(s, m.While):
            frame = self._frame("loop")
            self._open(frame, f"while {b.exprs.cond(s.cond)}:", s.loc)
            self.body(s.body)
            self._close(frame)
        elif isinstance(s, m.Repeat):
            frame = self._frame("loop")
            self._open(frame, "while True:", s.loc)
            self.body(s.body)
            b.loc = s.loc
            test = f"if {b.exprs.cond(s.cond)}: break"
            frame.cont = [test]
            b.emit(test)
            self._close(frame)
        elif isinstance(s, m.Jump):
            self._jump(s)
        elif isinstance(s, m.Labeled):
            raise Problem("E219", f"label {s.label} here is not in a statement list", s.loc)
        else:
            b.emit("pass")

    def _assign(self, s: m.Assign) -> None:
        b = self.b
        place = b.places.place(s.target, writing=True)
        if place.get == "_ret":
            b.ret_set = True
        if isinstance(s.value, m.Path):
            got = b.places.resolve(s.value)
            if isinstance(got, Target) and (got.kind == "fc" or got.name in S5_FUNCTIONS):
                b.calls.statement(got, result=place)
                return
        x = b.exprs.expr(s.value)
        b.emit(place.store(b.exprs.convert(x, place.type, s.loc, "assign")))

    def _if(self, s: m.If) -> None:
        b = self.b
        arms = [(cond.loc, partial(b.exprs.cond, cond), body) for cond, body in s.branches]
        self._chain(arms, s.orelse)

    def _case(self, s: m.Case) -> None:
        b = self.b
        sel = b.exprs.expr(s.selector)
        if not ty.is_int(sel.type):
            raise Problem("E242", f"a CASE selector is an INT or DINT, not {sel.type}", s.loc)
        var = b.temp("c")
        b.emit(f"{var} = {sel.src}")
        taken: list[tuple[int, int]] = []  # sorted, disjoint: a look-up per value
        arms: list[tuple[SourceLocation, Callable[[], str], tuple[m.Stmt, ...]]] = []
        for arm in s.arms:
            tests = []
            for lo_lit, hi_lit in arm.values:
                lo, hi = self._case_value(lo_lit, sel.type), self._case_value(hi_lit, sel.type)
                at = bisect.bisect_left(taken, (lo, hi))
                before, after = taken[at - 1 : at], taken[at : at + 1]
                if lo > hi or any(h >= lo for _, h in before) or any(l <= hi for l, _ in after):  # noqa: E741
                    said = _said(lo_lit, lo) if lo_lit is hi_lit else f"{lo}..{hi}"
                    raise Problem("E242", f"CASE value {said} is empty or listed twice", lo_lit.loc)
                taken.insert(at, (lo, hi))
                tests.append(f"{var} == {lo}" if lo == hi else f"{lo} <= {var} <= {hi}")
            where = arm.values[0][0].loc if arm.values else s.loc
            arms.append((where, _given(" or ".join(tests)), arm.body))
        if not s.arms and s.orelse is not None:
            arms.append((s.loc, _given("True"), s.orelse))
        self._chain(arms, s.orelse if s.arms else None)

    def _chain(
        self,
        arms: Sequence[tuple[SourceLocation, Callable[[], str], tuple[m.Stmt, ...]]],
        orelse: tuple[m.Stmt, ...] | None,
    ) -> None:
        """``if``/``elif``/``else`` of IF's and CASE's arms, at most ``CHAIN`` to one Python
        chain: the next ones run behind a flag set when none of a chain's tests held."""
        b = self.b
        groups = [arms[k : k + CHAIN] for k in range(0, len(arms), CHAIN)]
        base = b.indent
        flag = b.temp("e") if len(groups) > 1 else ""
        if flag:
            b.emit(f"{flag} = False")
        try:
            for g, group in enumerate(groups):
                if g:
                    b.emit(f"if {flag}:")
                    b.indent = base + 1
                    b.emit(f"{flag} = False")
                self._arms(group)
                if g < len(groups) - 1:
                    b.emit("else:")
                    b.emit(f"    {flag} = True")
                elif orelse is not None:
                    b.emit("else:")
                    b.indent += 1
                    self.body(orelse)
                b.indent = base
        finally:
            b.indent = base

    def _arms(
        self, group: Sequence[tuple[SourceLocation, Callable[[], str], tuple[m.Stmt, ...]]]
    ) -> None:
        """One Python ``if``/``elif`` chain of ``group``'s tests and bodies."""
        b = self.b
        for k, (loc, test, body) in enumerate(group):
            b.loc = loc
            b.emit(f"{'if' if k == 0 else 'elif'} {test()}:")
            b.indent += 1
            self.body(body)
            b.indent -= 1

    def _case_value(self, value: m.CaseValue, t: ty.SclType) -> int:
        """An integer literal, or the name of an integer constant of the block."""
        from s7graph.steps.scl.consts import literal

        if isinstance(value, m.Path):
            name = value.base.text
            found = self.b.info.consts.get(name.upper())
            if found is None:
                raise Problem(
                    "E242",
                    f"CASE value {name} is not a constant declared in this block",
                    value.loc,
                )
            ctype, v = found
            what = f"CASE value {name} (the {ctype} constant {v!r})"
        else:
            v = literal(value).value
            what = f"CASE value {value.text}"
        if not isinstance(v, int) or isinstance(v, bool) or not ty.literal_fits(t, v):
            raise Problem("E242", f"{what} is not an integer of {t}", value.loc)
        return v

    def _for(self, s: m.For) -> None:
        b = self.b
        if s.var.selectors:
            raise Problem("E241", "the FOR variable is a simple variable", s.var.loc)
        var = b.places.place(s.var, writing=True)
        if var.type.kind not in ty.INTS or not _simple(var):
            raise Problem(
                "E241", f"the FOR variable is an INT or DINT variable, not {var.what}", s.loc
            )
        t = var.type
        start = b.exprs.convert(b.exprs.expr(s.start), t, s.start.loc, "start")
        end_x = b.exprs.expr(s.end)
        end = b.exprs.convert(end_x, t, s.end.loc, "end")
        step_x = b.exprs.expr(s.step) if s.step is not None else None
        step = b.exprs.convert(step_x, t, s.step.loc, "step") if step_x and s.step else "1"
        const_step: object = 1  # no BY: 1; a constant BY: its value; else read once below
        if step_x is not None:
            const_step = step_x.const.value if step_x.const else None
        b.emit(var.store(start))
        e = b.temp("e")
        b.emit(f"{e} = {end}")
        if isinstance(const_step, int):
            if const_step == 0:
                raise Problem("E241", "a FOR step of 0 never ends", s.loc)
            test = f"{var.get} {'<=' if const_step > 0 else '>='} {e}"
        else:
            st = b.temp("s")
            b.emit(f"{st} = {step}")
            step = st
            test = f"({var.get} <= {e} if {st} >= 0 else {var.get} >= {e})"
        frame = self._frame("loop")
        incr = var.store(checked(f"{var.get} + {step}", t.kind))
        frame.cont = [incr]
        first = len(b.lines)
        self._open(frame, f"while {test}:", s.loc)
        self.body(s.body)
        b.emit(incr)
        self._close(frame)
        if isinstance(const_step, int) and end_x.const is not None:
            last = end_x.const.value
            if isinstance(last, int):
                self._plain_step(var, t, last + const_step, step, incr, first)

    def _plain_step(
        self, var: Place, t: ty.SclType, last: int, step: str, incr: str, first: int
    ) -> None:
        """The FOR's step without the overflow test when it cannot overflow: the end and
        the step are constants whose sum ``last`` is in the type's range, and nothing in
        the loop (after line ``first``) stores into the variable — a VAR_TEMP or an FC's
        parameter, or an FB's variable in a loop that calls no block (which could write
        it through the instance DB)."""
        b = self.b
        if not ty.literal_fits(t, last):
            return
        assert var.put is not None
        store = re.compile(r"(?<![\w'\]])" + re.escape(var.put.split(HOLE)[0]))
        lines = b.lines[first:]
        body = [line for line in lines if line.strip() != incr]
        if any(store.search(line) for line in body):
            return
        if var.get.startswith("V[") and any(c in line for line in body for c in _CALLS):
            return
        plain = var.store(f"{var.get} + {step}")
        b.lines[first:] = [
            line.replace(incr, plain) if line.strip() == incr else line for line in lines
        ]

    def _jump(self, s: m.Jump) -> None:
        b = self.b
        if s.kind == "RETURN":
            for line in self.epilogue:
                b.emit(line)
            return
        if s.kind == "GOTO":
            self._goto(s)
            return
        loops = [f for f in self.frames if f.kind == "loop"]
        if not loops:
            raise Problem("E240", f"{s.kind} outside a loop", s.loc)
        target = loops[-1]
        kind = "exit" if s.kind == "EXIT" else "cont"
        if self.frames[-1] is not target:
            self._jump_out(kind, target)
        elif kind == "exit":
            b.emit("break")
        else:
            for line in target.cont:
                b.emit(line)
            b.emit("continue")

    def _goto(self, s: m.Jump) -> None:
        b = self.b
        key = s.label.upper()
        self.jumped.add(key)
        for names in reversed(self.labels):
            if key in names:
                frame, segment = names[key]
                b.emit(f"_pc{frame.id} = {segment}")
                if self.frames[-1] is frame:
                    b.emit("continue")
                else:
                    self._jump_out("goto", frame)
                return
        if key not in self.declared:
            raise Problem("E218", f"GOTO {s.label}: no such label is declared", s.loc)
        if key not in self.placed:
            raise Problem("E218", f"GOTO {s.label}: the label is never placed", s.loc)
        raise Problem("E219", f"GOTO {s.label}: a jump may not enter a loop or a branch", s.loc)


def _simple(place: Place) -> bool:
    """A variable held by the block (not an operand in memory or an element)."""
    return place.get.startswith(("t_", "V[", "P[", "P.get(")) and place.get.count("[") <= 1


def _given(test: str) -> Callable[[], str]:
    """A test already made, as ``Stmts._chain`` takes it."""
    return lambda: test


def _said(value: m.CaseValue, v: int) -> str:
    """A CASE value as written, with its number when it is a constant's name."""
    return f"{value.base.text} (= {v})" if isinstance(value, m.Path) else str(v)
