"""An SCL source → one generated Python module → code objects, compiled once
(docs/scl.md, "How a block runs").

Each FB, FC and OB becomes one function of the module: ``_b_FB17(ctx, db)`` over its
instance DB's values, ``_b_FC1(ctx, P)`` over its parameters, ``_b_OB1(ctx)``. The module is
compiled with ``compile()`` from a checked tree — no name or text of the source becomes
Python: variables are spelled ``t_NAME`` / ``V['Name']`` / ``P['Name']``, constants are
module names ``_kN``. The module runs against the helpers of ``runtime`` and a handful of
builtins, and each function keeps the line → source place table its errors are located by.
"""

from __future__ import annotations

import builtins
import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from types import CodeType
from typing import Any

from s7graph.engine.blocks import FB, FC, Decl
from s7graph.engine.errors import GENERATED_PLACES, SourceLocation
from s7graph.engine.symbols import SymbolTable
from s7graph.steps.scl import model as m
from s7graph.steps.scl import types as ty
from s7graph.steps.scl.calls import Calls
from s7graph.steps.scl.cases import split_arms
from s7graph.steps.scl.declare import BlockInfo, Program, declare
from s7graph.steps.scl.diagnostics import Diagnostic, Problem, SclError, error, sort_key, warning
from s7graph.steps.scl.exprs import Exprs
from s7graph.steps.scl.gen import Block, Module
from s7graph.steps.scl.parse import parse_source
from s7graph.steps.scl.places import Places
from s7graph.steps.scl.runtime import RUNTIME
from s7graph.steps.scl.stmts import Stmts

SAFE_BUILTINS = {n: getattr(builtins, n) for n in ("int", "float", "bool", "len", "min", "max")}
SAFE_BUILTINS |= {"chr": chr, "ord": ord, "abs": abs}
"""The only builtins generated code sees."""
_START_INFO = re.compile(r"OB\d+_(\w+)", re.IGNORECASE)


@dataclass(frozen=True)
class Generated:
    """The compiled module of a source: its code, the functions' names by block label,
    and the source place of each of its lines."""

    source: str
    code: CodeType
    filename: str
    functions: dict[str, str]
    lines: tuple[SourceLocation, ...]
    consts: dict[str, Any]

    def place(self, line: int) -> str | None:
        """The source place of ``line`` of the module."""
        return str(self.lines[line - 1]) if 1 <= line <= len(self.lines) else None

    def namespace(self) -> dict[str, Any]:
        """The module executed: its names, the functions among them."""
        GENERATED_PLACES[self.filename] = self.place
        ns: dict[str, Any] = {"__builtins__": SAFE_BUILTINS}
        ns.update(RUNTIME)
        ns.update(self.consts)
        exec(self.code, ns)  # the generated module, never text of the source
        return ns


def translate(
    text: str,
    file: str = "<input>",
    *,
    blocks: Iterable[FB | FC] = (),
    names: Mapping[str, str] | None = None,
    symbols: SymbolTable | None = None,
) -> tuple[m.Source, Program, Generated | None, list[Diagnostic]]:
    """Parse, declare and generate; the module is None when there are errors."""
    try:
        source = parse_source(text, file)
    except SclError as exc:
        return m.Source((), file), Program(file), None, exc.diagnostics
    prog = declare(source, blocks=blocks, names=names, symbols=symbols)
    _instances(source, prog)
    module = Module()
    parts: list[tuple[str, list[str], list[SourceLocation]]] = []
    diags = list(prog.diags)
    for unit in source.units:
        info = prog.block(unit.name)
        if info is None or info.unit is not unit or info.kind not in ("FB", "FC", "OB"):
            continue
        b = Block(prog, info, module)
        _generate(b)
        diags += b.diags
        parts.append((info.label, b.lines, b.locs))
    diags.sort(key=sort_key)
    if any(d.is_error for d in diags):
        return source, prog, None, diags
    try:
        generated = _assemble(file, parts, module)
    except (RecursionError, MemoryError) as exc:  # CPython's own limits: never a crash
        where = source.units[0].loc if source.units else SourceLocation(file, 1, 1)
        why = "nests too deeply" if isinstance(exc, RecursionError) else "is too large"
        diags.append(error("E204", f"the generated code {why} for Python to compile", where))
        return source, prog, None, diags
    return source, prog, generated, diags


def _assemble(
    file: str, parts: list[tuple[str, list[str], list[SourceLocation]]], module: Module
) -> Generated:
    lines: list[str] = []
    locs: list[SourceLocation] = []
    functions: dict[str, str] = {}
    for label, body, where in parts:
        functions[label] = f"_b_{label}"
        lines += body
        locs += where
    filename = f"<scl {file}>"
    source = "\n".join(lines) + "\n"
    code = compile(source, filename, "exec")
    return Generated(source, code, filename, functions, tuple(locs), dict(module.consts))


# ---------------------------------------------------------------- one block


def _generate(b: Block) -> None:
    """The function of one block: header, prologue, statements, epilogue."""
    info, unit = b.info, b.info.unit
    assert unit is not None
    b.exprs, b.places, b.calls = Exprs(b), Places(b), Calls(b)
    b.declare_locals()
    labels: dict[str, SourceLocation] = {}
    for section in unit.decls:
        if isinstance(section, m.LabelSection):
            for name, loc in section.names:
                if name.upper() in labels:
                    b.report(Problem("E210", f"label {name} is declared twice", loc))
                labels[name.upper()] = loc
    epilogue = {
        "FB": ["return _ok[0]"],
        "FC": ["P['ENO'] = _ok[0]", "return _ret"],
        "OB": ["return None"],
    }[info.kind]
    head = {"FB": "(ctx, db)", "FC": "(ctx, P)", "OB": "(ctx)"}[info.kind]
    b.loc = unit.loc
    body_start = len(b.lines)
    stmts = Stmts(b, labels, epilogue)
    stmts.run(split_arms(unit.body, labels, b.report))
    b.loc = unit.end
    for line in epilogue:
        b.emit(line)
    body, body_locs = b.lines[body_start:], b.locs[body_start:]
    del b.lines[body_start:], b.locs[body_start:]
    b.loc = unit.loc
    b.indent = 0
    b.emit(f"def _b_{info.label}{head}:")
    b.indent = 1
    _prologue(b, sorted(stmts.flags), _USED.findall("\n".join(body)))
    b.lines += body
    b.locs += body_locs
    _finish(b, stmts, labels)


_USED = re.compile(r"\b(V|_mem|_ok|_eno|_M)\b")
"""The names of a block's prologue its body may use: only those used are bound (the loop
meter's look-up, above all, costs a block without loops or jumps nothing)."""


def _prologue(b: Block, flags: list[str], used: list[str]) -> None:
    info = b.info
    need = set(used) | ({"_ok"} if info.kind in ("FB", "FC") else set())  # the epilogue's ENO
    if info.kind == "FB" and "V" in need:
        b.emit("V = db.values")
    for name, value in (("_mem", "ctx.mem"), ("_ok", "[True]"), ("_eno", "[True]")):
        if name in need:
            b.emit(f"{name} = {value}")
    if "_M" in need:
        b.emit("_M = _meter(ctx)")
    for flag in flags:
        b.emit(f"{flag} = {'False' if flag.startswith('_g') else '0'}")
    if info.kind == "FC":
        b.emit(f"_ret = {b.literal_src(ty.zero(info.ret)) if info.ret else 'None'}")
        for p in info.params.values():
            if p.decl is Decl.OUT and p.type.aggregate:
                b.emit(
                    f"if {p.name!r} not in P: P[{p.name!r}] = {b.const(ty.zero_factory(p.type))}()"
                )
    for key, p in info.temps.items():
        b.emit(f"t_{key} = {_temp_initial(b, p.name, p.type)}")


def _temp_initial(b: Block, name: str, t: ty.SclType) -> str:
    """A TEMP's value at block start: its zero, or an OB's start information."""
    if t.aggregate:
        return f"{b.const(ty.zero_factory(t))}()"
    zero = b.literal_src(ty.zero(t))
    found = _START_INFO.fullmatch(name)
    if b.kind != "OB" or found is None:
        return zero
    key = found[1].upper()
    if key == "OB_NUMBR":
        return str(b.info.number) if t.kind in ("BYTE", "INT", "DINT", "WORD") else zero
    return f"_start_info(ctx, {key!r}, {zero}, {ty.engine_type(t)!r})"


def _finish(b: Block, stmts: Stmts, labels: dict[str, SourceLocation]) -> None:
    info, unit = b.info, b.info.unit
    assert unit is not None
    if info.kind == "FC" and info.ret is not None and not b.ret_set:
        b.diags.append(
            error("E243", f"the value of {unit.name} is never assigned", unit.loc, info.label)
        )
    for key, loc in labels.items():
        if key not in stmts.placed:
            b.diags.append(
                warning("W301", f"label {key} is declared but never placed", loc, b.label)
            )
        elif key not in stmts.jumped:
            b.diags.append(warning("W301", f"label {key} is never jumped to", loc, b.label))


# ---------------------------------------------------------------- instance DBs the source names


def _instances(source: m.Source, prog: Program) -> None:
    """``FBn.DBm(…)`` anywhere in the source makes DBm an instance of FBn (for reads of
    ``DBm.x`` in blocks that come before the call)."""
    for s in m.every_stmt(s for unit in source.units for s in unit.body):
        if isinstance(s, m.CallStmt):
            _instance_of(s.call, prog)


def _instance_of(path: m.Path, prog: Program) -> None:
    fb: BlockInfo | None = prog.block(path.base.text)
    if fb is None or fb.kind not in ("FB", "SFB") or not path.selectors:
        return
    first = path.selectors[0]
    if not isinstance(first, m.Member):
        return
    number = prog.db_number(first.name)
    if prog.global_db(first.name) is not None:
        return  # the call is E233 (``places``)
    if number is not None:
        prog.instances.setdefault(number, fb.label)
