"""Where an S7-SCL source uses operands from outside its blocks — symbols, absolute
addresses, DB variables, timers and counters, the blocks it calls and their instance DBs —
for the cross-reference list of a chart and the blocks beside it (docs/cli.md, "s7graph
xref"), as TIA Portal's cross-references list a tag's uses in every block.

A block's own variables, constants, labels and the built-in functions are not listed. An
operand is shown as written, with a few spellings made one: an address without its ``%``,
a block as ``FB 17``, a DB variable as ``DB41.LMN`` or ``"Data".temps`` (members up to the
first index). Its access: *write* for an assignment's target and a FOR variable, *call*
for a called block, *instance* for its instance DB, an actual parameter by the called
block's interface (:data:`ARG_ACCESS`; *argument* when the interface is not known), *read*
for everything else. A DB passed as a whole (``FC5(src := DB5)``, or ``"Recipe"`` to a
BLOCK_DB input) is that DB, ``DB 5`` or ``"Recipe"``, its access *argument*, as a chart's
``CALL`` passing it is listed (``sequencer.xref``): one operand for both. Pure: the parsed
source in, data out.
"""

from __future__ import annotations

import re
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from typing import Final

from s7graph.engine.errors import SourceLocation
from s7graph.steps.scl import model as m
from s7graph.steps.scl.builtins import BUILTINS
from s7graph.steps.scl.calls import S5_COUNTERS, S5_TIMERS

__all__ = [
    "ARG_ACCESS",
    "Params",
    "SclUse",
    "block_label",
    "block_name",
    "interfaces",
    "scl_uses",
]

ARG_ACCESS: Final[dict[str, str]] = {
    "VAR_INPUT": "read",
    "VAR_OUTPUT": "write",
    "VAR_IN_OUT": "read/write",
    "BLOCK_DB": "argument",
}
"""How an actual parameter's operand is used, by the section of the called block that
declares the parameter; ``BLOCK_DB`` an input of that type, whose DB the block may read
or write."""

Params = Mapping[str, Mapping[str, str]]
"""Blocks' parameters: block (upper case: ``FC10``, ``SCALE``, ``CONT_C``) → parameter
(upper case) → its section, or ``BLOCK_DB`` (a key of :data:`ARG_ACCESS`)."""

_FUNCTIONS: Final = frozenset(
    {*BUILTINS, *S5_TIMERS, *S5_COUNTERS, "WORD_TO_BLOCK_DB"}  # the last opens a DB (places)
)
_BLOCK = re.compile(r"(OB|FB|FC|SFB|SFC|DB|UDT)\s*(\d+)", re.I)
_CODE_KINDS: Final = {"FUNCTION_BLOCK": "FB", "FUNCTION": "FC", "ORGANIZATION_BLOCK": "OB"}


@dataclass(frozen=True, slots=True)
class SclUse:
    """One use of ``operand`` in the block ``block`` (``OB 35``, ``FC "Scale"``), with
    ``access``, written at ``loc``."""

    operand: str
    block: str
    access: str
    loc: SourceLocation


def block_label(unit: m.Unit) -> str:
    """How a block is named in a use: ``OB 35``, ``FC "Scale"``."""
    numbered = _BLOCK.fullmatch(unit.name)
    if numbered is not None:
        return f"{numbered[1].upper()} {int(numbered[2])}"
    return f'{_CODE_KINDS.get(unit.kind, unit.kind)} "{unit.name}"'


def interfaces(source: m.Source) -> dict[str, dict[str, str]]:
    """The parameters of the source's FBs and FCs (:data:`Params`), by the block's name as
    written, in upper case and without spaces (``FC3``, ``SCALE``)."""
    out: dict[str, dict[str, str]] = {}
    for unit in source.units:
        if unit.kind not in ("FUNCTION_BLOCK", "FUNCTION"):
            continue
        params: dict[str, str] = {
            name.upper(): "BLOCK_DB" if _is_block_db(decl) else section.kind
            for section in unit.decls
            if isinstance(section, m.VarSection) and section.kind in ARG_ACCESS
            for decl in section.decls
            for name, _ in decl.names
        }
        out[unit.name.upper().replace(" ", "")] = params
    return out


def scl_uses(source: m.Source, params: Params | None = None) -> list[SclUse]:
    """Every use of an outside operand in the code blocks of ``source``, in the order
    written; ``params``: the interfaces of the blocks it may call (its own are added)."""
    known = {**(params or {}), **interfaces(source)}
    out: list[SclUse] = []
    for unit in source.units:
        if unit.kind in _CODE_KINDS:
            walk = _Walk(unit, known)
            out += [SclUse(op, walk.label, access, loc) for op, access, loc in walk.uses()]
    return sorted(out, key=lambda u: (u.loc.line, u.loc.col))


_Found = tuple[str, str, SourceLocation]  # operand, access, place


class _Walk:
    """The uses of one code block."""

    def __init__(self, unit: m.Unit, params: Params) -> None:
        self.unit, self.params, self.label = unit, params, block_label(unit)
        self.local: set[str] = set()
        for section in unit.decls:
            if isinstance(section, m.VarSection):
                self.local |= {name.upper() for d in section.decls for name, _ in d.names}
            elif isinstance(section, m.ConstSection):
                self.local |= {name.upper() for name, _, _ in section.items}

    def uses(self) -> Iterator[_Found]:
        for stmt in m.every_stmt(self.unit.body):
            yield from self._stmt(stmt)

    def _stmt(self, s: m.Stmt) -> Iterator[_Found]:
        if isinstance(s, m.Assign):
            yield from self._path(s.target, "write")
            yield from self._expr(s.value)
        elif isinstance(s, m.CallStmt):
            yield from self._path(s.call, "read")
        elif isinstance(s, m.If):
            for cond, _ in s.branches:
                yield from self._expr(cond)
        elif isinstance(s, m.Case):
            yield from self._expr(s.selector)
        elif isinstance(s, m.For):
            yield from self._path(s.var, "write")
            for e in (s.start, s.end, s.step):
                yield from self._expr(e)
        elif isinstance(s, m.While | m.Repeat):
            yield from self._expr(s.cond)

    def _expr(self, e: m.Expr | None) -> Iterator[_Found]:
        todo = [e]
        while todo:
            x = todo.pop()
            if isinstance(x, m.Path):
                yield from self._path(x, "read")
            elif isinstance(x, m.Unary):
                todo.append(x.operand)
            elif isinstance(x, m.Binary):
                todo += [x.right, x.left]

    def _path(self, path: m.Path, access: str) -> Iterator[_Found]:
        args = next((s for s in path.selectors if isinstance(s, m.Args)), None)
        shown = self._operand(path, called=args is not None)
        if args is None:
            if shown is not None:
                yield shown, access, path.base.loc
        else:
            yield from self._call(path, shown, args)
        for sel in path.selectors:
            if isinstance(sel, m.Index):
                for item in sel.items:
                    yield from self._expr(item)

    def _call(self, path: m.Path, shown: str | None, args: m.Args) -> Iterator[_Found]:
        if shown is not None:
            yield shown, "call", path.base.loc
        for sel in path.selectors:
            if isinstance(sel, m.Member) and sel.block:
                yield block_name(sel.name), "instance", sel.loc
        callee = self.params.get(path.base.text.upper().replace(" ", ""), {})
        for arg in args.items:
            section = callee.get(arg.name.upper())
            db = self._passed_db(arg.value, section)
            if db is not None:
                yield db
            elif isinstance(arg.value, m.Path):
                how = ARG_ACCESS.get(section or "", "argument" if shown else "read")
                yield from self._path(arg.value, how)
            else:
                yield from self._expr(arg.value)

    def _passed_db(self, value: m.Expr, section: str | None) -> _Found | None:
        """A DB an actual parameter passes as a whole: ``DB5`` (to any parameter: nothing
        else is a DB by itself), or a symbol given to a BLOCK_DB input (``"Recipe"``) —
        the DB as a chart's call passing it is listed, its access *argument*; None for
        anything else (a BLOCK_DB parameter of the caller passed on is its own)."""
        if not isinstance(value, m.Path) or value.selectors:
            return None
        base = value.base
        if base.kind == "block" and base.text.upper().startswith("DB"):
            return block_name(base.text), "argument", base.loc
        shown = self._operand(value, called=False)  # "Recipe"; None for a local
        if section == "BLOCK_DB" and shown is not None and base.kind in ("symbol", "name"):
            return shown, "argument", base.loc
        return None

    def _operand(self, path: m.Path, *, called: bool) -> str | None:
        """``path`` as an outside operand is shown, None for the block's own names."""
        base = path.base
        if base.kind == "name":
            key = base.text.upper()
            if key in self.local or (called and key in _FUNCTIONS):
                return None
            return f'"{base.text}"' if called else base.text + _members(path)
        if base.kind == "address":
            return base.text.lstrip("%").upper()
        if base.kind == "db_address":
            return base.text.upper()
        if base.kind == "block":
            return block_name(base.text) if called else base.text.upper() + _members(path)
        if base.kind == "symbol":
            return f'"{base.text}"' + ("" if called else _members(path))
        return base.text.upper()  # a timer or counter: T10, C3


def _is_block_db(decl: m.VarDecl) -> bool:
    return isinstance(decl.type, m.NamedType) and decl.type.name.upper() == "BLOCK_DB"


def _members(path: m.Path) -> str:
    """The path's members up to its first index or call: ``.temps``, ``.LMN``."""
    out = ""
    for sel in path.selectors:
        if not isinstance(sel, m.Member):
            break
        out += f".{sel.name}"
    return out


def block_name(text: str) -> str:
    """A block as the cross-reference shows it: ``DB 5`` for ``DB5`` or ``db 5``, else the
    name quoted (``"Recipe"``)."""
    numbered = _BLOCK.fullmatch(text.replace(" ", ""))
    return f"{numbered[1].upper()} {int(numbered[2])}" if numbered else f'"{text}"'
