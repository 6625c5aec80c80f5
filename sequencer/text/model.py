"""The source chart: what a `.s7g` file says, with the place of every element
(docs/chart-format.md).

The parser builds this model; the validator reads it and reports diagnostics; the compiler
turns it into an immutable, int-indexed ``CompiledChart``. Nothing here evaluates anything.
Step and transition numbers are unique within one FB (a jump may target any sequencer).
Expressions, action rows and permanent instructions are the step language of
``steps.syntax``, re-exported here so that the model reads whole.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

from s7graph.engine.errors import SourceLocation
from s7graph.steps.syntax import (
    NOWHERE,
    ActionOperand,
    ActionRow,
    Assignment,
    Binary,
    BlockCall,
    Coil,
    Const,
    Expr,
    FuncCall,
    Operand,
    PermanentInstruction,
    StepAttr,
    StepTarget,
    TransAttr,
    Unary,
)

__all__ = [  # the structure, and the step language it holds (``steps.syntax``)
    "NOWHERE",
    "ActionOperand",
    "ActionRow",
    "Assignment",
    "Binary",
    "BlockCall",
    "Chart",
    "ChartOptions",
    "Coil",
    "Const",
    "Expr",
    "FuncCall",
    "Operand",
    "PermanentInstruction",
    "Sequence",
    "Step",
    "StepAttr",
    "StepTarget",
    "SymbolDecl",
    "TransAttr",
    "Transition",
    "Unary",
    "VarDecl",
]

# ------------------------------------------------------ structure (docs/semantics.md, "Structure")


@dataclass(frozen=True, slots=True)
class Step:
    number: int
    name: str
    initial: bool = False
    message: str = ""  # the second string after the name (docs/semantics.md, "Messages")
    interlock: Expr | None = None
    supervision: Expr | None = None
    actions: tuple[ActionRow, ...] = ()
    loc: SourceLocation = NOWHERE
    interlock_loc: SourceLocation | None = None
    supervision_loc: SourceLocation | None = None
    comment: str = ""  # the comments written with it, verbatim (sequencer.text.comments)
    trailing: str = ""  # the comments at the end of its first line, verbatim


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
    comment: str = ""
    trailing: str = ""


@dataclass(frozen=True, slots=True)
class Sequence:
    number: int
    name: str
    steps: tuple[Step, ...]
    transitions: tuple[Transition, ...]
    loc: SourceLocation = NOWHERE
    comment: str = ""
    trailing: str = ""


@dataclass(frozen=True, slots=True)
class VarDecl:
    """A static FB variable from ``VAR ... END_VAR`` (type name upper-case, ``init`` a Const)."""

    name: str
    type: str
    init: Const | None = None
    loc: SourceLocation = NOWHERE
    comment: str = ""
    trailing: str = ""


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
    """FB header options (docs/chart-format.md). ``order``: "graph" (docs/semantics.md, "One FB
    call" default) or "codesys"."""

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
    comment: str = ""  # what stands above FUNCTION_BLOCK
    trailing: str = ""  # the comments at the end of the FUNCTION_BLOCK line
    end_comment: str = ""  # the comments after the last element

    def all_steps(self) -> tuple[Step, ...]:
        return tuple(s for seq in self.sequences for s in seq.steps)

    def all_transitions(self) -> tuple[Transition, ...]:
        return tuple(t for seq in self.sequences for t in seq.transitions)
