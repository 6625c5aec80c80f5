"""The source chart: what a `.s7g` file says, with the place of every element (SPEC §3).

The parser builds this model; the validator reads it and reports diagnostics; the compiler
turns it into an immutable, int-indexed ``CompiledChart``. Nothing here evaluates anything.
Step and transition numbers are unique within one FB (a jump may target any sequencer).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

from s7graph.engine.errors import SourceLocation

NOWHERE = SourceLocation()

# ---------------------------------------------------------------- expressions (SPEC §2.9, §2.8)


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
    and compiler."""

    name: str
    quoted: bool = False
    loc: SourceLocation = NOWHERE


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
    """A function of seed 000 lines 5838-5884: ``ABS(x)``, ``INT_TO_DINT(x)``, ``SQRT(x)`` ..."""

    name: str
    args: tuple[Expr, ...]
    loc: SourceLocation = NOWHERE


Expr = Const | Operand | StepAttr | TransAttr | Unary | Binary | FuncCall

# ---------------------------------------------------------------- action rows (SPEC §2.8)


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


# ------------------------------------------------------- permanent instructions (SPEC §2.9)


@dataclass(frozen=True, slots=True)
class Coil:
    """A permanent instruction writing a bit: ``M0.1 := cond;`` (``kind`` "="), ``S M0.1 := cond;``
    (set when cond), ``R M0.1 := cond;`` (reset when cond)."""

    kind: Literal["=", "S", "R"]
    target: Operand
    condition: Expr
    loc: SourceLocation = NOWHERE


PermanentInstruction = Coil | Assignment | BlockCall

# ---------------------------------------------------------------- structure (SPEC §2.1)


@dataclass(frozen=True, slots=True)
class Step:
    number: int
    name: str
    initial: bool = False
    message: str = ""  # second string after the name: the step's message text (SPEC §2.10)
    interlock: Expr | None = None
    supervision: Expr | None = None
    actions: tuple[ActionRow, ...] = ()
    loc: SourceLocation = NOWHERE
    interlock_loc: SourceLocation | None = None
    supervision_loc: SourceLocation | None = None


@dataclass(frozen=True, slots=True)
class Transition:
    """``TRANSITION T1 "name" FROM S1 TO S2 := cond;``. ``sources``/``targets`` hold step
    numbers; several sources = simultaneous join, several targets = simultaneous divergence;
    ``targets == ()`` means ``TO STOP`` (branch stop). ``condition`` None = empty (holds).
    Written order within the file is the priority at an alternative divergence."""

    number: int
    name: str
    sources: tuple[int, ...]
    targets: tuple[int, ...]
    condition: Expr | None = None
    loc: SourceLocation = NOWHERE
    source_locs: tuple[SourceLocation, ...] = ()
    target_locs: tuple[SourceLocation, ...] = ()


@dataclass(frozen=True, slots=True)
class Sequence:
    number: int
    name: str
    steps: tuple[Step, ...]
    transitions: tuple[Transition, ...]
    loc: SourceLocation = NOWHERE


@dataclass(frozen=True, slots=True)
class VarDecl:
    """A static FB variable from ``VAR ... END_VAR`` (type name upper-case, ``init`` a Const)."""

    name: str
    type: str
    init: Const | None = None
    loc: SourceLocation = NOWHERE


@dataclass(frozen=True, slots=True)
class SymbolDecl:
    """``"Start_button" : I0.7 : BOOL // comment`` inside SYMBOLS ... END_SYMBOLS."""

    name: str
    address: str
    type: str
    comment: str = ""
    loc: SourceLocation = NOWHERE


@dataclass(frozen=True, slots=True)
class ChartOptions:
    """FB header options (SPEC §3). ``order``: "graph" (SPEC §2.2 default) or "codesys"."""

    parameters: str = "STANDARD"  # MINIMUM | STANDARD | MAXIMUM | USER
    skip_steps: bool = False
    ack_required: bool = True
    messages: bool = False
    ack_forces_switch: bool = False
    order: Literal["graph", "codesys"] = "graph"


@dataclass(frozen=True, slots=True)
class Chart:
    """One GRAPH FB as written."""

    name: str
    fb_number: int | None = None
    db_number: int | None = None
    options: ChartOptions = field(default_factory=ChartOptions)
    option_locs: tuple[tuple[str, SourceLocation], ...] = ()
    vars: tuple[VarDecl, ...] = ()
    symbols: tuple[SymbolDecl, ...] = ()
    before: tuple[PermanentInstruction, ...] = ()
    sequences: tuple[Sequence, ...] = ()
    after: tuple[PermanentInstruction, ...] = ()
    file: str = "<input>"
    loc: SourceLocation = NOWHERE

    def all_steps(self) -> tuple[Step, ...]:
        return tuple(s for seq in self.sequences for s in seq.steps)

    def all_transitions(self) -> tuple[Transition, ...]:
        return tuple(t for seq in self.sequences for t in seq.transitions)
