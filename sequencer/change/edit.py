"""Editing a chart: the table of edit operations, applying one, and an editing session
with undo and redo (docs/online-change.md, "Editing charts (core)").

The model is the source of truth: a chart is immutable, an edit gives a new chart (sharing
what it does not change) validated by the same rules as ``s7graph check``
(``sequencer.checks.validate``), or a refusal naming the problem while the chart stays as it
was. The source view is the chart written as text; a text typed there comes back through
the ``set_source`` operation. ``OPERATIONS`` is the one table of what can be done, to which
element, with which arguments; a user interface or a bus command builds edits from it
(``make_edit``) and so cannot build anything else.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import MISSING, dataclass, fields, replace
from typing import Any, Final, Literal

from s7graph.engine.literals import shorten
from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.change.base import (
    MAX_NAME,
    MAX_UNDO,
    Edit,
    EditRefused,
    Refusal,
    checked_number,
    checked_text,
)
from s7graph.sequencer.change.content import (
    AddRow,
    ChangeRow,
    MoveRow,
    RemoveRow,
    RenameSequence,
    RenameStep,
    RenameTransition,
    RenumberStep,
    RenumberTransition,
    SetCondition,
    SetInitial,
    SetInterlock,
    SetMessage,
    SetOption,
    SetSource,
    SetSupervision,
)
from s7graph.sequencer.change.structure import (
    BranchStop,
    DeleteAlternativeBranch,
    DeleteSequence,
    DeleteSimultaneousBranch,
    DeleteStep,
    DeleteTransition,
    InsertAlternativeBranch,
    InsertSequence,
    InsertSimultaneousBranch,
    InsertStep,
    Jump,
    new_step,
    new_transition,
)
from s7graph.sequencer.change.typed import RowFields, check_bounds
from s7graph.sequencer.checks.diagnostics import Diagnostic
from s7graph.sequencer.checks.interfaces import ProgramBlocks
from s7graph.sequencer.checks.validate import validate
from s7graph.sequencer.text.elements import (
    Ref,
    RowRef,
    SequenceRef,
    StepRef,
    TransitionRef,
    element_of,
    find,
    label,
)
from s7graph.sequencer.text.model import Chart, Sequence

Target = Literal["step", "row", "transition", "sequence", "chart"]

# The arguments naming the element an operation acts on, filled from the selection.
_ELEMENT_ARGS: Final[dict[Target, tuple[str, ...]]] = {
    "step": ("step",),
    "row": ("step", "index"),
    "transition": ("transition",),
    "sequence": ("sequence",),
    "chart": (),
}


@dataclass(frozen=True, slots=True)
class Argument:
    name: str
    type: str  # "int", "str", "bool", "int | None", "RowFields"
    default: object = MISSING  # MISSING: required

    @property
    def required(self) -> bool:
        return self.default is MISSING


@dataclass(frozen=True, slots=True)
class Operation:
    """One edit operation: its stable ``name`` (for a bus command), its ``edit`` class,
    the kind of element it acts on, the menu ``title`` (S7-GRAPH's wording) and the
    ``phrase`` of the undo and redo line (``describe``: the edit's fields in braces)."""

    name: str
    edit: type[Edit]
    target: Target
    title: str
    phrase: str

    @property
    def doc(self) -> str:
        """What the operation does (its class's docstring, one paragraph)."""
        return " ".join((self.edit.__doc__ or "").split())

    @property
    def hint(self) -> str:
        """What the operation does, for the editor's user (its tooltip): ``HINTS``."""
        return HINTS[self.name]

    @property
    def element_arguments(self) -> tuple[str, ...]:
        """The leading arguments that name the element (filled from the selection)."""
        return _ELEMENT_ARGS[self.target]

    @property
    def arguments(self) -> tuple[Argument, ...]:
        return tuple(
            Argument(f.name, str(f.type), f.default)
            for f in fields(self.edit)  # type: ignore[arg-type]
        )

    def on(self, ref: Ref | None, **values: object) -> Edit:
        """The edit of this operation on the element ``ref`` (the selection), with the
        other arguments ``values``."""
        names = self.element_arguments
        got: tuple[object, ...] = ()
        if self.target == "row" and isinstance(ref, RowRef):
            got = (ref.step, ref.index)
        elif self.target == "step" and isinstance(ref, StepRef | RowRef):
            got = (ref.number if isinstance(ref, StepRef) else ref.step,)
        elif (self.target == "transition" and isinstance(ref, TransitionRef)) or (
            self.target == "sequence" and isinstance(ref, SequenceRef)
        ):
            got = (ref.number,)
        if len(got) != len(names):
            raise EditRefused(f"{self.title} acts on a {self.target}; select one first")
        return make_edit(self.name, {**dict(zip(names, got, strict=True)), **values})


# The editor's tooltip of each operation, written for its user (the docstrings are for
# developers); the selected step, transition or sequencer is "this".
HINTS: Final[dict[str, str]] = {
    "rename_step": "The step's name, shown in its box.",
    "renumber_step": "The step's number; every transition, ON/OFF row and condition naming the"
    " step follows.",
    "set_initial": "An initial step is active after the sequencer is initialized (INIT_SQ).",
    "set_message": "The text of this step's interlock and supervision messages; empty: none.",
    "set_interlock": "While this condition does not hold, the rows marked C do not run and the"
    " step shows an interlock error; empty: no interlock.",
    "set_supervision": "While this condition holds the step is faulted and does not switch,"
    " e.g. S2.U > T#10S; empty: no supervision.",
    "add_row": "Add an action row to this step.",
    "insert_alternative_branch": "A new transition leaving this step, with the lowest priority,"
    " leading to the step numbered here.",
    "delete_step": "Delete this step and its following transition; what led to the step then"
    " leads where that transition led.",
    "delete_simultaneous_branch": "Delete the simultaneous path that starts with this step, up"
    " to its join, branch stop or jump.",
    "change_row": "Replace the selected action row by the fields.",
    "remove_row": "Remove the selected action row.",
    "move_row": "Move the selected action row; rows run top to bottom.",
    "rename_transition": "The transition's name, shown beside it.",
    "renumber_transition": "The transition's number; every condition reading Tn.TT follows.",
    "set_condition": "The condition for the transition to switch; empty: it holds at once"
    " (warning W120).",
    "insert_step": "Insert a new step and transition after this transition.",
    "insert_simultaneous_branch": "This transition also activates a new step, whose path joins"
    " the transition numbered here.",
    "jump": "End the path after this transition with a jump to the step numbered here, in any"
    " sequencer of the block.",
    "branch_stop": "End the path after this transition: a branch stop.",
    "delete_transition": "Delete this transition (an alternative path without steps, a jump or"
    " a branch stop) when every step keeps a way in and out.",
    "delete_alternative_branch": "Delete the alternative path that starts with this transition,"
    " up to where it ends or joins another path.",
    "rename_sequence": "The sequencer's name.",
    "delete_sequence": "Delete this sequencer with its steps and transitions (not the only one,"
    " nor one that others jump into).",
    "insert_sequence": "Add a sequencer: an initial step and a transition back to it.",
    "set_option": "A block option, e.g. SKIP_STEPS := TRUE, as the chart's header writes it.",
    "set_source": "Replace the whole chart by the text of the source view.",
}

# The one table of edit operations, by the element they act on (STEP7 comprehensive guide vol. 2,
# ch. 14 for
# S7-GRAPH's Insert menu: Step + Transition, Alternative/Simultaneous branch, Jump, Branch
# stop, Sequencer).
OPERATIONS: Final[tuple[Operation, ...]] = (
    Operation("rename_step", RenameStep, "step", "Name", 'rename S{step} to "{name}"'),
    Operation("renumber_step", RenumberStep, "step", "Number", "renumber S{step} to S{to}"),
    Operation("set_initial", SetInitial, "step", "Initial step", "initial step setting of S{step}"),
    Operation("set_message", SetMessage, "step", "Message text", "message text of S{step}"),
    Operation("set_interlock", SetInterlock, "step", "Interlock", "interlock of S{step}"),
    Operation("set_supervision", SetSupervision, "step", "Supervision", "supervision of S{step}"),
    Operation("add_row", AddRow, "step", "Add action row", "add action row to S{step}"),
    Operation(
        "insert_alternative_branch",
        InsertAlternativeBranch,
        "step",
        "Alternative branch",
        "insert alternative branch at S{step}",
    ),
    Operation("delete_step", DeleteStep, "step", "Delete step", "delete S{step}"),
    Operation(
        "delete_simultaneous_branch",
        DeleteSimultaneousBranch,
        "step",
        "Delete simultaneous branch",
        "delete simultaneous branch at S{step}",
    ),
    Operation(
        "change_row", ChangeRow, "row", "Change action row", "change action row {index} of S{step}"
    ),
    Operation(
        "remove_row", RemoveRow, "row", "Remove action row", "remove action row {index} of S{step}"
    ),
    Operation("move_row", MoveRow, "row", "Move action row", "move action row {index} of S{step}"),
    Operation(
        "rename_transition",
        RenameTransition,
        "transition",
        "Name",
        'rename T{transition} to "{name}"',
    ),
    Operation(
        "renumber_transition",
        RenumberTransition,
        "transition",
        "Number",
        "renumber T{transition} to T{to}",
    ),
    Operation(
        "set_condition", SetCondition, "transition", "Condition", "condition of T{transition}"
    ),
    Operation(
        "insert_step",
        InsertStep,
        "transition",
        "Step + Transition",
        "insert step after T{transition}",
    ),
    Operation(
        "insert_simultaneous_branch",
        InsertSimultaneousBranch,
        "transition",
        "Simultaneous branch",
        "insert simultaneous branch at T{transition}",
    ),
    Operation("jump", Jump, "transition", "Jump", "jump after T{transition} to S{to}"),
    Operation(
        "branch_stop", BranchStop, "transition", "Branch stop", "branch stop after T{transition}"
    ),
    Operation(
        "delete_transition",
        DeleteTransition,
        "transition",
        "Delete transition",
        "delete T{transition}",
    ),
    Operation(
        "delete_alternative_branch",
        DeleteAlternativeBranch,
        "transition",
        "Delete alternative branch",
        "delete alternative branch at T{transition}",
    ),
    Operation(
        "rename_sequence",
        RenameSequence,
        "sequence",
        "Name",
        'rename sequencer {sequence} to "{name}"',
    ),
    Operation(
        "delete_sequence",
        DeleteSequence,
        "sequence",
        "Delete sequencer",
        "delete sequencer {sequence}",
    ),
    Operation("insert_sequence", InsertSequence, "chart", "Sequencer", "insert sequencer"),
    Operation("set_option", SetOption, "chart", "Block option", "block option {option}"),
    Operation("set_source", SetSource, "chart", "Source", "edit in the source view"),
)
BY_NAME: Final[dict[str, Operation]] = {op.name: op for op in OPERATIONS}
_BY_CLASS: Final[dict[type[Edit], Operation]] = {op.edit: op for op in OPERATIONS}


def operations_for(ref: Ref | None) -> tuple[Operation, ...]:
    """The operations that act on the element ``ref`` names (None: on the chart)."""
    kinds: set[Target] = {"chart"}
    if isinstance(ref, StepRef):
        kinds.add("step")
    elif isinstance(ref, RowRef):
        kinds |= {"row", "step"}
    elif isinstance(ref, TransitionRef):
        kinds.add("transition")
    elif isinstance(ref, SequenceRef):
        kinds.add("sequence")
    return tuple(op for op in OPERATIONS if op.target in kinds)


def _value(arg: Argument, value: object, op: str) -> object:
    what = f"{op}: {arg.name}"
    if arg.type == "RowFields":
        if isinstance(value, RowFields):
            return value
        if not isinstance(value, Mapping):
            raise EditRefused(f"{what} must be the fields of an action row")
        known = {f.name: f for f in fields(RowFields)}
        extra = sorted(set(value) - set(known))
        if extra:
            raise EditRefused(f"{what}: unknown field {extra[0]!r}; fields are {', '.join(known)}")
        kept: dict[str, Any] = {}
        for name, v in value.items():
            want = bool if name == "interlocked" else str
            if not isinstance(v, want):
                raise EditRefused(f"{what}.{name} must be {want.__name__}")
            kept[name] = v
        try:
            return RowFields(**kept)
        except TypeError:
            raise EditRefused(f"{what} needs a qualifier and an operand") from None
    if value is None and arg.type.endswith("| None"):
        return None
    if arg.type.startswith("int"):
        if not isinstance(value, int) or isinstance(value, bool):
            raise EditRefused(f"{what} must be a whole number")
    elif arg.type == "bool":
        if not isinstance(value, bool):
            raise EditRefused(f"{what} must be true or false")
    elif not isinstance(value, str):
        raise EditRefused(f"{what} must be text")
    return value


def make_edit(name: str, args: Mapping[str, object]) -> Edit:
    """The edit operation ``name`` with ``args`` (as a bus command or a form sends them),
    every argument checked against ``OPERATIONS``; else refuse naming the problem."""
    op = BY_NAME.get(name) if isinstance(name, str) else None
    if op is None:
        raise EditRefused(f"unknown edit operation {str(name)[:40]!r}")
    if not isinstance(args, Mapping):
        raise EditRefused(f"{name}: the arguments must be named")
    params = {a.name: a for a in op.arguments}
    extra = sorted(str(k) for k in args if k not in params)
    if extra:
        raise EditRefused(
            f"{name}: unknown argument {extra[0][:40]!r}; it takes {', '.join(params) or 'none'}"
        )
    values = {}
    for a in params.values():
        if a.name in args:
            values[a.name] = _value(a, args[a.name], name)
        elif a.default is MISSING:
            raise EditRefused(f"{name}: missing argument {a.name!r}")
    return op.edit(**values)


def describe(edit: Edit) -> str:
    """The undo and redo line of ``edit``: its operation's ``phrase`` with the edit's
    fields as the chart says them (``rename S2 to "Clamp part"``, ``condition of T3``)."""
    op = _BY_CLASS.get(type(edit))
    if op is None:
        return type(edit).__name__
    said = {f.name: _said(f.name, getattr(edit, f.name)) for f in fields(edit)}  # type: ignore[arg-type]
    return op.phrase.format_map(said)


def _said(name: str, value: object) -> str:
    """One field of an edit in an undo line: a number as it is, a row index counted from 1
    (as ``check`` prints rows), a text cut short; never a Python repr."""
    if name == "index" and isinstance(value, int):
        return str(value + 1)
    return shorten(str(value), 24)


# ---------------------------------------------------------------- applying an edit


@dataclass(frozen=True, slots=True)
class Outcome:
    """What an edit gave: the chart (unchanged when refused), its diagnostics, the
    refusal (None when made) and the element to select."""

    chart: Chart
    diagnostics: tuple[Diagnostic, ...]
    refusal: Refusal | None = None
    selection: Ref | None = None

    @property
    def made(self) -> bool:
        return self.refusal is None


def diagnostics_of(
    chart: Chart, symbols: SymbolTable | None, blocks: ProgramBlocks | None = None
) -> tuple[Diagnostic, ...]:
    """The validator's diagnostics of ``chart``, sorted by place; ``blocks``: the interfaces
    of the CPU's user blocks, whose FBs' variables the chart reads by name
    (``"Motor_DB".Running``) as a download's compile reads them, and against which its calls
    of those blocks are checked as a chart-only download checks them (E047,
    ``sequencer.calls.unfit_calls``): what the download would refuse is listed before it.
    One pass of the validator (``validate(held=blocks)``)."""
    return tuple(validate(chart, symbols, held=blocks))


def _checked(
    chart: Chart, symbols: SymbolTable | None, blocks: ProgramBlocks | None = None
) -> tuple[Diagnostic, ...]:
    """``diagnostics_of`` a chart within the editor's limits."""
    check_bounds(chart)
    try:
        return diagnostics_of(chart, symbols, blocks)
    except RecursionError:  # pragma: no cover - check_bounds bounds the nesting
        raise EditRefused("the chart nests too deeply to check") from None


def apply_edit(
    chart: Chart,
    edit: Edit,
    symbols: SymbolTable | None = None,
    diagnostics: tuple[Diagnostic, ...] | None = None,
    *,
    blocks: ProgramBlocks | None = None,
) -> Outcome:
    """``edit`` applied to ``chart``: the edited chart with all its diagnostics (errors
    included: they are listed, the chart is kept), or a refusal with ``chart`` and its
    ``diagnostics`` (computed when not given); ``blocks`` as ``diagnostics_of``. Never
    raises for any input."""
    try:
        if not isinstance(edit, Edit):
            raise EditRefused(f"not an edit operation: {type(edit).__name__}")
        edited, selection = edit.apply(chart)
        checked = _checked(edited, symbols, blocks)
        across = _new_crossings(checked, chart, symbols, diagnostics, blocks)
        if across is not None:  # the structure edits cannot know every way a path leaves
            raise EditRefused(across.message)
        return Outcome(edited, checked, None, selection)
    except EditRefused as exc:
        refusal = Refusal(exc.reason, exc.diagnostics)
    except RecursionError:  # pragma: no cover - texts and charts are bounded before
        refusal = Refusal("the edit nests too deeply")
    if diagnostics is None:
        diagnostics = diagnostics_of(chart, symbols, blocks)
    return Outcome(chart, diagnostics, refusal, None)


def _new_crossings(
    checked: tuple[Diagnostic, ...],
    chart: Chart,
    symbols: SymbolTable | None,
    before: tuple[Diagnostic, ...] | None,
    blocks: ProgramBlocks | None = None,
) -> Diagnostic | None:
    """The first branch or join across sequencers (E015: it does not compile) an edit made
    that ``chart`` did not have (None: none)."""
    made = [d for d in checked if d.code == "E015"]
    if not made:
        return None
    had = before if before is not None else tuple(validate(chart, symbols, readable=blocks))
    known = {d.message for d in had if d.code == "E015"}
    return next((d for d in made if d.message not in known), None)


def new_chart(
    name: str = "GRAPH_block", fb_number: int | None = None, db_number: int | None = None
) -> Chart:
    """A new GRAPH block as TIA Portal creates one: sequencer 1 with the initial step S1
    and transition T1 (empty condition) jumping back to S1."""
    name = checked_text(name, "the block name", MAX_NAME)
    for n in (fb_number, db_number):
        if n is not None:
            checked_number(n, "a block number")
    seq = Sequence(1, "", (new_step(1, initial=True),), (new_transition(1, (1,), (1,)),))
    return Chart(name, fb_number, db_number, sequences=(seq,), file=f"{name}.s7g")


# ---------------------------------------------------------------- the session


@dataclass(frozen=True, slots=True)
class _Done:
    chart: Chart
    diagnostics: tuple[Diagnostic, ...]
    selection: Ref | None
    what: str


@dataclass(frozen=True, slots=True)
class Session:
    """An editor's state as one immutable value: the chart, its diagnostics, the selected
    element, the last refusal, and the charts to undo and redo (at most ``MAX_UNDO``);
    ``blocks``: the interfaces of the CPU's user blocks, whose FBs' variables the chart
    reads by name and whose calls it checks (``diagnostics_of``). Every method returns the
    next state; none raises except ``open`` on a chart beyond the editor's limits."""

    chart: Chart
    diagnostics: tuple[Diagnostic, ...]
    symbols: SymbolTable | None = None
    selection: Ref | None = None
    refusal: Refusal | None = None
    done: tuple[_Done, ...] = ()
    undone: tuple[_Done, ...] = ()
    blocks: ProgramBlocks | None = None

    @classmethod
    def open(
        cls, chart: Chart, symbols: SymbolTable | None = None, blocks: ProgramBlocks | None = None
    ) -> Session:
        """A session on ``chart``; raises ``EditRefused`` when the chart is beyond the
        editor's limits (``change.base``: steps, transitions, rows, nesting)."""
        return cls(chart, _checked(chart, symbols, blocks), symbols, blocks=blocks)

    def with_blocks(self, blocks: ProgramBlocks | None) -> Session:
        """The session checking its chart against ``blocks`` from now on (the CPU's user
        blocks changed), its diagnostics made again."""
        diagnostics = _checked(self.chart, self.symbols, blocks)
        return replace(self, blocks=blocks, diagnostics=diagnostics)

    @property
    def has_errors(self) -> bool:
        """Whether the chart does not compile (a download refuses it)."""
        return any(d.is_error for d in self.diagnostics)

    @property
    def undo_label(self) -> str | None:
        return self.done[-1].what if self.done else None

    @property
    def redo_label(self) -> str | None:
        return self.undone[-1].what if self.undone else None

    def apply(self, edit: Edit) -> Session:
        """The state after ``edit``: made (undoable, redo cleared) or refused (the chart
        as it was, ``refusal`` saying why)."""
        out = apply_edit(self.chart, edit, self.symbols, self.diagnostics, blocks=self.blocks)
        if out.refusal is not None:
            return replace(self, refusal=out.refusal)
        done = _Done(self.chart, self.diagnostics, self.selection, describe(edit))
        return replace(
            self,
            chart=out.chart,
            diagnostics=out.diagnostics,
            selection=out.selection,
            refusal=None,
            done=(*self.done, done)[-MAX_UNDO:],
            undone=(),
        )

    def undo(self) -> Session:
        """The state before the last edit made (the very chart it was); as it is when
        there is nothing to undo."""
        if not self.done:
            return replace(self, refusal=Refusal("nothing to undo"))
        last = self.done[-1]
        back = _Done(self.chart, self.diagnostics, self.selection, last.what)
        return replace(
            self,
            chart=last.chart,
            diagnostics=last.diagnostics,
            selection=last.selection,
            refusal=None,
            done=self.done[:-1],
            undone=(*self.undone, back),
        )

    def redo(self) -> Session:
        """The state after the last edit undone."""
        if not self.undone:
            return replace(self, refusal=Refusal("nothing to redo"))
        last = self.undone[-1]
        again = _Done(self.chart, self.diagnostics, self.selection, last.what)
        return replace(
            self,
            chart=last.chart,
            diagnostics=last.diagnostics,
            selection=last.selection,
            refusal=None,
            done=(*self.done, again),
            undone=self.undone[:-1],
        )

    def select(self, ref: Ref | None) -> Session:
        """Select the element ``ref`` (None: nothing); refused when there is none."""
        if ref is not None and find(self.chart, ref) is None:
            return replace(self, refusal=Refusal(f"there is no {label(ref)} in the chart"))
        return replace(self, selection=ref, refusal=None)

    def select_diagnostic(self, d: Diagnostic) -> Session:
        """Select the element diagnostic ``d`` concerns (a click in the diagnostics list)."""
        return self.select(element_of(d, self.chart))
