"""What a source declares before any statement is compiled: its blocks and their numbers,
interfaces, UDTs and DB structures, and the blocks it may call outside it (docs/scl.md,
"Blocks and declarations").

A block is named by number (``FB17``), or by a name mapped to one in ``names``
(``{"ACQUIRE": "FB10"}``) — a block symbol, as the STEP 7 symbol table gives S7-SCL V5
(the symbol table's block rows, ``"Data" ; DB 20``, are such names too); a name without a
number is E214. Blocks known outside the source (system blocks, blocks already loaded) are
given as engine blocks and found by label or name.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field

from s7graph.engine.blocks import FB, FC, Decl
from s7graph.engine.errors import SourceLocation
from s7graph.engine.symbols import SymbolTable
from s7graph.steps.scl import model as m
from s7graph.steps.scl import types as ty
from s7graph.steps.scl.consts import Consts, initial
from s7graph.steps.scl.diagnostics import Diagnostic, Problem, error
from s7graph.steps.scl.tia import type_hint

SECTION_DECL = {
    "VAR_INPUT": Decl.IN,
    "VAR_OUTPUT": Decl.OUT,
    "VAR_IN_OUT": Decl.IN_OUT,
    "VAR": Decl.STAT,
    "VAR_TEMP": Decl.TEMP,
}
ALLOWED = {
    "FUNCTION_BLOCK": {"VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT", "VAR", "VAR_TEMP"},
    "FUNCTION": {"VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT", "VAR_TEMP"},
    "ORGANIZATION_BLOCK": {"VAR_TEMP"},
}
"""Declaration sections per block (the guide ch. 13, the table of sections; an FC has
no static data, an OB only temporary data)."""
KIND_OF_UNIT = {"FUNCTION_BLOCK": "FB", "FUNCTION": "FC", "ORGANIZATION_BLOCK": "OB"}
KIND_OF_UNIT |= {"DATA_BLOCK": "DB", "TYPE": "UDT"}
_LABEL = re.compile(r"(SFB|SFC|FB|FC|OB|DB|UDT)(\d+)", re.IGNORECASE)
# Names S7-SCL reads as something else (an absolute address, a timer or counter, a block;
# in a DB, a data word: ``DB20.DW1``), what each is.
_NOT_NAMES: tuple[tuple[re.Pattern[str], str, bool], ...] = (
    (re.compile(r"(?:PI|PQ|I|Q|M)[BWD]\d+", re.I), "the absolute address {}", False),
    (re.compile(r"[TC]\d+", re.I), "the timer or counter {}", False),
    (re.compile(r"(?:SFB|SFC|FB|FC|OB|DB|UDT)\d+", re.I), "the block {}", False),
    (re.compile(r"(?:DB[XBWD]|D[XBWD])\d+", re.I), "a DB's absolute address (DB20.{})", True),
)
NUMBERS = {"FB": (0, 65535), "FC": (0, 65535), "DB": (1, 65535), "UDT": (0, 65535)}
NUMBERS |= {"OB": (1, 32767)}
"""The numbers a block of each kind may have (an S7-400's; OBs up to S7-1500's 32767)."""
MAX_DIMENSIONS = 6
MAX_BYTES = 65536
"""The largest DB of an S7-400 CPU, in bytes: no variable, structure or array is larger."""


@dataclass(frozen=True, slots=True)
class Param:
    """One declared variable of a block: its spelling, section, type and initial value."""

    name: str
    decl: Decl
    type: ty.SclType
    init: object = None
    loc: SourceLocation = m.NOWHERE


@dataclass(slots=True)
class BlockInfo:
    """A block the source declares or may call. ``params`` by upper-case name: an FB's IN,
    OUT, IN_OUT and STAT, an FC's IN, OUT and IN_OUT (TEMP are in ``temps``)."""

    kind: str
    number: int
    name: str
    unit: m.Unit | None = None
    params: dict[str, Param] = field(default_factory=dict)
    temps: dict[str, Param] = field(default_factory=dict)
    ret: ty.SclType | None = None
    db_type: ty.SclType | None = None
    instance_of: str = ""
    engine: FB | FC | None = None
    consts: dict[str, tuple[ty.SclType, object]] = field(default_factory=dict)
    untyped: set[str] = field(default_factory=set)
    """The constants written as untyped numbers (``LIMIT := 7``)."""

    @property
    def label(self) -> str:
        return f"{self.kind}{self.number}"

    def ordered(self) -> list[Param]:
        return list(self.params.values())


@dataclass(slots=True)
class Program:
    """The declarations of one source: blocks by label and by name (upper case), UDTs."""

    file: str
    blocks: dict[str, BlockInfo] = field(default_factory=dict)
    udts: dict[str, ty.SclType] = field(default_factory=dict)
    udt_specs: dict[str, m.TypeSpec] = field(default_factory=dict)
    symbols: SymbolTable | None = None
    names: dict[str, str] = field(default_factory=dict)
    diags: list[Diagnostic] = field(default_factory=list)
    instances: dict[int, str] = field(default_factory=dict)
    """Instance DBs the source names (``FB17.DB10`` or ``DATA_BLOCK DB10 FB17``): number →
    FB label."""

    def block(self, name: str) -> BlockInfo | None:
        key = "".join(name.split()).upper()
        found = self.blocks.get(key)
        if found is None and key in self.names:
            found = self.blocks.get(self.names[key])
        return found

    def global_db(self, name: str) -> BlockInfo | None:
        """The DB ``name`` if this source declares it as a global DB (its own
        ``DATA_BLOCK``, not an FB's instance): no FB call may use it as an instance."""
        found = self.block(name)
        if found is None or found.kind != "DB" or found.unit is None or found.instance_of:
            return None
        return found

    def db_number(self, name: str) -> int | None:
        """The number of a DB named by label (``DB10``), by a block symbol or declared."""
        found = self.block(name)
        if found is not None:
            return found.number if found.kind == "DB" else None
        label = split_label(name) or split_label(self.names.get(name.upper(), ""))
        return label[1] if label is not None and label[0] == "DB" else None

    def problem(self, p: Problem, block: str = "") -> None:
        self.diags.append(error(p.code, p.message, p.loc, block))


def split_label(text: str) -> tuple[str, int] | None:
    """``FB17`` → ``("FB", 17)``; None if ``text`` is not a block label."""
    found = _LABEL.fullmatch("".join(text.split()))
    if found is None:
        return None
    return found[1].upper(), int(found[2])


# ---------------------------------------------------------------- engine blocks outside


def engine_type(name: str) -> ty.SclType:
    """An engine interface's type name as an SCL type (``ANY`` for what SCL cannot type)."""
    upper = "".join(name.split()).upper()
    if found := re.fullmatch(r"STRING\[(\d+)\]", upper):
        return ty.string(int(found[1]))
    return ty.by_name(upper) or ty.ANY


def _external_type(type_name: str, comment: str) -> ty.SclType:
    if ty.is_block_db_var(type_name, comment):
        return ty.BLOCK_DB
    return engine_type(type_name)


def _is_any(type_name: str) -> bool:
    """A system block's ANY pin: declared to the engine as the pointer text it takes
    (``P#DB5.DBX4.0 BYTE 20``), a ``STRING[254]`` (``sfb.catalogue``, ``ANY_AS``)."""
    return "".join(type_name.split()).upper() == "STRING[254]"


def external(blocks: Iterable[FB | FC]) -> list[BlockInfo]:
    """``BlockInfo`` of engine blocks (system blocks, blocks loaded before). A BLOCK_DB
    parameter of an S7-SCL block is a WORD of the engine, its comment saying BLOCK_DB."""
    out = []
    for blk in blocks:
        kind = str(blk.kind)
        system = kind in ("SFB", "SFC")
        params = {
            v.name.upper(): Param(
                v.name,
                v.decl,
                ty.ANY if system and _is_any(v.type) else _external_type(v.type, v.comment),
            )
            for v in blk.interface
            if v.decl is not Decl.TEMP
        }
        ret = None
        if isinstance(blk, FC) and blk.ret_type is not None:
            ret = engine_type(blk.ret_type)
        out.append(BlockInfo(kind, blk.number, blk.name, params=params, ret=ret, engine=blk))
    return out


# ---------------------------------------------------------------- the pass


def declare(
    source: m.Source,
    *,
    blocks: Iterable[FB | FC] = (),
    names: Mapping[str, str] | None = None,
    symbols: SymbolTable | None = None,
) -> Program:
    """Number every block, resolve UDTs and interfaces; problems go to ``diags``."""
    prog = Program(source.file, symbols=symbols)
    table = symbols.block_names() if symbols is not None else {}  # "Data" ; DB 20
    given = {**table, **(names or {})}
    prog.names = {k.upper(): "".join(v.split()).upper() for k, v in given.items()}
    for info in external(blocks):
        prog.blocks.setdefault(info.label, info)
        prog.blocks.setdefault(info.name.upper(), info)
    infos = [_number(prog, unit) for unit in source.units]
    for unit, numbered in zip(source.units, infos, strict=True):
        if numbered is None:
            continue
        info = numbered
        consts = Consts()
        try:
            if unit.kind == "TYPE":
                prog.udts[info.name.upper()] = _udt(prog, unit, consts)
                assert unit.of is not None
                prog.udt_specs[info.name.upper()] = unit.of
                if info.number:
                    prog.udts[info.label] = prog.udts[info.name.upper()]
                    prog.udt_specs[info.label] = unit.of
            elif unit.kind == "DATA_BLOCK":
                _data_block(prog, info, unit, consts)
            else:
                _interface(prog, info, unit, consts)
        except Problem as p:
            prog.problem(p, info.label)
    return prog


def _number(prog: Program, unit: m.Unit) -> BlockInfo | None:
    kind = KIND_OF_UNIT[unit.kind]
    label = split_label(unit.name) or split_label(prog.names.get(unit.name.upper(), ""))
    loc = unit.loc
    if label is None:
        if kind == "UDT":
            info = BlockInfo("UDT", 0, unit.name, unit)
            return info
        prog.diags.append(
            error(
                "E214",
                f"{unit.kind} {unit.name}: no number; write {kind}n or map the name to one",
                loc,
            )
        )
        return None
    if label[0] != kind:
        prog.diags.append(error("E213", f"{unit.kind} {unit.name} is not a {kind}", loc))
        return None
    low, high = NUMBERS[kind]
    if not low <= label[1] <= high:
        shown = f"{label[1]}" if len(str(label[1])) < 12 else f"{str(label[1])[:8]}…"
        prog.diags.append(error("E214", f"{kind} number {shown} is outside {low}..{high}", loc))
        return None
    info = BlockInfo(kind, label[1], unit.name, unit)
    if info.label in prog.blocks and prog.blocks[info.label].unit is not None:
        prog.diags.append(error("E210", f"{info.label} is declared twice", loc))
        return None
    prog.blocks[info.label] = info
    prog.blocks[unit.name.upper()] = info
    return info


def _udt(prog: Program, unit: m.Unit, consts: Consts) -> ty.SclType:
    assert unit.of is not None
    t = resolve_type(prog, unit.of, consts)
    if t.kind != "STRUCT":
        raise Problem("E212", f"TYPE {unit.name} must be a STRUCT", unit.loc)
    return ty.SclType("STRUCT", fields=t.fields, name=unit.name)


def _data_block(prog: Program, info: BlockInfo, unit: m.Unit, consts: Consts) -> None:
    assert unit.of is not None
    spec = unit.of
    if isinstance(spec, m.NamedType):
        owner = prog.block(spec.name)
        if owner is not None and owner.kind in ("FB", "SFB"):
            info.instance_of = owner.label
            prog.instances[info.number] = owner.label
            return
    t = resolve_type(prog, spec, consts)
    if t.kind != "STRUCT":
        raise Problem("E212", f"DATA_BLOCK {unit.name} needs a STRUCT, a UDT or an FB", spec.loc)
    info.db_type = t
    if isinstance(spec, m.StructType):  # read as DB20.name: only DB20.DW1 is an address
        for member in spec.members:
            for name, loc in member.names:
                try:
                    _a_name(name, loc, in_db=True, plain=False)
                except Problem as p:
                    prog.problem(p, info.label)


def _interface(prog: Program, info: BlockInfo, unit: m.Unit, consts: Consts) -> None:
    """The block's constants and variables by section (E210 twice, E215 wrong section)."""
    seen: set[str] = set()
    for section in unit.decls:
        if isinstance(section, m.ConstSection):
            for name, expr, loc in section.items:
                _fresh(seen, name, loc)
                _a_name(name, loc, in_db=False, plain=True)
                try:
                    consts.define(name, expr, loc)
                except Problem as p:
                    prog.problem(p, info.label)
            continue
        if not isinstance(section, m.VarSection):
            continue
        if section.kind not in ALLOWED[unit.kind]:
            what = {"FB": "an FB", "FC": "an FC", "OB": "an OB"}[info.kind]
            prog.diags.append(
                error("E215", f"{section.kind} is not allowed in {what}", section.loc, info.label)
            )
            continue
        decl = SECTION_DECL[section.kind]
        for var in section.decls:
            try:
                _variables(prog, info, var, decl, consts, seen)
            except Problem as p:
                prog.problem(p, info.label)
    info.consts = dict(consts.values)
    info.untyped = set(consts.untyped)
    if unit.kind == "FUNCTION" and unit.ret is not None:
        try:
            info.ret = resolve_type(prog, unit.ret, consts)
        except Problem as p:
            prog.problem(p, info.label)


def _a_name(name: str, loc: SourceLocation, *, in_db: bool, plain: bool) -> None:
    """``name`` reads as a name where it is used, not as an address, a timer or counter or
    a block: written alone (``plain``) not ``MW2``, ``T1``, ``FB3``; at the top of a DB
    (``in_db``: read as ``DB20.name``) not ``DW1``. E201, as S7-SCL's own lexer takes
    those for what they are."""
    for pattern, what, db_only in _NOT_NAMES:
        if (in_db if db_only else plain) and pattern.fullmatch(name):
            raise Problem(
                "E201",
                f"{name} is {what.format(name.upper())} in S7-SCL, not a name: "
                "give the variable another name",
                loc,
            )


def _fresh(seen: set[str], name: str, loc: SourceLocation) -> None:
    key = name.upper()
    if key in seen:
        raise Problem("E210", f"{name!r} is declared twice", loc)
    seen.add(key)


def _variables(
    prog: Program,
    info: BlockInfo,
    var: m.VarDecl,
    decl: Decl,
    consts: Consts,
    seen: set[str],
) -> None:
    t = resolve_type(prog, var.type, consts)
    if t.kind == "FB" and decl is not Decl.STAT:
        raise Problem("E212", f"an FB instance ({t}) is declared in VAR only", var.loc)
    if t.kind == "BLOCK_DB" and decl is not Decl.IN:
        raise Problem("E212", "a BLOCK_DB is an input: declare it in VAR_INPUT", var.loc)
    init: object = None
    if var.init is not None:
        if (
            decl is Decl.TEMP
            or info.kind == "FC"
            or t.kind in ("FB", "TIMER", "COUNTER", "BLOCK_DB")
        ):
            raise Problem("E216", "no initial value is allowed here", var.loc)
        init = initial(consts, t, var.init, var.loc)
    elif t.kind in ("STRUCT", "ARRAY") and decl is not Decl.TEMP and info.kind == "FB":
        init = aggregate_initial(prog, var.type, consts)
    for name, loc in var.names:
        _fresh(seen, name, loc)
        _a_name(name, loc, in_db=info.kind == "FB" and decl is not Decl.TEMP, plain=True)
        param = Param(name, decl, t, init, loc)
        (info.temps if decl is Decl.TEMP else info.params)[name.upper()] = param


def aggregate_initial(prog: Program, spec: m.TypeSpec, consts: Consts) -> object | None:
    """The initial value of a STRUCT, or of an ARRAY of STRUCTs (each element the STRUCT's),
    from the members' ``:= …`` (a UDT's included); None when no member has one."""
    if isinstance(spec, m.ArrayType):
        inner = aggregate_initial(prog, spec.element, consts)
        if inner is None:
            return None
        count = resolve_type(prog, spec, consts).count
        return [ty.clone(inner) for _ in range(count)]
    return struct_initial(prog, spec, consts)


def struct_initial(prog: Program, spec: m.TypeSpec, consts: Consts) -> dict[str, object] | None:
    """The initial value of a STRUCT from its members' ``:= …`` (a UDT's included);
    None when no member has one."""
    if isinstance(spec, m.NamedType):
        inner = prog.udt_specs.get("".join(spec.name.split()).upper())
        return struct_initial(prog, inner, Consts()) if inner is not None else None
    if not isinstance(spec, m.StructType):
        return None
    value: dict[str, object] = {}
    given = False
    for decl in spec.members:
        t = resolve_type(prog, decl.type, consts)
        v: object
        if decl.init is not None:
            v, given = initial(consts, t, decl.init, decl.loc), True
        elif t.aggregate and (sub := aggregate_initial(prog, decl.type, consts)) is not None:
            v, given = sub, True
        else:
            v = ty.zero(t)
        for name, _ in decl.names:
            value[name] = ty.clone(v)
    return value if given else None


# ---------------------------------------------------------------- types


def resolve_type(prog: Program, spec: m.TypeSpec, consts: Consts) -> ty.SclType:
    """The ``SclType`` of a written type (E212 unknown, E217 bad bounds or length)."""
    if isinstance(spec, m.NamedType):
        return _named_type(prog, spec)
    if isinstance(spec, m.StringType):
        if spec.length is None:
            return ty.STRING
        n = consts.integer(spec.length)
        if not 0 <= n <= ty.MAX_STRING:
            raise Problem("E217", f"STRING[{n}]: the length is 0..254", spec.loc)
        return ty.string(n)
    if isinstance(spec, m.ArrayType):
        if len(spec.ranges) > MAX_DIMENSIONS:
            raise Problem("E217", f"an ARRAY has at most {MAX_DIMENSIONS} dimensions", spec.loc)
        dims = []
        for lo_e, hi_e in spec.ranges:
            lo, hi = consts.integer(lo_e), consts.integer(hi_e)
            if not -32768 <= lo <= hi <= 32767:
                raise Problem("E217", f"array bounds {lo}..{hi}: need lo <= hi in INT", lo_e.loc)
            dims.append((lo, hi))
        element = resolve_type(prog, spec.element, consts)
        if element.kind in ("FB", "ARRAY", "TIMER", "COUNTER", "BLOCK_DB"):
            raise Problem("E212", f"an ARRAY of {element.kind} is not allowed", spec.loc)
        t = ty.SclType("ARRAY", dims=tuple(dims), element=element)
        if t.count > MAX_BYTES or ty.size_of(t) > MAX_BYTES:
            raise Problem("E217", f"{t} is larger than a DB can be (64 KB)", spec.loc)
        return t
    fields: list[tuple[str, ty.SclType]] = []
    seen: set[str] = set()
    for decl in spec.members:
        ft = resolve_type(prog, decl.type, consts)
        if ft.kind in ("FB", "BLOCK_DB"):
            what = "an FB instance" if ft.kind == "FB" else "a BLOCK_DB (an input only)"
            raise Problem("E212", f"a STRUCT cannot hold {what}", decl.loc)
        for name, loc in decl.names:
            _fresh(seen, name, loc)
            fields.append((name, ft))
    t = ty.SclType("STRUCT", fields=tuple(fields))
    if ty.size_of(t) > MAX_BYTES:
        raise Problem("E217", "a STRUCT larger than a DB can be (64 KB)", spec.loc)
    return t


def _named_type(prog: Program, spec: m.NamedType) -> ty.SclType:
    t = ty.by_name(spec.name)
    if t is not None:
        return t
    key = "".join(spec.name.split()).upper()
    if key in prog.udts:
        return prog.udts[key]
    blk = prog.block(spec.name)
    if blk is not None and blk.kind in ("FB", "SFB"):
        return ty.SclType("FB", name=blk.label)
    if key in _PARAMETER_TYPES:
        why = _PARAMETER_TYPES[key]
        raise Problem("E212", f"the parameter type {key} is not supported here: {why}", spec.loc)
    raise Problem("E212", type_hint(spec.name) or f"unknown data type {spec.name!r}", spec.loc)


_PARAMETER_TYPES = {
    "BLOCK_FB": "call the FB by name",
    "BLOCK_FC": "call the FC by name",
    "BLOCK_SDB": "no SDB is loaded",
    "ANY": "pass the data itself (a STRUCT, an ARRAY) or a DB as a BLOCK_DB",
    "POINTER": "pass the data itself (a STRUCT, an ARRAY) or a DB as a BLOCK_DB",
}
"""S7-SCL's parameter types that s7graph does not take, and what to write instead."""
