"""Compile a source ``Chart`` into a ``CompiledChart`` (DESIGN "A compiled chart is
immutable data"; SPEC §2.1, §2.8, §2.9).

The validator runs first; any error-severity diagnostic raises ``ChartError`` carrying all of
them. Then every operand is resolved once (symbol → address, FB variable, FB pin, step or
transition attribute), and all conditions and action rows are rendered into one Python
module compiled with ``compile()``; nothing is interpreted per scan.

Name resolution (SPEC §2.9) is ``sequencer.names.resolve_operand``, shared with the
validator: ``"quoted"`` → symbol; otherwise FB static variable, FB pin, S7 address.
"""

from __future__ import annotations

import re
from typing import Any

from engine.address import Area, Width
from engine.errors import S7Error, SourceLocation
from sequencer.compiled import CompiledChart
from sequencer.model import BlockCall, Chart, Coil, Operand, Transition
from sequencer.names import resolve_operand
from sequencer.params import pin as pin_info
from steps.actions import gen_step_actions
from steps.conditions import contact_text, contacts, gen_condition, with_locals
from steps.expressions import gen_value
from steps.operands import WIDTH_TYPE, CodeGen, Ref


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


def _validate(chart: Chart, symbols: Any) -> tuple[list[Any], list[Any]]:
    """Run ``sequencer.validate`` when present; return (errors, warnings)."""
    try:
        from sequencer.validate import validate  # written by H4
    except ImportError:
        return [], []
    diags = list(validate(chart, symbols))
    errors = [d for d in diags if str(getattr(d, "severity", "error")).lower().endswith("error")]
    warnings = [d for d in diags if d not in errors]
    return errors, warnings


class _Resolver:
    def __init__(self, chart: Chart, symbols: Any, step_index: dict[int, int],
                 tr_index: dict[int, int]) -> None:  # fmt: skip
        self.chart = chart
        self.symbols = symbols
        self.step_index = step_index
        self.tr_index = tr_index
        self.vars = {v.name.upper(): v for v in chart.vars}
        self.problems: list[_Problem] = []
        self.cache: dict[tuple[str, bool], Ref] = {}

    def __call__(self, op: Operand) -> Ref:
        key = (op.name, op.quoted)
        ref = self.cache.get(key)
        if ref is None:
            try:
                ref = self._resolve(op)
            except S7Error as exc:
                self.problems.append(_Problem(op.loc, exc.message))
                ref = Ref("var", "BOOL", name=f"?{op.name}")
            self.cache[key] = ref
        return ref

    def _resolve(self, op: Operand) -> Ref:
        """The operand as the generated code addresses it; the lookup order is the one rule
        of ``sequencer.names.resolve_operand`` (SPEC §1.1, §2.7)."""
        r = resolve_operand(op, self.chart, self.symbols)
        if r.kind == "var":
            return Ref("var", r.type, name=self.vars[op.name.upper()].name)
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
        return Ref("timer" if addr.area is Area.T else "counter", "BOOL", name=name,
                   number=addr.byte)  # fmt: skip
    t = type_name or WIDTH_TYPE[int(addr.width)]
    if addr.width is Width.BIT:
        t = "BOOL"
    return Ref("mem", t, name=name, area=str(addr.area), db=addr.db, byte=addr.byte,
               bit=addr.bit)  # fmt: skip


def _priority(seq_transitions: tuple[Transition, ...]) -> dict[int, int]:
    return {t.number: k for k, t in enumerate(seq_transitions)}


def compile_chart(chart: Chart, symbols: Any = None) -> CompiledChart:
    """Validate and compile ``chart``; raise ``ChartError`` listing every error."""
    errors, warnings = _validate(chart, symbols)
    if errors:
        raise ChartError(errors)
    steps = chart.all_steps()
    trans = chart.all_transitions()
    step_index = {s.number: i for i, s in enumerate(steps)}
    tr_index = {t.number: j for j, t in enumerate(trans)}
    if len(step_index) != len(steps) or len(tr_index) != len(trans):
        raise ChartError([_Problem(chart.loc, "step and transition numbers must be unique")])
    res = _Resolver(chart, symbols, step_index, tr_index)
    g = CodeGen()
    parts: list[str] = []

    step_seq: list[int] = []
    tr_seq: list[int] = []
    for k, seq in enumerate(chart.sequences):
        step_seq += [k] * len(seq.steps)
        tr_seq += [k] * len(seq.transitions)

    tr_src = tuple(tuple(res.step(s, t.loc) for s in t.sources) for t in trans)
    tr_dst = tuple(tuple(res.step(s, t.loc) for s in t.targets) for t in trans)
    # leaving transitions per step in written order (SPEC §2.2 4b: leftmost/first-listed wins)
    leaving: list[list[int]] = [[] for _ in steps]
    for j, srcs in enumerate(tr_src):
        for i in srcs:
            leaving[i].append(j)

    for j, t in enumerate(trans):
        parts.append(gen_condition(f"_t{j}", t.condition, g, res, res.step, res.transition))
    for i, s in enumerate(steps):
        if s.interlock is not None:
            parts.append(gen_condition(f"_il{i}", s.interlock, g, res, res.step, res.transition))
        if s.supervision is not None:
            parts.append(gen_condition(f"_sv{i}", s.supervision, g, res, res.step, res.transition))
        try:
            a_src, f_src = gen_step_actions(i, s, g, res, res.step, res.transition)
        except S7Error as exc:
            res.problems.append(_Problem(exc.where or s.loc, f"S{s.number}: {exc.message}"))
            a_src = f"def _a{i}(st, R, ev, c_ok, zero):\n    pass\n"
            f_src = f"def _f{i}(st, R, ev):\n    pass\n"
        parts += [a_src, f_src]
    parts.append(_gen_permanent("_before", chart.before, g, res))
    parts.append(_gen_permanent("_after", chart.after, g, res))

    if res.problems:
        raise ChartError(res.problems)
    source = "\n".join(_share(parts))
    code = compile(source, f"<chart {chart.name}>", "exec")
    var_inits = {
        v.name: (v.init.value if v.init is not None else _zero(v.type)) for v in chart.vars
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
        consts=dict(g.consts),
        step_index=step_index,
        transition_index=tr_index,
        warnings=tuple(str(w) for w in warnings),
    )


_OWN_INDEX = re.compile(r", _i=(\d+)\):")


def _share(parts: list[str]) -> list[str]:
    """Generated functions with the same code (apart from their name and the own-step
    default ``_i``) are compiled once: the others are bound to the first one's function
    (``_with_index`` gives it another ``_i``). Keeps ``compile()`` proportional to the
    distinct code, not to the steps (bench: 250 steps, 1000 functions → 3 distinct)."""
    seen: dict[str, tuple[str, str | None]] = {}
    out: list[str] = []
    for src in parts:
        head, _, rest = src.partition("(")
        name = head[4:]
        m = _OWN_INDEX.search(rest, 0, rest.find("\n"))
        own = m.group(1) if m else None
        key = _OWN_INDEX.sub(", _i=):", rest, 1) if m else rest
        first = seen.get(key)
        if first is None:
            seen[key] = (name, own)
            out.append(src)
        elif first[1] == own:
            out.append(f"{name} = {first[0]}\n")
        else:
            out.append(f"{name} = _with_index({first[0]}, {own})\n")
    return out


def _zero(type_name: str) -> Any:
    t = type_name.upper()
    if t == "BOOL":
        return False
    if t == "REAL":
        return 0.0
    if t.startswith("STRING"):
        return ""
    return 0


def _gen_permanent(name: str, instrs: tuple[Any, ...], g: CodeGen, res: _Resolver) -> str:
    """``def name(st, R)``: permanent instructions, in order (SPEC §2.2 steps 3 and 5)."""
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
            inputs = ", ".join(f"{n!r}: {val(e)}" for n, e in ins.inputs)
            lines.append(
                f"    _o = R.call({ins.kind!r}, {ins.block!r}, {ins.instance!r}, {{{inputs}}})"
            )
            for pname, target in ins.outputs:
                lines.append(f"    if {pname!r} in _o:")
                lines.append("        " + g.write(res(target), f"_o[{pname!r}]"))
        else:  # Assignment
            lines.append("    " + g.write(res(ins.target), val(ins.expr)))
    if len(lines) == 1:
        lines.append("    pass")
    return with_locals(lines)
