"""Action rows of a step → two generated Python functions (docs/semantics.md, "Actions" and
"Decisions").

``def _a<i>(st, R, ev, c_ok, zero)`` runs while step ``i`` is active, rows top to bottom:
  N bit      operand = 1 (0 while C does not hold, or ZERO_OP); an event N row writes
             ``event occurred`` — a one-call pulse, the compiled form ``A ev; = op``
  S / R      set / reset (latching), every call (or once, with an event)
  D op, t    operand = 1 once the step has been active ≥ t (``st.t_ns``: HALT_TM freezes it;
             the step's own index is the default parameter ``_i``)
  L op, t    operand = 1 while the step has been active < t
  CALL       ``R.call(...)`` every call (skipped by ZERO_OP)
  x := expr  assignment (every call, or once with an event)
  ON/OFF Sx, OFF S_ALL, counters CS CU CD CR, timers TL TD TF TR: event rows only
``ev`` is the step's event bits of this call, ``c_ok`` whether its interlock holds.
``def _f<i>(st, R, ev)`` is the final scan of a step deactivated in this call: N, D and L
operands are reset, then the S0 rows run (ZERO_OP holds back their N pulses, assignments and
CALLs as it does those of the active steps).
"""

from __future__ import annotations

import re
from collections.abc import Callable
from typing import NamedTuple

from s7graph.engine.errors import S7Error
from s7graph.steps.conditions import with_locals
from s7graph.steps.expressions import Resolve, StepIndex, gen_assigned, gen_value
from s7graph.steps.operands import CELLS, CodeGen, Ref, address_text
from s7graph.steps.qualifiers import EVENT_BITS
from s7graph.steps.syntax import (
    ActionRow,
    Assignment,
    BlockCall,
    Expr,
    Operand,
    StepTarget,
)

TimeValue = Callable[[Expr], str]


class ActionError(S7Error):
    """An action row that cannot be compiled."""


def _indent(lines: list[str], n: int = 1) -> list[str]:
    return ["    " * n + ln for ln in lines]


class ActionParts(NamedTuple):
    """The two functions of a step's rows and their bodies (indented one level), for
    functions that run the rows after other code: ``rows`` uses ``st R ev c_ok zero`` and
    ``_i`` (the step's own index); ``reset`` (the final scan's N/D/L resets) and ``s0``
    (its S0 rows) use ``st R ev c_ok zero`` and never ``_i``."""

    a_src: str
    f_src: str
    rows: list[str]
    reset: list[str]
    s0: list[str]
    p_src: str | None = None
    """``def _p<i>(st)``: the end of the one-call pulses of the step's ``S0 N`` rows (their
    operands back to 0), for the call after the one that left the step; None without such
    rows."""


def step_action_parts(
    i: int,
    rows: tuple[ActionRow, ...],
    g: CodeGen,
    resolve: Resolve,
    sidx: StepIndex,
    tidx: StepIndex,
) -> ActionParts:
    """The sources of ``_a<i>`` and ``_f<i>`` for the action ``rows`` of step ``i``, and
    their bodies (``ActionParts``)."""
    body: list[str] = []
    final_reset: list[str] = []
    s0_rows: list[str] = []
    pulse_end: list[str] = []

    def val(e: Expr) -> str:
        return gen_value(e, g, resolve, sidx, tidx)

    off_self = False  # a row above may switch the step itself off (``OFF Sn`` of its own)
    for row in rows:
        code = _row(i, row, g, resolve, val, sidx, tidx)
        q = row.qualifier.upper()
        bit = _nld_bit(row)
        if bit is not None:
            final_reset.append(g.set_bit(resolve(bit), False))
        if row.event == "S0":
            s0_rows.extend(code)
            if q == "N" and isinstance(row.operand, Operand):  # a one-call pulse, as any
                pulse_end.append(g.write(resolve(row.operand), "False"))  # event N row
            continue
        lines = _guarded(row, q, bit, code, g, resolve)
        if off_self:  # the step is left once that row ran: the rows below it do not run
            body.append("if X[_i]:")
            body.extend(_indent(lines))
        else:
            body.extend(lines)
        off_self = off_self or _switches_itself_off(i, row, sidx)
    a_body = _indent(body) or ["    pass"]
    f_body = _indent(final_reset)
    if s0_rows:
        f_body += ["    c_ok = True", "    zero = st.zeroed", *_indent(s0_rows)]
    f_body = f_body or ["    pass"]
    a_src = [f"def _a{i}(st, R, ev, c_ok, zero{_own(i, a_body)}):", *a_body]
    f_src = [f"def _f{i}(st, R, ev{_own(i, f_body)}):", *f_body]
    p_src = with_locals([f"def _p{i}(st):", *_indent(pulse_end)]) if pulse_end else None
    return ActionParts(
        with_locals(a_src),
        with_locals(f_src),
        _indent(body),
        _indent(final_reset),
        _indent(s0_rows),
        p_src,
    )


def _guarded(
    row: ActionRow,
    q: str,
    bit: Operand | None,
    code: list[str],
    g: CodeGen,
    resolve: Resolve,
) -> list[str]:
    """The statements of a row of an active step (not an S0 row) with its guard: its event
    (and interlock) for an event row — an event N row is its one-call pulse, written every
    call — the interlock for a row marked C but N, D, L (which gate their bit themselves)."""
    if row.event is not None:
        cond = f"ev & {EVENT_BITS[row.event]}"
        if row.interlocked:
            cond += " and c_ok"
        if q == "N" and isinstance(row.operand, Operand):
            return _n_event(row, g, resolve, cond)
        return [f"if {cond}:", *_indent(code)]
    if row.interlocked and bit is None:
        return ["if c_ok:", *_indent(code)]
    return code


def _switches_itself_off(i: int, row: ActionRow, sidx: StepIndex) -> bool:
    """Whether ``row`` of step ``i`` is ``OFF Sn`` of step ``i`` itself: once it ran, the
    step is left (its final scan done) and the rows below it do not run — an N, D or L
    operand stays 0, as after any leaving (docs/semantics.md, "Decisions")."""
    op = row.operand
    return (
        row.qualifier.upper() == "OFF"
        and isinstance(op, StepTarget)
        and op.step is not None
        and sidx(op.step, op.loc) == i
    )


def _nld_bit(row: ActionRow) -> Operand | None:
    """The bit of an N, D or L row (else None): the final scan resets it, and the row gates it by
    writing ``operand = c_ok and …`` (C off writes 0). Every other row marked C — the
    assignment ``N C x := expr`` included — runs only while the interlock holds (S7-GRAPH
    manual 14-8: all actions marked C; STEP7 comprehensive guide vol. 2, ch. 14)."""
    nld = row.qualifier.upper() in ("N", "D", "L")
    return row.operand if nld and isinstance(row.operand, Operand) else None


_OWN = re.compile(r"\b_i\b")


def uses_own_index(body: list[str]) -> bool:
    """Whether generated lines use ``_i``, the step's own index (D/L times, OFF S_ALL)."""
    return any(_OWN.search(ln) for ln in body)


def _own(i: int, body: list[str]) -> str:
    """The parameter ``_i`` = the step's own index when the body uses it: the code then
    does not depend on ``i`` and the compiler shares it between steps."""
    return f", _i={i}" if uses_own_index(body) else ""


def _n_event(row: ActionRow, g: CodeGen, resolve: Resolve, cond: str) -> list[str]:
    assert isinstance(row.operand, Operand)
    return [g.write(resolve(row.operand), f"bool({cond}) and not zero")]


def _bit(row: ActionRow, resolve: Resolve) -> Ref:
    if not isinstance(row.operand, Operand):
        raise ActionError(f"{row.qualifier} needs a bit operand", row.loc)
    ref = resolve(row.operand)
    if ref.type != "BOOL":
        raise ActionError(
            f"{row.qualifier} {row.operand.name}: operand must be BOOL, not {ref.type}", row.loc
        )
    return ref


def call_code(call: BlockCall, val: Callable[[Expr], str], resolve: Resolve) -> str:
    """``_o = R.call(kind, block, instance, {params})`` for a CALL row or permanent
    instruction: its inputs' values, and each output without an operand (``None``: the
    block returns it and the code after the call writes it to the row's operand; RET_VAL
    always comes back). A bare timer or counter goes as its operand (``'T12'``), so the
    parameter's type decides what arrives: a TIMER or COUNTER parameter its number, a BOOL
    its status bit, a number its value (``engine.context``)."""
    pairs = [f"{name!r}: {_actual(e, val, resolve)}" for name, e in call.inputs]
    pairs += [f"{name!r}: None" for name, _ in call.outputs if name.upper() != "RET_VAL"]
    return f"_o = R.call({call.kind!r}, {call.block!r}, {call.instance!r}, {{{', '.join(pairs)}}})"


def _actual(e: Expr, val: Callable[[Expr], str], resolve: Resolve) -> str:
    """The code of one CALL input: a timer or counter cell's or a memory operand's address
    text (``'T12'``, ``'MW0'``: the block reads it in its parameter's type, and an in/out
    parameter is written back to it, as S7 passes the operand itself), else ``val(e)``."""
    if isinstance(e, Operand):
        ref = resolve(e)
        if ref.kind in CELLS:
            return repr(f"{'T' if ref.kind == 'timer' else 'C'}{ref.number}")
        if ref.kind == "mem" and (text := address_text(ref)) is not None:
            return repr(text)
    return val(e)


def _cell_value(row: ActionRow, val: Callable[[Expr], str], resolve: Resolve) -> str:
    """The code of a counter or timer row's value. The time of TL, TD, TF goes as an S5TIME
    word (BCD count and time base), as the CPU loads it: a word of memory (``MW10``,
    ``DB1.DBW2``) as it holds it; the constant ``S5T#…`` and an FB variable, which hold
    milliseconds, encoded with the finest time base, as STEP 7 encodes the constant."""
    if row.value is None:
        return "0"
    code = val(row.value)
    if row.qualifier.upper() not in ("TL", "TD", "TF"):
        return code
    if isinstance(row.value, Operand) and resolve(row.value).kind == "mem":
        return code
    return f"_s5t({code})"


def _row(
    i: int,
    row: ActionRow,
    g: CodeGen,
    resolve: Resolve,
    val: Callable[[Expr], str],
    sidx: StepIndex,
    tidx: StepIndex,
) -> list[str]:
    """The statements of one row, without its event/interlock guard (N/D/L include C)."""
    q = row.qualifier.upper()
    op = row.operand
    gate = " and c_ok" if row.interlocked else ""
    if isinstance(op, Assignment):  # an N action: ZERO_OP holds it back as it does a CALL
        code = gen_assigned(op.expr, resolve(op.target), g, resolve, sidx, tidx)
        return ["if not zero:", *(f"    {line}" for line in code.splitlines())]
    if q == "N":
        ref = _bit(row, resolve)
        return [g.write(ref, f"not zero{gate}")]
    if q in ("S", "R"):
        return [g.set_bit(_bit(row, resolve), q == "S")]
    if q in ("D", "L"):
        ref = _bit(row, resolve)
        if row.value is None:
            raise ActionError(f"{q} needs a time", row.loc)
        t = f"st.t_ns[_i] {'>=' if q == 'D' else '<'} ({val(row.value)}) * 1000000"
        return [g.write(ref, f"not zero{gate} and {t}")]
    if q == "CALL":
        if not isinstance(op, BlockCall):
            raise ActionError("CALL needs a block", row.loc)
        lines = [call_code(op, val, resolve)]
        lines = ["if not zero:", f"    {lines[0]}"]
        for name, target in op.outputs:
            lines.append(f"    if {name!r} in _o:")
            lines.append(f"        {g.write_returned(resolve(target), f'_o[{name!r}]')}")
        return lines
    if q in ("ON", "OFF"):
        if not isinstance(op, StepTarget):
            raise ActionError(f"{q} needs a step (Sn or S_ALL)", row.loc)
        if op.step is None:
            return ["R.off_all(_i)"]
        k = sidx(op.step, op.loc)
        return [f"R.{q.lower()}({k})"]
    if q in ("CS", "CU", "CD", "CR", "TL", "TD", "TF", "TR"):
        if not isinstance(op, Operand):
            raise ActionError(f"{q} needs a timer or counter", row.loc)
        ref = resolve(op)
        if ref.kind not in ("timer", "counter"):
            raise ActionError(
                f"{q} {op.name}: not a {'counter' if q[0] == 'C' else 'timer'}", row.loc
            )
        value = _cell_value(row, val, resolve)
        fn = "counter" if q[0] == "C" else "timer"
        return [f"R.{fn}({q!r}, {ref.number}, {value})"]
    raise ActionError(f"unknown qualifier {row.qualifier}", row.loc)
