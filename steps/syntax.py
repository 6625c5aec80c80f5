"""The language inside a step: expressions, action rows and permanent instructions as
written, with the place of every element (docs/semantics.md, "Actions" and "Conditions").

The parser builds these nodes; ``steps`` compiles them to Python and the chart model
(``sequencer.text.model``) holds them in its steps, transitions and permanent instructions.
Nothing here evaluates anything.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

from s7graph.engine.errors import SourceLocation

__all__ = [
    "CHAIN_OPS",
    "NOWHERE",
    "ActionOperand",
    "ActionRow",
    "Assignment",
    "Binary",
    "BlockCall",
    "Coil",
    "Const",
    "Expr",
    "FuncCall",
    "Operand",
    "PermanentInstruction",
    "StepAttr",
    "StepTarget",
    "TransAttr",
    "Unary",
    "chain",
    "chain_parts",
]

NOWHERE = SourceLocation()

# ------------------------------------- expressions (docs/semantics.md, "Conditions" and "Actions")


@dataclass(frozen=True, slots=True)
class Const:
    """A literal. ``type`` is the S7 type name (BOOL INT DINT REAL TIME S5TIME WORD ...);
    ``value`` is the Python value (bool, int, float; TIME and S5TIME in milliseconds);
    ``text`` is the literal as written."""

    value: object
    type: str
    text: str
    loc: SourceLocation = NOWHERE


@dataclass(frozen=True, slots=True)
class Operand:
    """A named or addressed operand as written: an absolute address (``I0.7``, ``MW10``,
    ``DB1.DBX0.0``), a quoted symbol (``"Start_button"``, quotes removed, ``quoted`` set),
    an FB variable or FB pin (``count``, ``ERR_FLT``). Resolution happens in the validator
    and compiler. ``member`` names a variable of an instance DB read by name (S7-SCL's
    structured access: ``DB10.Q`` is name ``DB10``, ``"T_S2".Q`` the quoted name ``T_S2``,
    each with member ``Q``); "" for any other operand."""

    name: str
    quoted: bool = False
    loc: SourceLocation = NOWHERE
    member: str = ""


@dataclass(frozen=True, slots=True)
class StepAttr:
    """``S3.X`` (active), ``S3.T`` (activation time), ``S3.U`` (time without disturbance)."""

    step: int
    attr: Literal["X", "T", "U"]
    loc: SourceLocation = NOWHERE


@dataclass(frozen=True, slots=True)
class TransAttr:
    """``T2.TT``: the transition's condition holds."""

    transition: int
    attr: Literal["TT"]
    loc: SourceLocation = NOWHERE


@dataclass(frozen=True, slots=True)
class Unary:
    """``NOT x`` or arithmetic negation ``-x``."""

    op: Literal["NOT", "-"]
    operand: Expr
    loc: SourceLocation = NOWHERE


@dataclass(frozen=True, slots=True)
class Binary:
    """Boolean (AND OR XOR), comparison (= <> < > <= >=) or arithmetic / word
    (+ - * / MOD AND OR XOR SHL SHR SSR ROL ROR) operation. ``AND``/``OR``/``XOR`` are
    boolean on BOOL operands and bitwise on WORD/DWORD operands."""

    op: str
    left: Expr
    right: Expr
    loc: SourceLocation = NOWHERE


@dataclass(frozen=True, slots=True)
class FuncCall:
    """A function of STEP7 comprehensive guide vol. 2, ch. 14: ``ABS(x)``, ``INT_TO_DINT(x)``,
    ``SQRT(x)`` ..."""

    name: str
    args: tuple[Expr, ...]
    loc: SourceLocation = NOWHERE


Expr = Const | Operand | StepAttr | TransAttr | Unary | Binary | FuncCall

# ------------------------------------------------------ action rows (docs/semantics.md, "Actions")


@dataclass(frozen=True, slots=True)
class Assignment:
    """``target := expr`` (an action row with qualifier N, or a permanent instruction)."""

    target: Operand
    expr: Expr
    loc: SourceLocation = NOWHERE


@dataclass(frozen=True, slots=True)
class BlockCall:
    """``CALL FB 5, DB 5 (IN1 := I0.0, OUT1 => Q0.1)`` / ``CALL FC 1`` / ``CALL "Name"``
    / ``CALL SFB 4, DB 10 (...)``. ``kind`` is FB FC SFB SFC or "" for a symbolic name.
    ``inputs`` are ``:=`` parameters, ``outputs`` are ``=>`` parameters."""

    kind: str
    block: int | str
    instance: int | str | None = None
    inputs: tuple[tuple[str, Expr], ...] = ()
    outputs: tuple[tuple[str, Operand], ...] = ()
    loc: SourceLocation = NOWHERE


@dataclass(frozen=True, slots=True)
class StepTarget:
    """The operand of ``ON S4`` / ``OFF S4``; ``step`` is None for ``S_ALL``."""

    step: int | None
    loc: SourceLocation = NOWHERE


ActionOperand = Operand | Assignment | BlockCall | StepTarget


@dataclass(frozen=True, slots=True)
class ActionRow:
    """One row ``[event] qualifier[C] operand [, value]`` of a step's action table.

    ``qualifier``: N S R D L CALL ON OFF CS CU CD CR TL TD TF TR.
    ``event``: None or S1 S0 V1 V0 L1 L0 A1 R1.
    ``value``: the time of D/L (a TIME Expr), the counter preset of CS (``C#5``), the S5TIME
    of TL/TD/TF; None otherwise.
    ``operand``: Operand for bit / timer / counter rows, Assignment for ``N x := expr``,
    BlockCall for CALL, StepTarget for ON/OFF."""

    qualifier: str
    operand: ActionOperand
    event: str | None = None
    interlocked: bool = False
    value: Expr | None = None
    loc: SourceLocation = NOWHERE
    comment: str = ""  # the comments written above the row, verbatim
    trailing: str = ""  # the comments at the end of its line, verbatim


# ---------------------------------------- permanent instructions (docs/semantics.md, "Conditions")


@dataclass(frozen=True, slots=True)
class Coil:
    """A permanent instruction writing a bit: ``M0.1 := cond;`` (``kind`` "="), ``S M0.1 := cond;``
    (set when cond), ``R M0.1 := cond;`` (reset when cond)."""

    kind: Literal["=", "S", "R"]
    target: Operand
    condition: Expr
    loc: SourceLocation = NOWHERE


PermanentInstruction = Coil | Assignment | BlockCall


# ---------------------------------------------------------------- chains of AND, OR, XOR

CHAIN_OPS = frozenset({"AND", "OR", "XOR"})
"""The associative operators: ``a AND b AND c`` is one chain of three parts."""


def chain(op: str, parts: Sequence[Expr]) -> Expr:
    """``parts[0] op parts[1] op …`` in the shape the parser gives a written chain: balanced
    (a binary counter: two neighbours of the same size merge, the rest folds to the right),
    so a chain of n parts is about log2(n) deep; the parts stay in order (the order of the
    criteria bits). Importers build their chains with it, so that an imported chart is the
    model its ``.s7g`` text parses to."""
    stack: list[tuple[int, Expr]] = []
    for part in parts:
        stack.append((1, part))
        while len(stack) > 1 and stack[-1][0] == stack[-2][0]:
            (n, a), (m, b) = stack[-2], stack[-1]
            stack[-2:] = [(n + m, Binary(op, a, b, a.loc))]
    tree = stack[-1][1]
    for _, part in reversed(stack[:-1]):
        tree = Binary(op, part, tree, part.loc)
    return tree


def chain_parts(e: Binary) -> list[Expr]:
    """The parts of the chain ``e`` is the root of: its operands under the same operator,
    however nested, in order (iteratively: a chain may be thousands long)."""
    out: list[Expr] = []
    todo: list[Expr] = [e]
    while todo:
        x = todo.pop()
        if isinstance(x, Binary) and x.op == e.op:
            todo += (x.right, x.left)
        else:
            out.append(x)
    return out
