"""The command vocabulary: one msgspec struct per operation, a tagged union on ``op``.

Every remote command a page, a shell or a bus client can send a CPU is one struct here,
with typed arguments (``args``) and, as class attributes, what the rest of the system
derives from it: the lowest role allowed (``web.access.roles`` builds its table, and
docs/bus.md and docs/security.md, from these), the S7-GRAPH pin it acts as
(``web.bus.live`` builds its pin maps from them), what it does and an example of its
arguments, its conflict group and where it is carried out (the FB, the RUN/STOP switch,
the force table, the online change) and how a shell gives it (``shell``: ``web.cli``
builds its sub-commands from it, docs/cli.md lists them, :func:`shell_markdown`); the
shell's ``s7graph send`` (:func:`command_args`), the page's buttons and docs/bus.md's
argument table (:func:`arguments_markdown`) read them too. The wire format is the one of
the former ``Command(op, fb, args: dict)``: ``{"op": "step_on", "fb": "FILL", "user": ...,
"token": ..., "origin": ..., "args": {"step": 3}}`` decodes to :class:`StepOn`.
``Command(op=..., fb=..., args={...})`` still builds a command: it returns the struct of
that op, or raises ``ValueError`` with a one-line reason. An argument struct reads like the
dict it was (``args.get("step")``, ``dict(args)``: the arguments given).

A page or a shell builds the struct of its op (``StepOn(fb=..., args=StepArgs(step=3))``),
so a misspelt op or argument is a type error; msgspec checks the constraints (a step from
1, the names' patterns) only when it decodes, so a sender passes the struct through
:func:`checked` before sending it.

This module sits at the root of ``web`` (below ``access`` and ``bus``): it imports only
msgspec and the layers below ``web``.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass
from typing import Annotated, Any, ClassVar, Literal, TypeVar, cast, get_args

import msgspec
import msgspec.inspect as mi
from msgspec import UNSET, Meta, Struct, UnsetType

from s7graph.sequencer.change.base import MAX_SOURCE

__all__ = [
    "COMMAND_TYPES",
    "MODES",
    "NAME_PATTERN",
    "OPS",
    "REMOVED_CHOICES",
    "AnyCommand",
    "Args",
    "Command",
    "Mode",
    "Shell",
    "args_of",
    "argument_field",
    "arguments_markdown",
    "checked",
    "command_args",
    "command_type",
    "explain",
    "make_command",
    "op_of",
    "shell_markdown",
    "shell_usage",
]

Mode = Literal["AUTO", "MAN", "TAP", "TOP"]
MODES: tuple[Mode, ...] = get_args(Mode)
Removed = Literal["keep", "init"]
REMOVED_CHOICES: tuple[str, ...] = get_args(Removed)

# A name that is safe inside a zenoh key expression and in a scene node path.
NAME_PATTERN = r"^[A-Za-z_][A-Za-z0-9_.\-]{0,63}\Z"
Name = Annotated[str, Meta(pattern=NAME_PATTERN)]
# who and from where (web.access.users.USER_PATTERN; "" = nobody claimed a name). ``\Z``,
# not ``$``: a ``$`` matches before a final newline, and ``olga\n`` is not ``olga``.
UserName = Annotated[str, Meta(pattern=r"^([A-Za-z0-9._-]{1,32})?\Z")]
Token = Annotated[str, Meta(pattern=r"^[A-Za-z0-9_-]{0,64}\Z")]
Origin = Annotated[str, Meta(pattern=r"^[ -~]{0,160}\Z")]  # printable ASCII: safe in a log line
# a command's number in its session (1, 2, ...) and its signature, the session key's
# HMAC-SHA256 in hex (web.access.scram)
Seq = Annotated[int, Meta(ge=0, le=2**63 - 1)]
Mac = Annotated[str, Meta(pattern=r"^([0-9a-f]{64})?\Z")]
Scalar = bool | int | float | str | None
StepNumber = Annotated[int, Meta(ge=1, le=65535)]
MsgKey = Annotated[str, Meta(min_length=1, max_length=128)]
MsgId = Annotated[int, Meta(ge=1, le=0xFFFFFFFF)] | MsgKey
Version = Annotated[int, Meta(ge=0, le=2**63 - 1)]
Source = Annotated[str, Meta(max_length=MAX_SOURCE)]
MAX_FILE_NAME = 128
FileName = Annotated[str, Meta(min_length=1, max_length=MAX_FILE_NAME)]
MAX_FORCE_TEXT = 64  # an address or symbol, or a value's text, in a force command
ForceText = Annotated[str, Meta(min_length=1, max_length=MAX_FORCE_TEXT)]
ForceValue = bool | int | float | ForceText | None
MAX_COMMENT = 256  # an acknowledgement's comment (an OPC UA client's Acknowledge)
Comment = Annotated[str, Meta(max_length=MAX_COMMENT)]


# ---------------------------------------------------------------- arguments


class Args(Struct, frozen=True, forbid_unknown_fields=True, kw_only=True):
    """The arguments of one op; reads like the dict of the arguments given (an optional
    argument left out is not there)."""

    def given(self) -> dict[str, Any]:
        return {f: v for f in self.__struct_fields__ if (v := getattr(self, f)) is not UNSET}

    def keys(self) -> list[str]:
        return list(self.given())

    def get(self, name: str, default: Any = None) -> Any:
        return self.given().get(name, default)

    def __getitem__(self, name: str) -> Any:
        return self.given()[name]

    def __contains__(self, name: object) -> bool:
        return name in self.given()

    def __iter__(self) -> Iterator[str]:
        return iter(self.given())

    def __len__(self) -> int:
        return len(self.given())


class NoArgs(Args, frozen=True, kw_only=True):
    """No argument: ``{}``."""


class StepArgs(Args, frozen=True, kw_only=True):
    step: StepNumber


MAX_SET_STEPS = 64  # steps one set_steps names


class StepsArgs(Args, frozen=True, kw_only=True):
    steps: Annotated[list[StepNumber], Meta(min_length=1, max_length=MAX_SET_STEPS)]


class ModeArgs(Args, frozen=True, kw_only=True):
    mode: Mode


class OnArgs(Args, frozen=True, kw_only=True):
    on: bool


class MessageArgs(Args, frozen=True, kw_only=True):
    """``{"msg_id": id}``, and the acknowledger's ``comment`` (the audit row keeps it)."""

    msg_id: MsgId
    comment: Comment | UnsetType = UNSET


class ForceArgs(Args, frozen=True, kw_only=True):
    """``{"address": "I0.3", "value": true}`` (value null: unforce) or ``{"all": true}``."""

    address: ForceText | UnsetType = UNSET
    value: ForceValue | UnsetType = UNSET
    all: bool | UnsetType = UNSET

    def __post_init__(self) -> None:
        if self.all is not UNSET:
            if self.all is not True or self.address is not UNSET or self.value is not UNSET:
                raise ValueError('unforce every job with {"all": true} alone')
            return
        if self.address is UNSET or self.value is UNSET:
            raise ValueError(
                'force takes {"address": "I0.3", "value": true} (value null: unforce) or '
                '{"all": true}'
            )
        _finite(self.value)


class ModifyArgs(Args, frozen=True, kw_only=True):
    """``{"address": "M10.0", "value": true}``: the operand and the value written once."""

    address: ForceText
    value: bool | int | float | ForceText

    def __post_init__(self) -> None:
        _finite(self.value)


def _finite(value: object) -> None:
    """A value a command carries is a finite number: JSON has no infinity or NaN, and
    would carry one as null — for ``force``, *unforce*."""
    if isinstance(value, float) and not math.isfinite(value):
        raise ValueError(f"value {value}: the bus carries finite numbers only (no inf or NaN)")


MAX_BLOCK_FILES = 8  # S7-SCL sources one download brings
BlockSources = Annotated[dict[FileName, Source], Meta(max_length=MAX_BLOCK_FILES)]


class DownloadArgs(Args, frozen=True, kw_only=True):
    """The chart text; the chart version the sender saw, what to do with active steps the
    change removes, and whether only to preview the change; ``blocks``: changed S7-SCL
    sources the chart's calls reach, by the file name of the CPU's ``--blocks`` source
    each replaces (swapped in with the chart); ``file``: the name the chart's diagnostics
    give it (the engineer's file; without it, "the edited chart")."""

    source: Source
    base: Version | UnsetType = UNSET
    removed: Removed | UnsetType = UNSET
    preview: bool | UnsetType = UNSET
    blocks: BlockSources | UnsetType = UNSET
    file: FileName | UnsetType = UNSET


class UndoArgs(Args, frozen=True, kw_only=True):
    base: Version | UnsetType = UNSET
    removed: Removed | UnsetType = UNSET
    preview: bool | UnsetType = UNSET


class SaveArgs(Args, frozen=True, kw_only=True):
    file: FileName
    source: Source


class OpenArgs(Args, frozen=True, kw_only=True):
    file: FileName
    pou: FileName | UnsetType = UNSET  # the chart of a file that holds several (--pou)


# ---------------------------------------------------------------- commands


@dataclass(frozen=True, slots=True)
class Shell:
    """How a shell gives an op: ``s7graph NAME [ARGUMENT] --user U ...`` (``web.cli`` builds
    the sub-command, docs/cli.md lists it). ``help`` is the command's ``--help`` text; the
    op's one argument, if it has one, is the positional (``argument`` its help, else its
    choices; ``metavar`` its placeholder). With ``option`` the op is that option of command
    ``name`` (``ack --step N``, ``help`` the option's): given, it is sent instead of the
    command's own op. ``by_hand``: ``web.cli`` writes the command itself (it does more than
    send the op)."""

    name: str
    help: str = ""
    argument: str = ""
    metavar: str = ""
    option: str = ""
    by_hand: bool = False


class _CommandMeta(msgspec.StructMeta):
    """``Command(op=..., ...)`` builds the struct of that op (:func:`make_command`)."""

    def __call__(cls, *args: Any, **kwargs: Any) -> Any:
        if cls is Command:
            if args:
                raise TypeError("Command takes keyword arguments only")
            return make_command(**kwargs)
        return super().__call__(*args, **kwargs)


class Command(
    Struct,
    frozen=True,
    kw_only=True,
    forbid_unknown_fields=True,
    tag_field="op",
    metaclass=_CommandMeta,
):
    """An operator command (``cmd`` queryable), applied at a scan boundary: the base of
    every op's struct. ``user`` and ``token`` come from a ``login``; ``origin`` says where
    the command was given (``page 3 (127.0.0.1)``, ``shell``, ``bus``) for the audit;
    ``seq`` numbers the commands of a session and ``mac`` signs each with the session key
    (``web.access.scram.Signer``), so a captured command is refused when replayed and a
    changed one when it arrives (both required with a users file; unset in the demo).

    Class attributes of each op: ``role`` the lowest role allowed, ``pin`` the pin it acts
    as (shown in the role table), ``kind`` how (``edge``: a one-call edge of ``pin``;
    ``level``: ``pin`` held at ``held``; ``mode``: a mode selector; "" no pin), ``does``
    and ``example`` (its arguments) for the documentation; ``where`` it is carried out
    (``fb``: the FB at the scan boundary, ``web.bus.live``; ``cpu``: the RUN/STOP switch
    and the memory reset; ``force``: the force table, and ``modify``'s write into the CPU's
    memory; ``online``: the online change,
    ``web.bus.online``) and its ``group``: two commands of one group at the same scan
    boundary would act as simultaneous edges of one call, so the second is refused;
    ``shell`` how a shell gives it (None: only by ``s7graph send``); ``words`` what the
    page's notices call it, in the words of its buttons (never the op's wire name)."""

    role: ClassVar[str] = ""
    where: ClassVar[Literal["fb", "cpu", "force", "online"]] = "fb"
    group: ClassVar[str] = ""
    pin: ClassVar[str] = ""
    kind: ClassVar[Literal["edge", "level", "mode", ""]] = ""
    held: ClassVar[bool] = False
    does: ClassVar[str] = ""
    example: ClassVar[str] = ""
    shell: ClassVar[Shell | None] = None
    words: ClassVar[str] = ""

    fb: Name
    user: UserName = ""
    token: Token = ""
    origin: Origin = ""
    seq: Seq | UnsetType = UNSET  # left out of the JSON when not set: the wire format
    mac: Mac | UnsetType = UNSET  # of a command without them is the one it always was
    args: Args = NoArgs()

    @property
    def op(self) -> str:
        """The op's name on the bus (the tag)."""
        return op_of(type(self))

    @property
    def step(self) -> int | None:
        """The step of ``step_on``/``step_off``/``ack_step``, else None."""
        value = getattr(self.args, "step", None)
        return value if isinstance(value, int) and not isinstance(value, bool) else None

    @property
    def msg_id(self) -> int | str | None:
        """The message of an ``ack_msg`` command, else None."""
        value = getattr(self.args, "msg_id", None)
        return value if isinstance(value, int | str) and not isinstance(value, bool) else None

    @property
    def mode(self) -> str | None:
        """The mode of a ``mode`` command, else None."""
        value = getattr(self.args, "mode", None)
        return value if isinstance(value, str) else None


class Ack(Command, tag="ack", frozen=True, kw_only=True):
    words = "acknowledge"
    role, pin, kind = "operator", "ACK_EF", "edge"
    does = "acknowledge every supervision fault of the FB"
    shell = Shell(
        "ack", "Acknowledge the FB's supervision faults (ACK_EF), one step's or one message."
    )
    args: NoArgs = NoArgs()


class AckStep(Command, tag="ack_step", frozen=True, kw_only=True):
    words = "acknowledge step"
    group = "step"
    role, pin, kind = "operator", "ACK_S", "edge"
    does, example = "acknowledge one step's fault", '{"step": n}'
    shell = Shell("ack", "Only this step (ACK_S).", metavar="N", option="--step")
    args: StepArgs


class AckMsg(Command, tag="ack_msg", frozen=True, kw_only=True):
    words = "acknowledge message"
    role = "operator"
    does, example = "acknowledge one message of the alarm list", '{"msg_id": id}'
    shell = Shell("ack", "One message of the alarm list.", metavar="ID", option="--message")
    args: MessageArgs


class SetMode(Command, tag="mode", frozen=True, kw_only=True):
    words = "mode"
    group = "mode"
    role, pin, kind = "operator", "SW_AUTO/MAN/TAP/TOP", "mode"
    does, example = "switch the mode", '{"mode": "MAN"}'
    shell = Shell("mode", "Switch the FB's mode.", metavar="MODE")
    args: ModeArgs


class Init(Command, tag="init", frozen=True, kw_only=True):
    words = "initialize"
    group = "init"
    role, pin, kind = "operator", "INIT_SQ", "edge"
    does = "activate the initial steps"
    shell = Shell("init", "Initialize the sequencer (INIT_SQ).")
    args: NoArgs = NoArgs()


class Off(Command, tag="off", frozen=True, kw_only=True):
    words = "disable (OFF)"
    group = "init"
    role, pin, kind = "operator", "OFF_SQ", "edge"
    does = "deactivate every step"
    shell = Shell("off", "Switch the sequencer off (OFF_SQ).")
    args: NoArgs = NoArgs()


class Halt(Command, tag="halt", frozen=True, kw_only=True):
    words = "halt"
    role, pin, kind, held = "operator", "HALT_SQ", "level", True
    does, example = "halt / resume the sequencer", '{"on": true}'
    args: OnArgs


class TPush(Command, tag="t_push", frozen=True, kw_only=True):
    words = "T_PUSH (continue)"
    role, pin, kind = "operator", "T_PUSH", "edge"
    does = "switch a ready transition (TAP, TOP)"
    shell = Shell("t-push", "Switch a ready transition (TAP, TOP; T_PUSH).")
    args: NoArgs = NoArgs()


class StepOn(Command, tag="step_on", frozen=True, kw_only=True):
    words = "activate step"
    group = "step"
    role, pin, kind = "operator", "S_ON", "edge"
    does, example = "activate a step (MAN)", '{"step": n}'
    shell = Shell("step-on", "Activate a step (MAN, S_ON).", "The step number.")
    args: StepArgs


class StepOff(Command, tag="step_off", frozen=True, kw_only=True):
    words = "deactivate step"
    group = "step"
    role, pin, kind = "operator", "S_OFF", "edge"
    does, example = "deactivate a step (MAN)", '{"step": n}'
    shell = Shell("step-off", "Deactivate a step (MAN, S_OFF).", "The step number.")
    args: StepArgs


class SetSteps(Command, tag="set_steps", frozen=True, kw_only=True):
    words = "set step"
    group = "step"
    role = "operator"
    does = (
        "make the steps named the active ones of their sequences in one call (MAN): the "
        "others of those sequences leave with their final scan"
    )
    example = '{"steps": [n, ...]}'
    shell = Shell(
        "set-steps",
        "Make these steps the active ones of their sequences in one call (MAN): the steps "
        "active in those sequences now leave, other sequences keep theirs.",
        "The step numbers.",
        metavar="STEP",
    )
    args: StepsArgs


class EnIl(Command, tag="en_il", frozen=True, kw_only=True):
    words = "interlocks"
    role, pin, kind, held = "engineer", "EN_IL", "level", False
    does, example = "enable / disable interlocks", '{"on": false}'
    args: OnArgs


class EnSv(Command, tag="en_sv", frozen=True, kw_only=True):
    words = "supervisions"
    role, pin, kind, held = "engineer", "EN_SV", "level", False
    does, example = "enable / disable supervisions", '{"on": false}'
    args: OnArgs


class Force(Command, tag="force", frozen=True, kw_only=True):
    words = "force"
    where = "force"
    role = "engineer"
    does = (
        "force an input, output or flag (I, Q, M) until unforced: value null unforces it, "
        '`{"all": true}` unforces every job'
    )
    example = '{"address": "I0.3", "value": true}'
    shell = Shell("force", metavar="ADDRESS VALUE|off", by_hand=True)
    args: ForceArgs


class Modify(Command, tag="modify", frozen=True, kw_only=True):
    words = "modify"
    where = "force"
    role = "engineer"
    does = (
        "write an input, output, flag or data block value once at the scan boundary, not held"
        " (STEP 7's Modify): the program and the modules may write it again"
    )
    example = '{"address": "M10.0", "value": true}'
    shell = Shell("modify", metavar="ADDRESS VALUE", by_hand=True)
    args: ModifyArgs


class Download(Command, tag="download", frozen=True, kw_only=True):
    words = "download"
    where = "online"
    role = "engineer"
    does = "download a changed chart into the running FB (online change)"
    example = '{"source": "...", "base": 1, "removed": "keep", "preview": true}'
    shell = Shell("download", metavar="CHART.s7g", by_hand=True)
    args: DownloadArgs


class UndoDownload(Command, tag="undo_download", frozen=True, kw_only=True):
    words = "undo download"
    where = "online"
    role = "engineer"
    does = "put the chart before the last download back"
    example = '{"base": 2, "removed": "keep", "preview": true}'
    args: UndoArgs = UndoArgs()


class Save(Command, tag="save", frozen=True, kw_only=True):
    words = "save"
    where = "online"
    role = "engineer"
    does, example = (
        "write a chart into the CPU's project directory",
        ('{"file": "x.s7g", "source": "..."}'),
    )
    args: SaveArgs


class Open(Command, tag="open", frozen=True, kw_only=True):
    words = "open"
    where = "online"
    role = "engineer"
    does = "read a chart or importable file of the project directory"
    example = '{"file": "x.xml"}'
    args: OpenArgs


class Stop(Command, tag="stop", frozen=True, kw_only=True):
    words = "CPU to STOP"
    where = "cpu"
    role = "engineer"
    does = "the CPU's RUN/STOP switch to STOP (outputs to 0)"
    shell = Shell("stop", "Put the CPU in STOP, as its RUN/STOP switch (engineer; outputs to 0).")
    args: NoArgs = NoArgs()


class Start(Command, tag="start", frozen=True, kw_only=True):
    words = "CPU to RUN"
    where = "cpu"
    role = "engineer"
    does = "the switch to RUN: the CPU's configured restart (`--restart`)"
    shell = Shell(
        "start",
        "Start the CPU from STOP with its configured restart (--restart of its run; engineer).",
    )
    args: NoArgs = NoArgs()


class Mres(Command, tag="mres", frozen=True, kw_only=True):
    words = "memory reset (MRES)"
    where = "cpu"
    role = "engineer"
    does = (
        "memory reset (MRES), in STOP only: every memory area, DB and instance DB to its "
        "initial values, force jobs deleted; the program and the diagnostic buffer are kept"
    )
    shell = Shell(
        "mres",
        "Reset the CPU's memory (MRES; engineer): in STOP only, every flag, timer, counter, DB "
        "and instance DB to its initial values, force jobs deleted; the diagnostic buffer is "
        "kept.",
    )
    args: NoArgs = NoArgs()


# The union, in the order of the role table.
AnyCommand = (
    Ack
    | AckStep
    | AckMsg
    | SetMode
    | Init
    | Off
    | Halt
    | TPush
    | StepOn
    | StepOff
    | SetSteps
    | EnIl
    | EnSv
    | Force
    | Modify
    | Download
    | UndoDownload
    | Save
    | Open
    | Stop
    | Start
    | Mres
)
COMMAND_TYPES: tuple[type[Command], ...] = get_args(AnyCommand)


def op_of(kind: type[Command]) -> str:
    """The op (the tag) of a command struct."""
    return str(kind.__struct_config__.tag)


def _args_type(kind: type[Command]) -> Any:
    """The argument struct of ``kind``."""
    return next(f.type for f in msgspec.structs.fields(kind) if f.name == "args")


def _args_info(kind: type[Command]) -> mi.StructType:
    info = mi.type_info(_args_type(kind))
    assert isinstance(info, mi.StructType)
    return info


def argument_field(kind: type[Command]) -> mi.Field | None:
    """The one argument of ``kind`` (the only field of its argument struct, or its only
    required one when the others are optional: ``ack_msg``'s ``msg_id``), else None: what
    its shell command takes as the positional or the option's value."""
    fields = _args_info(kind).fields
    required = [f for f in fields if f.required]
    if len(fields) == 1:
        return fields[0]
    return required[0] if len(required) == 1 else None


OPS: tuple[str, ...] = tuple(op_of(c) for c in COMMAND_TYPES)
_BY_OP: dict[str, type[Command]] = {op_of(c): c for c in COMMAND_TYPES}


def command_type(op: str) -> type[Command] | None:
    """The struct of ``op``; None for an unknown op."""
    return _BY_OP.get(op)


def make_command(**fields: Any) -> Command:
    """The command of ``fields["op"]`` (the fields of the wire format); ``ValueError`` with
    a one-line reason for anything the bus would refuse."""
    op = fields.get("op")
    try:
        made: Command = msgspec.convert(fields, AnyCommand)
    except msgspec.ValidationError as exc:
        reason = explain(op, str(exc))
        if not reason.isprintable():  # what it quotes of the fields: one line
            reason = "".join(c if c.isprintable() else repr(c)[1:-1] for c in reason)
        raise ValueError(reason) from None
    try:
        msgspec.json.encode(made)
    except UnicodeEncodeError:  # a lone surrogate: what Python makes of bytes not UTF-8
        raise ValueError(f"op {op!r}: a text of it is not valid Unicode") from None
    return made


C = TypeVar("C", bound=Command)


def checked(command: C) -> C:
    """``command`` as the bus decodes it: a struct built in Python is not checked against its
    constraints (a step from 1, the names' patterns, the lengths), so a sender checks it
    here first; ``ValueError`` with the one-line reason the bus would give."""
    return cast(C, make_command(**msgspec.to_builtins(command)))


def args_of(kind: type[Command], given: Mapping[str, Any]) -> Args:
    """``given`` as the checked argument struct of ``kind``; ``ValueError`` with a one-line
    reason."""
    return make_command(op=op_of(kind), fb="_", args=dict(given)).args


_MISSING_ARGS = re.compile(r"^Object missing required field `args`$")
_MISSING = re.compile(r"^Object missing required field `(\w+)` - at `\$\.args`$")
_UNKNOWN = re.compile(r"^Object contains unknown field `(.+)` - at `\$\.args`$")
_ENUM = re.compile(r"^Invalid enum value .* - at `\$\.args\.(\w+)`$")
_USER = re.compile(r"^Expected `str` matching regex .* - at `\$\.user`$", re.S)
_TYPE = re.compile(
    r"^Expected `(\w+)(?: \| null)?`, got `(\w+)` - at `\$\.args\.(\w+(?:\[\d+\])?)`$"
)
_TYPE_WORDS = {
    "bool": "true or false",
    "int": "a whole number",
    "float": "a number",
    "str": "a text",
    "array": "a list",
    "object": "an object",
}
_BOUND = re.compile(
    r"^Expected `(str|int|array|object)`(?: of length)? ([<>]=) (\d+)"
    r" - at `\$\.args\.(\w+(?:\[\d+\])?)`$"
)
_BOUND_WORDS = {
    ("str", "<="): "{name} takes at most {n:,} characters",
    ("str", ">="): "{name} takes at least {n:,} characters",
    ("int", "<="): "{name} is at most {n:,}",
    ("int", ">="): "{name} is at least {n:,}",
    ("array", "<="): "{name} takes at most {n:,} items",
    ("array", ">="): "{name} takes at least {n:,} item(s)",
    ("object", "<="): "{name} takes at most {n:,} entries",
}
"""msgspec's words for a bound an argument goes past, in the vocabulary's."""


def explain(op: object, message: str) -> str:
    """A msgspec validation message of a command in the words of the vocabulary (``op
    'mode' needs argument 'mode'``, ``takes no argument``, ``mode must be one of``, the
    name rule of ``user``)."""
    if _USER.match(message):
        return (
            "invalid user name: use 1-32 of A-Z a-z 0-9 . _ - (no whitespace around it, "
            "no control character) - at `$.user`"
        )
    kind = command_type(op) if isinstance(op, str) else None
    if kind is None:
        return message
    args = _args_type(kind)
    if _MISSING_ARGS.match(message) and isinstance(args, type) and issubclass(args, Args):
        required = [f.name for f in msgspec.structs.fields(args) if f.required]
        if required:
            return f"op {op!r} needs argument {required[0]!r} - at `$.args`"
        try:  # no argument is required, yet none is not enough (force): say why
            msgspec.convert({}, args)
        except msgspec.ValidationError as exc:
            return f"{exc} - at `$.args`"
    if m := _MISSING.match(message):
        return f"op {op!r} needs argument {m[1]!r} - at `$.args`"
    if m := _UNKNOWN.match(message):
        return f"op {op!r} takes no argument {m[1]!r} - at `$.args`"
    if m := _ENUM.match(message):
        choices = {"mode": MODES, "removed": REMOVED_CHOICES}.get(m[1])
        if choices:
            return f"{m[1]} must be one of {', '.join(choices)} - at `$.args.{m[1]}`"
    if m := _TYPE.match(message):
        want, got = (_TYPE_WORDS.get(t, t) for t in (m[1], m[2]))
        return f"{m[3]} is {want}, not {got} - at `$.args.{m[3]}`"
    if (m := _BOUND.match(message)) and (words := _BOUND_WORDS.get((m[1], m[2]))):
        said = f"{m[4]} is empty" if (m[1], m[2], m[3]) == ("str", ">=", "1") else words
        return f"{said.format(name=m[4], n=int(m[3]))} - at `$.args.{m[4]}`"
    return message


def command_args(op: str, words: Iterable[str]) -> dict[str, Any]:
    """The shell's ``NAME=VALUE`` words as the arguments of ``op`` (``s7graph send``): a
    value reads as JSON where it is JSON (``3``, ``true``, ``null``), else as text.
    ``ValueError`` with a one-line reason for an unknown op or arguments its struct refuses,
    before anything is sent."""
    kind = command_type(op)
    if kind is None:
        raise ValueError(f"unknown op {op!r}; one of {', '.join(OPS)}")
    args: dict[str, Any] = {}
    for word in words:
        name, eq, value = word.partition("=")
        if not eq or not name:
            raise ValueError(f"give each argument as NAME=VALUE, not {word!r}")
        try:
            args[name] = json.loads(value)
        except (ValueError, RecursionError):  # not JSON, or nested past Python's stack
            args[name] = value
    args_of(kind, args)  # refused here, not by the CPU
    return args


def _type_text(t: mi.Type) -> str:
    """An argument's type as the documentation says it (``int 1..65535``, ``text (1..64)``)."""
    if isinstance(t, mi.UnionType):
        return " or ".join(_type_text(x) for x in t.types)
    if isinstance(t, mi.LiteralType):
        return "one of " + ", ".join(f"`{v}`" for v in sorted(map(str, t.values)))
    if isinstance(t, mi.IntType):
        if t.ge is not None and t.le is not None and t.le < 2**63 - 1:
            return f"int {t.ge}..{t.le}"
        return f"int ≥ {t.ge}" if t.ge is not None else "int"
    if isinstance(t, mi.StrType):
        if t.max_length is None:
            return "text"
        return f"text ({t.min_length or 0}..{t.max_length:,} chars)"
    if isinstance(t, mi.DictType):
        most = f"at most {t.max_length} " if t.max_length is not None else ""
        return f"{most}file name → {_type_text(t.value_type)}"
    if isinstance(t, mi.ListType):
        return f"list ({t.min_length or 0}..{t.max_length}) of {_type_text(t.item_type)}"
    names = {mi.BoolType: "bool", mi.FloatType: "number", mi.NoneType: "null"}
    return names.get(type(t), type(t).__name__)


def arguments_markdown() -> str:
    """Each op's arguments as Markdown, read from its struct (docs/bus.md; a test keeps the
    two equal): name, type, and ``?`` for one that may be left out."""
    rows = ["| op | arguments |", "|---|---|"]
    for kind in COMMAND_TYPES:
        shown = [
            f"`{f.name}`{'' if f.required else '?'}: {_type_text(f.type)}"
            for f in _args_info(kind).fields
        ]
        rows.append(f"| `{op_of(kind)}` | {'; '.join(shown) or 'none'} |")
    return "\n".join(rows) + "\n"


def shell_usage(kind: type[Command]) -> str:
    """How a shell gives ``kind``: its command (``kind.shell``) with the placeholder of its
    argument, else ``s7graph send OP`` with its arguments (``[...]``: may be left out)."""
    shell = kind.shell
    if shell is None:
        words = [f"{f.name}=…" if f.required else f"[{f.name}=…]" for f in _args_info(kind).fields]
        return " ".join(["s7graph send", op_of(kind), *words])
    field = argument_field(kind)
    placeholder = shell.metavar or (field.name.upper() if field is not None else "")
    if field is not None and isinstance(field.type, mi.ListType):
        placeholder += "..."  # one word per item
    return " ".join(w for w in ("s7graph", shell.name, shell.option, placeholder) if w)


def shell_markdown() -> str:
    """Every op as a shell gives it, as Markdown (docs/cli.md; a test keeps the two equal):
    the command, the op, the lowest role, what it does."""
    rows = ["| from a shell | op | role | what it does |", "|---|---|---|---|"]
    for kind in COMMAND_TYPES:
        usage = shell_usage(kind).replace("|", "\\|")
        rows.append(f"| `{usage}` | `{op_of(kind)}` | {kind.role} | {kind.does} |")
    return "\n".join(rows) + "\n"
