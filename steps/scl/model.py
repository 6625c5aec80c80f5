"""The syntax tree of an S7-SCL source: block frames, declarations, statements and
expressions as written, each with its place (docs/scl.md, "Blocks and declarations").

The parser (``parse.py``) builds these frozen nodes; nothing here resolves a name or a type.
A name or an operand is a ``Path``: a base (a name, an absolute operand, a block or a
quoted symbol) followed by selectors — ``.member``, ``[index, …]`` and a call's
``(arguments)``.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from typing import Literal

from s7graph.engine.errors import SourceLocation

NOWHERE = SourceLocation()

# ---------------------------------------------------------------- expressions


@dataclass(frozen=True, slots=True)
class Lit:
    """A literal as written (``INT#5``, ``T#1S``, ``16#FF``; a ``-`` written right before a
    number is folded into it); an untyped number's type follows from its context."""

    text: str
    loc: SourceLocation = NOWHERE


BaseKind = Literal["name", "address", "db_address", "block", "symbol", "cell"]


@dataclass(frozen=True, slots=True)
class Base:
    """The start of a path: a name, an absolute operand (``MW10``, ``DB1.DBX0.0``), a block
    (``FB17``, ``DB10``), a quoted symbol or a timer/counter (``T10``, ``C3``)."""

    kind: BaseKind
    text: str
    loc: SourceLocation = NOWHERE


@dataclass(frozen=True, slots=True)
class Member:
    """``.name`` (a structure member, an instance's variable, ``FB17.DB10``)."""

    name: str
    loc: SourceLocation = NOWHERE
    block: bool = False
    """The member is written as a block (``DB10`` in ``FB17.DB10``)."""


@dataclass(frozen=True, slots=True)
class Index:
    """``[i, j, …]``: array indices, or the byte (and bit) of an indexed operand."""

    items: tuple[Expr, ...]
    loc: SourceLocation = NOWHERE


@dataclass(frozen=True, slots=True)
class Arg:
    """One actual parameter: ``name := value`` or a value alone (``name`` empty)."""

    name: str
    value: Expr
    loc: SourceLocation = NOWHERE


@dataclass(frozen=True, slots=True)
class Args:
    """``( … )``: the actual parameters of a call."""

    items: tuple[Arg, ...]
    loc: SourceLocation = NOWHERE


Selector = Member | Index | Args


@dataclass(frozen=True, slots=True)
class Path:
    """An operand, a variable, a call: a base and its selectors."""

    base: Base
    selectors: tuple[Selector, ...] = ()
    loc: SourceLocation = NOWHERE


@dataclass(frozen=True, slots=True)
class Unary:
    """``NOT x``, ``-x``, ``+x``."""

    op: str
    operand: Expr
    loc: SourceLocation = NOWHERE


@dataclass(frozen=True, slots=True)
class Binary:
    """``left op right``; ``op`` upper case: ``** * / MOD DIV + - < > <= >= = <> AND XOR OR``
    (``&`` is written ``AND``)."""

    op: str
    left: Expr
    right: Expr
    loc: SourceLocation = NOWHERE


Expr = Lit | Path | Unary | Binary
CaseValue = Lit | Path
"""A CASE value: an integer literal or a constant's name."""

# ---------------------------------------------------------------- statements


@dataclass(frozen=True, slots=True)
class Assign:
    """``target := value;``"""

    target: Path
    value: Expr
    loc: SourceLocation = NOWHERE


@dataclass(frozen=True, slots=True)
class CallStmt:
    """A block or function called as a statement: ``FB17.DB10(…);``, ``STP();``."""

    call: Path
    loc: SourceLocation = NOWHERE


@dataclass(frozen=True, slots=True)
class If:
    """``IF c THEN … ELSIF c THEN … ELSE … END_IF;``: the branches in order."""

    branches: tuple[tuple[Expr, tuple[Stmt, ...]], ...]
    orelse: tuple[Stmt, ...] | None
    loc: SourceLocation = NOWHERE


@dataclass(frozen=True, slots=True)
class CaseArm:
    """``3, 5..9: …``: values as ``(low, high)`` pairs (a single value twice), each an
    integer literal or the name of a constant (a ``Path`` of one name)."""

    values: tuple[tuple[CaseValue, CaseValue], ...]
    body: tuple[Stmt, ...]
    loc: SourceLocation = NOWHERE


@dataclass(frozen=True, slots=True)
class Case:
    """``CASE selector OF arms ELSE … END_CASE;``"""

    selector: Expr
    arms: tuple[CaseArm, ...]
    orelse: tuple[Stmt, ...] | None
    loc: SourceLocation = NOWHERE


@dataclass(frozen=True, slots=True)
class For:
    """``FOR v := start TO end BY step DO … END_FOR;``"""

    var: Path
    start: Expr
    end: Expr
    step: Expr | None
    body: tuple[Stmt, ...]
    loc: SourceLocation = NOWHERE


@dataclass(frozen=True, slots=True)
class While:
    """``WHILE c DO … END_WHILE;``"""

    cond: Expr
    body: tuple[Stmt, ...]
    loc: SourceLocation = NOWHERE


@dataclass(frozen=True, slots=True)
class Repeat:
    """``REPEAT … UNTIL c END_REPEAT;``"""

    body: tuple[Stmt, ...]
    cond: Expr
    loc: SourceLocation = NOWHERE


@dataclass(frozen=True, slots=True)
class Jump:
    """``EXIT;``, ``CONTINUE;``, ``RETURN;`` or ``GOTO label;`` (``label`` set)."""

    kind: Literal["EXIT", "CONTINUE", "RETURN", "GOTO"]
    label: str = ""
    loc: SourceLocation = NOWHERE


@dataclass(frozen=True, slots=True)
class Empty:
    """``;`` alone."""

    loc: SourceLocation = NOWHERE


@dataclass(frozen=True, slots=True)
class Labeled:
    """``label: statement``."""

    label: str
    stmt: Stmt
    loc: SourceLocation = NOWHERE


@dataclass(frozen=True, slots=True)
class CaseHead:
    """``Fill, 3..Drain: statement`` read inside a statement list: the values that start a
    further arm of the CASE around it (``steps/scl/cases.py`` makes it one)."""

    values: tuple[tuple[CaseValue, CaseValue], ...]
    stmt: Stmt
    loc: SourceLocation = NOWHERE


Stmt = Assign | CallStmt | If | Case | For | While | Repeat | Jump | Empty | Labeled | CaseHead


def every_stmt(stmts: Iterable[Stmt]) -> Iterator[Stmt]:
    """Each statement of ``stmts`` and each one nested in them (a labelled statement, the
    branches of IF and CASE, the bodies of loops), depth first from the last."""
    todo = list(stmts)
    while todo:
        s = todo.pop()
        yield s
        if isinstance(s, Labeled | CaseHead):
            todo.append(s.stmt)
        elif isinstance(s, If):
            todo += [x for _, body in s.branches for x in body] + list(s.orelse or ())
        elif isinstance(s, Case):
            todo += [x for arm in s.arms for x in arm.body] + list(s.orelse or ())
        elif isinstance(s, For | While | Repeat):
            todo += list(s.body)


# ---------------------------------------------------------------- declarations


@dataclass(frozen=True, slots=True)
class NamedType:
    """A type by name: ``INT``, ``TIMER``, a UDT (``MEASVALUES``, ``UDT1``), an FB for a
    multi-instance (``EVALUATE``, ``FB10``)."""

    name: str
    loc: SourceLocation = NOWHERE


@dataclass(frozen=True, slots=True)
class StringType:
    """``STRING`` or ``STRING[n]`` (``n`` a constant expression)."""

    length: Expr | None
    loc: SourceLocation = NOWHERE


@dataclass(frozen=True, slots=True)
class ArrayType:
    """``ARRAY[lo..hi, …] OF element`` (bounds are constant expressions)."""

    ranges: tuple[tuple[Expr, Expr], ...]
    element: TypeSpec
    loc: SourceLocation = NOWHERE


@dataclass(frozen=True, slots=True)
class StructType:
    """``STRUCT members END_STRUCT``."""

    members: tuple[VarDecl, ...]
    loc: SourceLocation = NOWHERE


TypeSpec = NamedType | StringType | ArrayType | StructType


@dataclass(frozen=True, slots=True)
class Repeated:
    """``n(values)`` in an initial value list."""

    count: Lit
    items: tuple[InitItem, ...]
    loc: SourceLocation = NOWHERE


InitItem = Expr | Repeated


@dataclass(frozen=True, slots=True)
class VarDecl:
    """``a, b : type := init;`` in one section."""

    names: tuple[tuple[str, SourceLocation], ...]
    type: TypeSpec
    init: tuple[InitItem, ...] | None
    loc: SourceLocation = NOWHERE


Section = Literal["VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT", "VAR", "VAR_TEMP"]


@dataclass(frozen=True, slots=True)
class VarSection:
    """``VAR_INPUT … END_VAR`` and its kin."""

    kind: Section
    decls: tuple[VarDecl, ...]
    loc: SourceLocation = NOWHERE


@dataclass(frozen=True, slots=True)
class ConstSection:
    """``CONST name := value; … END_CONST``."""

    items: tuple[tuple[str, Expr, SourceLocation], ...]
    loc: SourceLocation = NOWHERE


@dataclass(frozen=True, slots=True)
class LabelSection:
    """``LABEL a, b; END_LABEL``."""

    names: tuple[tuple[str, SourceLocation], ...]
    loc: SourceLocation = NOWHERE


Declaration = VarSection | ConstSection | LabelSection

# ---------------------------------------------------------------- block frames

UnitKind = Literal["FUNCTION_BLOCK", "FUNCTION", "ORGANIZATION_BLOCK", "DATA_BLOCK", "TYPE"]


@dataclass(frozen=True, slots=True)
class Unit:
    """One block of the source. ``name`` as written (``FB17``, ``"Name"`` without quotes, a
    symbol); ``ret`` the type of a FUNCTION (None: VOID); ``of`` the structure, UDT or FB of
    a DATA_BLOCK or TYPE; ``body`` the statements (a DATA_BLOCK: its assignments)."""

    kind: UnitKind
    name: str
    decls: tuple[Declaration, ...] = ()
    body: tuple[Stmt, ...] = ()
    ret: TypeSpec | None = None
    of: TypeSpec | None = None
    attributes: tuple[tuple[str, str], ...] = ()
    loc: SourceLocation = NOWHERE
    end: SourceLocation = NOWHERE


@dataclass(frozen=True, slots=True)
class Source:
    """A whole source file: its blocks in order."""

    units: tuple[Unit, ...]
    file: str = "<input>"
