"""The state shared by the parts of the code generator while one block is compiled: the
lines written so far with the place of each, the constants the module binds, the block's
variables and where each lives (docs/scl.md, "How a block runs").

Where a variable lives decides its Python spelling: a VAR_TEMP is a local of the block's
function (``t_NAME``), an FB's IN, OUT, IN_OUT and VAR are items of its instance DB
(``V['Name']``), an FC's parameters items of its parameter dict (``P['Name']``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Protocol

from s7graph.engine.blocks import Decl
from s7graph.engine.errors import SourceLocation
from s7graph.steps.scl import model as m
from s7graph.steps.scl import types as ty
from s7graph.steps.scl.consts import Constant
from s7graph.steps.scl.declare import BlockInfo, Param, Program
from s7graph.steps.scl.diagnostics import Diagnostic, Problem, error

HOLE = "\x00"
"""Where a value goes in a ``Place.put`` template."""


@dataclass(frozen=True, slots=True)
class X:
    """A compiled expression: its type, the Python source computing it, and its value when
    the compiler knows it (a literal or a constant)."""

    type: ty.SclType
    src: str
    const: Constant | None = None


@dataclass(frozen=True, slots=True)
class Place:
    """Something that holds a value: ``get`` reads it, ``put`` (a statement with ``HOLE``
    for the value, None if read-only) writes it; ``what`` names it in messages; ``pointer``
    points a system block's ANY parameter at it."""

    type: ty.SclType
    get: str
    put: str | None
    what: str
    pointer: str = ""
    """Python source of the ANY pointer text to it (``P#DB5.DBX4.0 BYTE 20``) when it lies
    in an operand area or a global DB's bytes; empty for a value held by the block."""
    address: str = ""
    """Python source of its ``Address`` when it is one value in an operand area's or a
    global DB's bytes, read and written there (``_mem.read_as(address, …)``); else empty."""

    def store(self, value: str) -> str:
        assert self.put is not None
        return self.put.replace(HOLE, value)


def in_memory(t: ty.SclType, address: str, what: str, pointer: str = "") -> Place:
    """The place of a value of ``t`` at ``address`` (Python source of an ``Address``),
    read and written in memory as its engine type (``types.engine_type``)."""
    name = ty.engine_type(t)
    get, put = f"_mem.read_as({address}, {name!r})", f"_mem.write_as({address}, {name!r}, {HOLE})"
    return Place(t, get, put, what, pointer, address)


@dataclass(frozen=True, slots=True)
class Target:
    """Something to call: a built-in function, an FC or SFC, an FB or SFB with its instance
    (``instance``: Python source of its ``InstanceDB``), a multi-instance."""

    kind: str
    name: str
    args: m.Args
    loc: SourceLocation
    info: BlockInfo | None = None
    instance: str = ""


Resolved = Place | X | Target


class Exprs(Protocol):
    """The expression translator (``exprs.Exprs``)."""

    def expr(self, e: m.Expr) -> X: ...

    def cond(self, e: m.Expr) -> str: ...

    def convert(self, x: X, t: ty.SclType, loc: SourceLocation, what: str) -> str: ...


class Places(Protocol):
    """The path resolver (``places.Places``)."""

    def resolve(self, path: m.Path) -> Resolved: ...

    def place(self, path: m.Path, writing: bool = False) -> Place: ...

    def block_db_number(self, call: m.Args, loc: SourceLocation) -> str: ...


class Calls(Protocol):
    """The call translator (``calls.Calls``)."""

    def value(self, target: Target) -> X: ...

    def statement(self, target: Target, result: Place | None = None) -> None: ...


@dataclass(frozen=True, slots=True)
class Local:
    """A variable of the block being compiled."""

    param: Param
    place: Place


class Module:
    """The generated module of one source: the constants it binds by name."""

    def __init__(self) -> None:
        self.consts: dict[str, Any] = {}
        self._seen: dict[tuple[type, Any], str] = {}

    def const(self, value: Any) -> str:
        """A module-level name bound to ``value`` (shared when equal and hashable)."""
        try:
            key: tuple[type, Any] | None = (type(value), value)
            hash(key)
        except TypeError:
            key = None
        if key is not None and key in self._seen:
            return self._seen[key]
        name = f"_k{len(self.consts)}"
        self.consts[name] = value
        if key is not None:
            self._seen[key] = name
        return name


@dataclass
class Block:
    """One block being compiled: its declarations, its variables and its lines."""

    prog: Program
    info: BlockInfo
    module: Module
    lines: list[str] = field(default_factory=list)
    locs: list[SourceLocation] = field(default_factory=list)
    locals: dict[str, Local] = field(default_factory=dict)
    diags: list[Diagnostic] = field(default_factory=list)
    loc: SourceLocation = m.NOWHERE
    indent: int = 1
    temps: int = 0
    ret_set: bool = False
    """A FUNCTION's value has been assigned somewhere (E243 if never)."""
    exprs: Exprs = field(init=False)
    places: Places = field(init=False)
    calls: Calls = field(init=False)

    @property
    def label(self) -> str:
        return self.info.label

    @property
    def kind(self) -> str:
        return self.info.kind

    def emit(self, line: str) -> None:
        self.lines.append("    " * self.indent + line)
        self.locs.append(self.loc)

    def temp(self, hint: str = "t") -> str:
        self.temps += 1
        return f"_{hint}{self.temps}"

    def const(self, value: Any) -> str:
        return self.module.const(value)

    def report(self, p: Problem) -> None:
        self.diags.append(error(p.code, p.message, p.loc, self.label))

    def where(self, loc: SourceLocation) -> str:
        """``file:line:col`` of ``loc`` as a Python string literal (runtime messages)."""
        return repr(f"{loc.file}:{loc.line}:{loc.col}")

    # ---- variables

    def declare_locals(self) -> None:
        """Give every variable of the block its Python spelling."""
        info = self.info
        for key, p in info.temps.items():
            name = f"t_{key}"
            self.locals[key] = Local(p, Place(p.type, name, f"{name} = {HOLE}", p.name))
        for key, p in info.params.items():
            self.locals[key] = Local(p, self._param_place(p))

    def _param_place(self, p: Param) -> Place:
        item = f"[{p.name!r}]"
        if self.kind == "FB":
            return Place(p.type, f"V{item}", f"V{item} = {HOLE}", p.name)
        if p.decl is Decl.OUT and not p.type.aggregate:
            zero = self.literal_src(ty.zero(p.type))
            return Place(p.type, f"P.get({p.name!r}, {zero})", f"P{item} = {HOLE}", p.name)
        return Place(p.type, f"P{item}", f"P{item} = {HOLE}", p.name)

    def literal_src(self, value: Any) -> str:
        """Python source of a constant value (inline for numbers, bools and text)."""
        if isinstance(value, bool | int | str) or value is None:
            return repr(value)
        if isinstance(value, float):
            return (
                repr(value) if value == value and abs(value) != float("inf") else self.const(value)
            )
        return self.const(value)
