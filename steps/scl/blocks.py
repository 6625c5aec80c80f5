"""Compiled SCL → engine blocks, and a program loaded into a CPU (docs/scl.md, "Loading
and running"; docs/runtime.md, "Programs of blocks in Python").

An FB becomes an ``engine.blocks.FB`` whose instance DB holds its IN, OUT, IN_OUT and VAR
(an ARRAY or STRUCT as a list or dict, a multi-instance as an ``InstanceDB``); an FC an
``engine.blocks.FC`` whose RET_VAL is the function value; an OB an ``engine.blocks.OB``;
a global DATA_BLOCK an ``engine.blocks.DB`` with its initial bytes laid out as S7 lays out
a DB. ``SclProgram.load(cpu)`` downloads them and creates the instance DBs the source
names. An error inside a block names the statement's place (``file:line:col``) and is a
block error: OB121, else STOP.
"""

from __future__ import annotations

import types as pytypes
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

from s7graph.engine.blocks import DB, FB, FC, OB, Decl, Var
from s7graph.engine.context import _Fault
from s7graph.engine.errors import ProgramError, S7Error, SourceLocation
from s7graph.engine.symbols import SymbolTable
from s7graph.steps.scl import model as m
from s7graph.steps.scl import types as ty
from s7graph.steps.scl.compile import Generated, translate
from s7graph.steps.scl.consts import Consts, adapt
from s7graph.steps.scl.declare import BlockInfo, Program, struct_initial
from s7graph.steps.scl.diagnostics import Diagnostic, Problem, SclError, error, sort_key
from s7graph.steps.scl.layout import db_layout
from s7graph.steps.scl.runtime import _encode
from s7graph.steps.scl.state import SclState, type_text


@dataclass
class SclProgram:
    """The blocks of one compiled source, ready to load; ``diagnostics`` holds warnings."""

    blocks: list[OB | FB | FC | DB]
    instances: dict[int, str]
    instance_values: dict[int, dict[str, object]] = field(default_factory=dict)
    diagnostics: list[Diagnostic] = field(default_factory=list)
    python: str = ""
    """The generated module's source (for reading, never run as text)."""
    types: dict[str, ty.SclType] = field(default_factory=dict)
    """The structure of each FB's instance (its IN, OUT, IN_OUT and VAR) and of each global
    DB, by label: what a DB variable is read by name with (``steps.scl.access``)."""
    places: dict[str, SourceLocation] = field(default_factory=dict)
    """Where each block is written, by label (``FB17``, ``DB10``): the place a conflict
    with another source names."""

    def block(self, label: str) -> OB | FB | FC | DB:
        for blk in self.blocks:
            if blk.label == label.upper():
                return blk
        raise KeyError(label)

    def load(self, cpu: Any) -> None:
        """Download the blocks into ``cpu`` and create (or keep) the instance DBs."""
        cpu.load(*self.blocks)
        for number, label in sorted(self.instances.items()):
            fb = cpu.block(label)
            have = cpu.instance_dbs.get(number)
            if have is None:
                idb = cpu.create_instance_db(number, fb)
            elif have.fb != fb:
                idb = cpu.replace_instance_db(number, fb)
            else:
                continue
            for name, value in self.instance_values.get(number, {}).items():
                idb.presets[name] = _factory(value)  # a cold restart comes back to it
                idb[name] = ty.clone(value)


def compile_scl(
    text: str,
    file: str = "<input>",
    *,
    blocks: Iterable[FB | FC] = (),
    names: Mapping[str, str] | None = None,
    symbols: SymbolTable | None = None,
) -> SclProgram:
    """Compile an SCL source into engine blocks; :class:`SclError` lists every problem.

    ``blocks``: engine blocks the source may call by label or name (the system blocks of
    ``sfb``, blocks already loaded); ``names``: block symbols (``{"ACQUIRE": "FB10"}``);
    ``symbols``: the operand symbol table."""
    source, prog, generated, diags = translate(
        text, file, blocks=list(blocks), names=names, symbols=symbols
    )
    if generated is None:
        raise SclError(diags)
    return build_program(source, prog, generated, diags)


def build_program(
    source: m.Source, prog: Program, generated: Generated, diags: list[Diagnostic]
) -> SclProgram:
    """The engine blocks of a translated source (``compile.translate``): what
    :func:`compile_scl` returns (:class:`SclError` when a block cannot be built)."""
    out, problems = _build(source, prog, generated)
    if problems:
        raise SclError(sorted(problems + diags, key=sort_key))
    out.diagnostics = diags
    return out


def _build(source: m.Source, prog: Program, gen: Generated) -> tuple[SclProgram, list[Diagnostic]]:
    ns = gen.namespace()
    built: dict[str, FB | FC] = {}
    out = SclProgram([], dict(prog.instances), python=gen.source)
    problems: list[Diagnostic] = []
    for unit in source.units:
        info = prog.block(unit.name)
        if info is None or info.unit is not unit:
            continue
        try:
            blk = _engine_block(prog, info, gen, ns, built)
        except Problem as p:
            problems.append(error(p.code, p.message, p.loc, info.label))
            continue
        if info.kind == "DB" and info.instance_of:
            out.instance_values[info.number] = _instance_inits(prog, info)
        if info.kind in ("FB", "FC", "OB", "DB"):
            out.places[info.label] = unit.loc
        if info.kind == "FB":
            fields = tuple((p.name, p.type) for p in info.params.values())
            out.types[info.label] = ty.SclType("STRUCT", fields=fields, name=info.label)
        elif info.kind == "DB" and info.db_type is not None:
            out.types[info.label] = info.db_type
        if blk is None:
            continue
        if isinstance(blk, FB | FC):
            built[blk.label] = blk
        out.blocks.append(blk)
    return out, problems


def _engine_block(
    prog: Program, info: BlockInfo, gen: Generated, ns: dict[str, Any], built: dict[str, FB | FC]
) -> OB | FB | FC | DB | None:
    if info.kind == "DB":
        return _data_block(prog, info) if info.db_type is not None else None
    if info.kind not in ("FB", "FC", "OB"):
        return None
    fn = ns[gen.functions[info.label]]
    name = info.name if not info.name.upper().startswith(info.kind) else info.label
    if info.kind == "OB":
        return OB(info.number, name, _located(fn, gen, info.label))
    interface = tuple(_var(prog, p, built, info) for p in info.params.values())
    if info.kind == "FB":
        fmt = _state_format(info, built)
        return FB(info.number, name, interface, _located(fn, gen, info.label), state_format=fmt)
    ret = ty.engine_type(info.ret) if info.ret is not None else None
    return FC(info.number, name, interface, _located(fn, gen, info.label), ret_type=ret)


def _var(prog: Program, p: Any, built: dict[str, FB | FC], info: BlockInfo) -> Var:
    t: ty.SclType = p.type
    if t.kind == "FB":
        fb = built.get(t.name)
        owner = prog.block(t.name)
        if fb is None and owner is not None and isinstance(owner.engine, FB):
            fb = owner.engine
        if not isinstance(fb, FB):
            raise Problem("E213", f"{t.name} must be declared before its instance {p.name}", p.loc)
        return Var(p.name, fb.label, Decl.STAT, fb)
    init = p.init
    if t.aggregate:
        value = init if init is not None else ty.zero(t)
        return Var(p.name, "OBJECT", p.decl, _factory(value) if info.kind == "FB" else None)
    if t.kind == "BLOCK_DB":  # the engine knows it as the WORD holding the DB's number
        return Var(p.name, ty.engine_type(t), p.decl, comment=ty.BLOCK_DB.kind)
    return Var(p.name, ty.engine_type(t), p.decl, init if info.kind == "FB" else None)


def _state_format(info: BlockInfo, built: dict[str, FB | FC]) -> SclState:
    """How the FB's instances are recognised in a state file (``steps.scl.state``)."""
    prints: dict[str, str] = {}
    for label, blk in built.items():
        fmt = getattr(blk, "state_format", None)
        if isinstance(blk, FB) and fmt is not None:
            prints[label] = fmt.fingerprint
    return SclState(tuple((p.name, type_text(p.type, prints)) for p in info.params.values()))


def _factory(value: object) -> Callable[[], object]:
    return lambda: ty.clone(value)


# ---------------------------------------------------------------- located block errors


def _located(fn: Callable[..., Any], gen: Generated, label: str) -> Callable[..., Any]:
    """``fn`` whose errors name the source place of the statement that raised them."""

    def body(ctx: Any, *arg: Any) -> Any:
        try:
            return fn(ctx, *arg)
        except _Fault:
            raise
        except Exception as exc:
            raise _locate(exc, gen) from None

    body.__name__ = f"scl_{label}"
    return body


def _locate(exc: Exception, gen: Generated) -> Exception:
    where = _where(exc.__traceback__, gen)
    if isinstance(exc, S7Error):
        if exc.where is None and where is not None:
            exc.where = where
            exc.args = (f"{where}: {exc.message}",)
        return exc
    located = ProgramError(f"{type(exc).__name__}: {exc}", where)
    located.__cause__ = exc
    return located


def _where(tb: pytypes.TracebackType | None, gen: Generated) -> SourceLocation | None:
    found = None
    while tb is not None:
        if tb.tb_frame.f_code.co_filename == gen.filename:
            found = tb.tb_lineno
        tb = tb.tb_next
    if found is None or not 1 <= found <= len(gen.lines):
        return None
    return gen.lines[found - 1]


# ---------------------------------------------------------------- data blocks


def _data_block(prog: Program, info: BlockInfo) -> DB:
    """A global DB: its structure laid out, initial values and BEGIN assignments in."""
    unit, t = info.unit, info.db_type
    assert unit is not None and t is not None and unit.of is not None
    consts = Consts()
    value = struct_initial(prog, unit.of, consts) or ty.zero(t)
    assert isinstance(value, dict)
    for assign in unit.body:
        if isinstance(assign, m.Assign):
            _db_assign(consts, t, value, assign)
    size = ty.size_of(t)
    image = bytearray(size)
    _encode(image, 0, 0, t, value)
    return DB(info.number, size, bytes(image), name=info.name, layout=db_layout(t))


def _db_assign(consts: Consts, t: ty.SclType, value: dict[str, object], a: m.Assign) -> None:
    """``VALUE[1] := 5;`` in a DATA_BLOCK's BEGIN section (constant indices and values)."""
    container: Any = value
    ct = t
    key: Any = None
    steps: list[m.Selector] = [m.Member(a.target.base.text, a.target.base.loc), *a.target.selectors]
    for sel in steps:
        if key is not None:
            container = container[key]
        if isinstance(sel, m.Member) and ct.kind == "STRUCT":
            found = ct.field_type(sel.name)
            if found is None:
                raise SclError([error("E224", f"no member {sel.name!r}", sel.loc)])
            key, ct = found
        elif isinstance(sel, m.Index) and ct.kind == "ARRAY" and len(sel.items) == len(ct.dims):
            assert ct.element is not None
            flat, stride = 0, 1
            for (lo, hi), item in reversed(list(zip(ct.dims, sel.items, strict=True))):
                i = consts.integer(item)
                if not lo <= i <= hi:
                    raise SclError([error("E225", f"index {i} outside {lo}..{hi}", item.loc)])
                flat += (i - lo) * stride
                stride *= hi - lo + 1
            key, ct = flat, ct.element
        else:
            raise SclError([error("E224", "not a member or element of the DB", sel.loc)])
    c = consts.evaluate(a.value)
    v = adapt(c, ct)
    if v is None:
        raise SclError([error("E216", f"{c.type} does not fit {ct}", a.value.loc)])
    container[key] = v


def _instance_inits(prog: Program, info: BlockInfo) -> dict[str, object]:
    """``DATA_BLOCK DB10 FB17 BEGIN x := 5; s.p := 7; a[2] := 9; END_DATA_BLOCK``: the
    values set, each variable whole (a STRUCT's or an ARRAY's other parts at their initial
    values); a name the FB lacks is E224 at the assignment."""
    unit = info.unit
    fb = prog.block(info.instance_of)
    assert unit is not None and fb is not None
    params = [p for p in fb.params.values() if p.type.kind != "FB"]  # not multi-instances
    t = ty.SclType("STRUCT", fields=tuple((p.name, p.type) for p in params))
    value: dict[str, object] = {
        p.name: ty.clone(p.init) if p.init is not None else ty.zero(p.type) for p in params
    }
    consts = Consts()
    set_: list[str] = []
    for a in unit.body:
        if not isinstance(a, m.Assign):
            raise SclError([error("E224", "an instance's variable is set by name", unit.loc)])
        _db_assign(consts, t, value, a)
        found = t.field_type(a.target.base.text)
        if found is not None and found[0] not in set_:
            set_.append(found[0])
    return {name: value[name] for name in set_}
