"""Compile a source ``Chart`` into a ``CompiledChart`` (docs/architecture.md, "The core is a
function"; docs/semantics.md, "Structure" and "Actions" and "Conditions").

The validator runs first; any error-severity diagnostic raises ``ChartError`` carrying all of
them. Then every operand is resolved once (symbol → address, FB variable, FB pin, step or
transition attribute), and all conditions and action rows are rendered into one Python
module compiled with ``compile()``; nothing is interpreted per scan.

Name resolution (docs/semantics.md, "Conditions") is ``sequencer.names.resolve_operand``, shared
with the validator: ``"quoted"`` → symbol; otherwise FB static variable, FB pin, S7 address.
"""

from __future__ import annotations

import re
from dataclasses import replace
from typing import Any

from s7graph.engine.address import Area, Width
from s7graph.engine.datatypes import DATE_EPOCH, DT_MIN, real32
from s7graph.engine.errors import S7Error, SourceLocation
from s7graph.sequencer.checks.interfaces import ProgramBlocks
from s7graph.sequencer.checks.validate import validate
from s7graph.sequencer.collector import collector_paused
from s7graph.sequencer.compiled import CompiledChart, Reach
from s7graph.sequencer.params import pin as pin_info
from s7graph.sequencer.text.model import ActionRow, BlockCall, Chart, Coil, Const, Operand, Step
from s7graph.sequencer.text.names import db_argument, resolve_operand
from s7graph.steps.actions import ActionParts, call_code, step_action_parts, uses_own_index
from s7graph.steps.conditions import (
    condition_parts,
    condition_source,
    contact_text,
    contacts,
    gen_condition,
    with_locals,
)
from s7graph.steps.diagnostics import Diagnostic, format_diagnostic
from s7graph.steps.expressions import gen_assigned, gen_value
from s7graph.steps.operands import TYPE_BYTES, WIDTH_TYPE, CodeGen, Ref


class ChartError(S7Error):
    """A chart that does not compile; ``diagnostics`` holds every problem found."""

    def __init__(self, diagnostics: list[Any]) -> None:
        self.diagnostics = list(diagnostics)
        text = "\n".join(str(d) for d in self.diagnostics) or "chart does not compile"
        super().__init__(text)


class _Problem:
    def __init__(
        self, where: SourceLocation | str | None, message: str, severity: str = "error"
    ) -> None:
        self.where = where
        self.message = message
        self.severity = severity

    def __str__(self) -> str:
        return f"{self.where}: {self.severity}: {self.message}"


def _validate(
    chart: Chart, symbols: Any, blocks: ProgramBlocks | None
) -> tuple[list[Diagnostic], list[Diagnostic]]:
    """``sequencer.checks.validate``'s diagnostics: (errors, warnings)."""
    diags = list(validate(chart, symbols, readable=blocks))
    errors = [d for d in diags if d.severity == "error"]
    return errors, [d for d in diags if d.severity != "error"]


class _Resolver:
    def __init__(
        self,
        chart: Chart,
        symbols: Any,
        step_index: dict[int, int],
        tr_index: dict[int, int],
        blocks: ProgramBlocks | None = None,
    ) -> None:
        self.chart = chart
        self.symbols = symbols
        self.blocks = blocks
        self.step_index = step_index
        self.tr_index = tr_index
        self.vars = {v.name.upper(): v for v in chart.vars}
        self.problems: list[_Problem] = []
        self.cache: dict[tuple[str, bool, str], Ref] = {}
        self.reach: dict[tuple[str, int | None], tuple[int, str]] = {}
        """Per area (and DB): the end of the furthest byte an operand uses, and its name."""

    def reaches(self) -> tuple[Reach, ...]:
        """What the chart's operands reach: ``(area, db, end byte, operand)`` — for a timer
        or counter cell the area ``T``/``C`` and the cell's number + 1 (``CompiledChart.bind``
        checks each against the memory it is bound to)."""
        return tuple((area, db, end, name) for (area, db), (end, name) in self.reach.items())

    def _note(self, ref: Ref) -> None:
        if ref.kind == "mem":
            key, end = (ref.area, ref.db), ref.byte + max(TYPE_BYTES.get(ref.type, 1), 1)
        elif ref.kind in ("timer", "counter"):
            key, end = ("T" if ref.kind == "timer" else "C", None), ref.number + 1
        else:
            return
        if end > self.reach.get(key, (0, ""))[0]:
            self.reach[key] = (end, ref.name)

    def __call__(self, op: Operand) -> Ref:
        key = (op.name, op.quoted, op.member)
        ref = self.cache.get(key)
        if ref is None:
            try:
                ref = self._resolve(op)
            except S7Error as exc:
                self.problems.append(_Problem(op.loc, exc.message))
                ref = Ref("var", "BOOL", name=f"?{op.name}")
            self._note(ref)
            self.cache[key] = ref
        return ref

    def _resolve(self, op: Operand) -> Ref:
        """The operand as the generated code addresses it; the lookup order is the one rule
        of ``sequencer.names.resolve_operand`` (docs/runtime.md, "The block runtime";
        docs/semantics.md, "FB pins")."""
        r = resolve_operand(op, self.chart, self.symbols, blocks=self.blocks)
        if r.kind == "var":
            return Ref("var", r.type, name=self.vars[op.name.upper()].name)
        if r.kind == "member":  # an instance DB's variable by name (DB10.Q)
            return Ref("idb", r.type, name=r.member, db=r.db)
        if r.kind == "pin":
            p = pin_info(op.name)
            assert p is not None
            return Ref("pin", p.type, name=p.name)
        assert r.address is not None
        return _addr_ref(r.address, r.type if r.kind == "symbol" else None, op.name)

    def step(self, number: int, loc: Any = None) -> int:
        try:
            return self.step_index[number]
        except KeyError:
            self.problems.append(_Problem(loc, f"no step S{number}"))
            return 0

    def transition(self, number: int, loc: Any = None) -> int:
        try:
            return self.tr_index[number]
        except KeyError:
            self.problems.append(_Problem(loc, f"no transition T{number}"))
            return 0


def _addr_ref(addr: Any, type_name: str | None, name: str) -> Ref:
    if addr.area in (Area.T, Area.C):
        return Ref(
            "timer" if addr.area is Area.T else "counter", "BOOL", name=name, number=addr.byte
        )
    t = type_name or WIDTH_TYPE[int(addr.width)]
    if addr.width is Width.BIT:
        t = "BOOL"
    flex = type_name is None and addr.width is not Width.BIT
    return Ref(
        "mem",
        t,
        name=name,
        area=str(addr.area),
        db=addr.db,
        byte=addr.byte,
        bit=addr.bit,
        flex=flex,
    )


def compile_chart(
    chart: Chart, symbols: Any = None, *, blocks: ProgramBlocks | None = None
) -> CompiledChart:
    """Validate and compile ``chart``; raise ``ChartError`` listing every error. ``blocks``:
    the program's user blocks (``--blocks``), when known: the chart reads their FBs'
    instance DBs' variables by name (its calls are checked against them by ``check`` and
    where the blocks are loaded). The garbage collector is paused meanwhile
    (``sequencer.collector``)."""
    with collector_paused():
        return _compile_chart(chart, symbols, blocks)


def _compile_chart(chart: Chart, symbols: Any, blocks: ProgramBlocks | None) -> CompiledChart:
    errors, warnings = _validate(chart, symbols, blocks)
    if errors:
        raise ChartError(errors)
    steps = chart.all_steps()
    trans = chart.all_transitions()
    step_index = {s.number: i for i, s in enumerate(steps)}
    tr_index = {t.number: j for j, t in enumerate(trans)}
    if len(step_index) != len(steps) or len(tr_index) != len(trans):
        raise ChartError([_Problem(chart.loc, "step and transition numbers must be unique")])
    res = _Resolver(chart, symbols, step_index, tr_index, blocks)
    g = CodeGen()
    parts: list[str] = []

    step_seq: list[int] = []
    tr_seq: list[int] = []
    for k, seq in enumerate(chart.sequences):
        step_seq += [k] * len(seq.steps)
        tr_seq += [k] * len(seq.transitions)

    tr_src = tuple(tuple(res.step(s, t.loc) for s in t.sources) for t in trans)
    tr_dst = tuple(tuple(res.step(s, t.loc) for s in t.targets) for t in trans)
    leaving = alternative_priority(tr_src, tuple(t.number for t in trans), len(steps))

    conds: list[tuple[list[str], str, str]] = []
    for j, t in enumerate(trans):
        conds.append(condition_parts(t.condition, g, res, res.step, res.transition))
        parts.append(condition_source(f"_t{j}", conds[j]))
    rows = _step_functions(steps, g, res, parts)
    nochk = [s.interlock is None and s.supervision is None for s in steps]
    for i, own in enumerate(rows):
        if own is not None and nochk[i] and all(len(tr_src[j]) == 1 for j in leaving[i]):
            parts.append(_gen_step(i, leaving[i], conds, own.rows))
            parts += _enter_functions(i, own, rows, nochk, leaving[i], tr_dst, step_seq)
    parts.append(_gen_permanent("_before", chart.before, g, res))
    parts.append(_gen_permanent("_after", chart.after, g, res))

    if res.problems:
        raise ChartError(res.problems)
    distinct, aliases = _share(parts)
    code = tuple(compile(src, f"<chart {chart.name}>", "exec") for src in _batches(distinct))
    source = "\n".join(_alias_source(src, aliases) for src in parts)
    var_inits = {
        v.name: (_initial(v.type, v.init.value) if v.init is not None else _zero(v.type))
        for v in chart.vars
    }

    def labels(e: Any) -> tuple[str, ...]:
        return tuple(contact_text(c) for c in contacts(e, res))

    return CompiledChart(
        chart=chart,
        options=chart.options,
        parameters=chart.options.parameters.upper(),
        step_numbers=tuple(s.number for s in steps),
        step_names=tuple(s.name for s in steps),
        step_seq=tuple(step_seq),
        initial=tuple(i for i, s in enumerate(steps) if s.initial),
        has_interlock=tuple(s.interlock is not None for s in steps),
        has_supervision=tuple(s.supervision is not None for s in steps),
        transition_numbers=tuple(t.number for t in trans),
        transition_names=tuple(t.name for t in trans),
        tr_seq=tuple(tr_seq),
        tr_src=tr_src,
        tr_dst=tr_dst,
        leaving=tuple(tuple(x) for x in leaving),
        seq_numbers=tuple(s.number for s in chart.sequences),
        seq_names=tuple(s.name for s in chart.sequences),
        seq_steps=tuple(tuple(step_index[s.number] for s in seq.steps) for seq in chart.sequences),
        crit_labels=tuple(labels(t.condition) for t in trans),
        il_labels=tuple(labels(s.interlock) for s in steps),
        sv_labels=tuple(labels(s.supervision) for s in steps),
        var_inits=var_inits,
        var_types={v.name: v.type.upper() for v in chart.vars},
        source=source,
        code=code,
        buffers=tuple(g.buffers),
        idbs=tuple(g.idbs),
        reach=res.reaches(),
        consts=dict(g.consts),
        step_index=step_index,
        transition_index=tr_index,
        warnings=tuple(format_diagnostic(w) for w in warnings),
        aliases=tuple(aliases.values()),
    )


def alternative_priority(
    tr_src: tuple[tuple[int, ...], ...], numbers: tuple[int, ...], n_steps: int
) -> list[list[int]]:
    """The transitions leaving each step in priority order (docs/semantics.md, "Decisions",
    alternative divergence): the one directly below the step — the first written — then the
    others by transition number, lowest first (manual 6-7)."""
    leaving: list[list[int]] = [[] for _ in range(n_steps)]
    for j, srcs in enumerate(tr_src):
        for i in srcs:
            leaving[i].append(j)
    for out in leaving:
        out[1:] = sorted(out[1:], key=numbers.__getitem__)
    return leaving


def _step_functions(
    steps: tuple[Step, ...], g: CodeGen, res: _Resolver, parts: list[str]
) -> list[ActionParts | None]:
    """Append the interlock, supervision and action functions of every step to ``parts``;
    each step's rows for the fused functions, None for a step that runs without them."""
    rows: list[ActionParts | None] = []
    for i, s in enumerate(steps):
        if s.interlock is not None:
            parts.append(gen_condition(f"_il{i}", s.interlock, g, res, res.step, res.transition))
        if s.supervision is not None:
            parts.append(gen_condition(f"_sv{i}", s.supervision, g, res, res.step, res.transition))
        own: ActionParts | None
        actions = tuple(_numbered_row(r, res) for r in s.actions)
        try:
            own = step_action_parts(i, actions, g, res, res.step, res.transition)
            a_src, f_src = own.a_src, own.f_src
        except S7Error as exc:
            res.problems.append(_Problem(exc.where or s.loc, f"S{s.number}: {exc.message}"))
            a_src = f"def _a{i}(st, R, ev, c_ok, zero):\n    pass\n"
            f_src = f"def _f{i}(st, R, ev):\n    pass\n"
            own = None
        parts += [*_split(a_src), *_split(f_src)]
        if own is not None and own.p_src is not None:
            parts.append(own.p_src)
        # a step whose rows had to be split (100,000 rows) runs without the fused functions
        small = own is not None and len(own.rows) + len(own.reset) + len(own.s0) <= _SPLIT_LINES
        rows.append(own if small else None)
    return rows


def _enter_functions(
    i: int,
    own: ActionParts,
    rows: list[ActionParts | None],
    nochk: list[bool],
    leaving: list[int],
    tr_dst: tuple[tuple[int, ...], ...],
    step_seq: list[int],
) -> list[str]:
    """The plain switches of the fast path out of step ``i`` (``Program.enter``)."""
    out: list[str] = []
    for j in leaving:
        d = tr_dst[j][0] if len(tr_dst[j]) == 1 else -1
        target = rows[d] if d >= 0 and nochk[d] and step_seq[d] == step_seq[i] else None
        if target is not None and not uses_own_index(own.s0):
            out.append(_gen_enter(j, d, own, target))
    return out


def _gen_step(
    i: int, leaving: list[int], conds: list[tuple[list[str], str, str]], a_body: list[str]
) -> str:
    """``def _s<i>(st, R, ev, c_ok, zero, _i, _j0, …) -> int`` (``Program.step``): step
    ``i``'s leaving transitions in priority order, each as ``tcond`` then ``crit_old``/
    ``crit``/``tt`` as the cycle writes them — every one of them, as step 4.1 evaluates every
    valid transition (``switching.switch``); the first that holds is returned, else the
    step's action rows run and -1 is returned. The indices are defaults, so the code of
    like steps is shared (``_share``)."""
    defaults = "".join(f", _j{k}={j}" for k, j in enumerate(leaving))
    lines = [f"def _s{i}(st, R, ev, c_ok, zero, _i={i}{defaults}):"]
    if leaving:
        lines += ["    _cr = st.crit", "    _tt = st.tt", "    _co = st.crit_old"]
    if len(leaving) > 1:
        lines.append("    _r = -1")
    for k, j in enumerate(leaving):
        body, value, crit = conds[j]
        lines += body
        lines += [
            f"    _v = {value}",
            f"    _co[_j{k}] = _cr[_j{k}]",
            f"    _cr[_j{k}] = {crit}",
            f"    _tt[_j{k}] = _v",
        ]
        if len(leaving) == 1:
            lines += ["    if _v:", f"        return _j{k}"]
        else:  # the first that holds wins; the others are evaluated all the same
            lines += ["    if _v and _r < 0:", f"        _r = _j{k}"]
    if len(leaving) > 1:
        lines += ["    if _r >= 0:", "        return _r"]
    lines += a_body
    lines.append("    return -1")
    return with_locals(lines)


def _gen_enter(j: int, d: int, left: ActionParts, entered: ActionParts) -> str:
    """``def _w<j>(st, R, ev, ev_d, zero, _i=d)`` (``Program.enter``): transition ``j``
    has switched from its plain source step to its only target ``d`` (same sequencer, no
    interlock, no supervision); the final scan of the source (N/D/L resets, then its S0
    rows with ``ev`` its events, as ``_f``), then the rows of ``d`` with its events
    ``ev_d`` and its interlock held (as ``_a``). ``_i`` is ``d``: a final scan never uses
    its own index."""
    lines = [f"def _w{j}(st, R, ev, ev_d, zero, _i={d}):", *left.reset]
    if left.s0:
        lines += ["    c_ok = True", *left.s0]
    lines += ["    ev = ev_d", "    c_ok = True", *entered.rows]
    return with_locals(lines)


_DEFAULTS = re.compile(r"((?:, _[ij]\d*=\d+)+)\):")
_DEFAULT_VALUE = re.compile(r"=(\d+)")


Alias = tuple[str, str, "tuple[int, ...] | None"]


_SPLIT_LINES = 400
"""A generated action function longer than this is split into functions of about this
many lines (called in order), and its step gets no fused function: ``compile()`` then needs
memory in proportion to the longest function, not to the rows of the chart."""
_BATCH_CHARS = 200_000
"""Generated source compiled at once, at most (as above, for charts of many steps)."""
_PARAM_ASSIGNMENT = re.compile(r"    (c_ok|zero) = ")


def _split(src: str) -> list[str]:
    """``src`` (a ``def`` of ``st R ev …`` whose top-level statements share no locals but
    its parameters) as itself, or — when longer than ``_SPLIT_LINES`` — as a function
    calling parts of its body in order, and those parts. An assignment to a parameter
    (``c_ok = True`` before the S0 rows of a final scan) stays in the caller."""
    lines = src.rstrip("\n").split("\n")
    if len(lines) <= _SPLIT_LINES:
        return [src]
    head, body = lines[0], lines[1:]
    while body and body[0] in ("    X = st.x", "    V = st.vars"):
        body = body[1:]  # with_locals binds them again where needed
    name = head[4 : head.index("(")]
    params = head[head.index("(") + 1 : head.rindex(")")]
    args = ", ".join(p.split("=")[0].strip() for p in params.split(","))
    statements: list[list[str]] = []
    for ln in body:
        top = ln.startswith("    ") and not ln.startswith("     ")
        if (top and not ln.lstrip().startswith(("elif ", "else:"))) or not statements:
            statements.append([ln])
        else:
            statements[-1].append(ln)
    caller: list[str] = [head]
    pieces: list[str] = []
    chunk: list[str] = []

    def flush() -> None:
        if chunk:
            k = len(pieces)
            pieces.append(with_locals([f"def {name}__{k}({params}):", *chunk]))
            caller.append(f"    {name}__{k}({args})")
            chunk.clear()

    for statement in statements:
        if len(statement) == 1 and _PARAM_ASSIGNMENT.match(statement[0]):
            flush()
            caller.extend(statement)
            continue
        chunk.extend(statement)
        if len(chunk) >= _SPLIT_LINES:
            flush()
    flush()
    return [with_locals(caller), *pieces]


def _batches(sources: list[str]) -> list[str]:
    """``sources`` joined into pieces of at most about ``_BATCH_CHARS`` characters."""
    out: list[str] = []
    batch: list[str] = []
    size = 0
    for src in sources:
        if batch and size + len(src) > _BATCH_CHARS:
            out.append("\n".join(batch))
            batch, size = [], 0
        batch.append(src)
        size += len(src) + 1
    if batch:
        out.append("\n".join(batch))
    return out


def _share(parts: list[str]) -> tuple[list[str], dict[str, Alias]]:
    """Generated functions with the same code (apart from their name and the index
    defaults ``_i``, ``_j0``, …) are compiled once: the others are aliases of the first one
    — (name, first name, its other defaults or None), bound by ``CompiledChart.bind``.
    Keeps ``compile()`` proportional to the distinct code, not to the steps (bench: 250
    steps, 1000 functions → 5 distinct). Returns the distinct sources and the aliases by
    name."""
    seen: dict[str, tuple[str, tuple[int, ...] | None]] = {}
    out: list[str] = []
    aliases: dict[str, Alias] = {}
    for src in parts:
        head, _, rest = src.partition("(")
        name = head[4:]
        m = _DEFAULTS.search(rest, 0, rest.find("\n"))
        own = None
        key = rest
        if m:
            own = tuple(int(v) for v in _DEFAULT_VALUE.findall(m.group(1)))
            key = rest[: m.start(1)] + _DEFAULT_VALUE.sub("=", m.group(1)) + rest[m.end(1) :]
        first = seen.get(key)
        if first is None:
            seen[key] = (name, own)
            out.append(src)
        else:
            aliases[name] = (name, first[0], None if first[1] == own else own)
    return out, aliases


def _alias_source(src: str, aliases: dict[str, Alias]) -> str:
    """``src`` for ``CompiledChart.source``: an alias as the assignment it stands for."""
    a = aliases.get(src[4 : src.find("(")])
    if a is None:
        return src
    if a[2] is None:
        return f"{a[0]} = {a[1]}\n"
    return f"{a[0]} = _with_defaults({a[1]}, {a[2]!r})\n"


def _initial(type_name: str, value: Any) -> Any:
    """A variable's initial value as its type holds it (a REAL's 32 bits)."""
    return real32(value) if type_name.upper() == "REAL" and isinstance(value, float) else value


def _zero(type_name: str) -> Any:
    """A variable's value without an initial one: FALSE, 0, 0.0, '', and for a date the
    first the CPU knows (D#1990-01-01, DT#1990-01-01-0:0:0), as S7 starts them."""
    t = type_name.upper()
    if t == "BOOL":
        return False
    if t == "REAL":
        return 0.0
    if t.startswith("STRING"):
        return ""
    if t in ("DATE_AND_TIME", "DT"):
        return DT_MIN
    if t == "DATE":
        return DATE_EPOCH
    return 0


def _numbered(call: BlockCall, res: _Resolver) -> BlockCall:
    """``call`` with each DB it passes (``src := DB5``, ``src := "Recipe"``) as the DB's
    number, a WORD: what the BLOCK_DB input of an S7-SCL block holds (the checks and
    ``sequencer.calls`` let a DB go to no other parameter)."""
    inputs = tuple(
        (name, e if (n := db_argument(e, res.chart, res.symbols)) is None else _word(n, e))
        for name, e in call.inputs
    )
    if all(a[1] is b[1] for a, b in zip(inputs, call.inputs, strict=True)):
        return call
    return replace(call, inputs=inputs)


def _word(number: int, e: object) -> Const:
    return Const(number, "WORD", f"W#16#{number:X}", getattr(e, "loc", SourceLocation()))


def _numbered_row(row: ActionRow, res: _Resolver) -> ActionRow:
    if not isinstance(row.operand, BlockCall):
        return row
    call = _numbered(row.operand, res)
    return row if call is row.operand else replace(row, operand=call)


def _gen_permanent(name: str, instrs: tuple[Any, ...], g: CodeGen, res: _Resolver) -> str:
    """``def name(st, R)``: permanent instructions, in order (docs/semantics.md, "One FB call",
    steps 3 and 5)."""
    lines = [f"def {name}(st, R):"]

    def val(e: Any) -> str:
        return gen_value(e, g, res, res.step, res.transition)

    for ins in instrs:
        if isinstance(ins, Coil):
            ref = res(ins.target)
            cond = val(ins.condition)
            if ins.kind == "=":
                lines.append("    " + g.write(ref, f"bool({cond})"))
            else:
                lines.append(f"    if {cond}:")
                lines.append("        " + g.set_bit(ref, ins.kind == "S"))
        elif isinstance(ins, BlockCall):
            lines.append("    " + call_code(_numbered(ins, res), val, res))
            for pname, target in ins.outputs:
                lines.append(f"    if {pname!r} in _o:")
                lines.append("        " + g.write_returned(res(target), f"_o[{pname!r}]"))
        else:  # Assignment
            ref = res(ins.target)
            lines.append("    " + gen_assigned(ins.expr, ref, g, res, res.step, res.transition))
    if len(lines) == 1:
        lines.append("    pass")
    return with_locals(lines)
