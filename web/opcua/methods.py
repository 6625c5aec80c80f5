"""The control sequencer's commands as OPC UA methods, made from the command union
(``web.commands``): one method per op, named as its struct (``AckStep``, ``SetMode``),
with one typed input argument per field of its argument struct, in the struct's order
(docs/opcua.md, "Methods").

:func:`method_specs` reads the union; :func:`arguments_of` turns a call's input variants
into the op's checked argument struct — a wrong type is ``BadTypeMismatch`` on that
argument, a value the struct refuses ``BadInvalidArgument``, never an exception;
:func:`refusal_status` turns the kind of the CPU's refusal of a command (its reason's
words for a reply without one) into the status code an OPC UA client sees;
:func:`outputs` the output arguments of an applied one.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Final

import msgspec.inspect as mi
from asyncua import ua

from s7graph.web.bus.protocol import CommandReply
from s7graph.web.commands import COMMAND_TYPES, Args, Command, args_of, op_of
from s7graph.web.opcua.model import FLOAT_VARIANTS, INT_VARIANTS
from s7graph.web.opcua.typed import ObjectIds, StatusCodes, ua_id

__all__ = [
    "KIND_STATUS",
    "ArgSpec",
    "CallError",
    "MethodSpec",
    "arguments_of",
    "method_specs",
    "output_arguments",
    "outputs",
    "refusal_status",
]

_BASE_DATA_TYPE: Final = ua_id(ObjectIds.BaseDataType)


class CallError(Exception):
    """A call refused before it reaches the bus: its status code, and per input argument
    its own (empty: none singled out)."""

    def __init__(self, status: int, arguments: Sequence[int] = ()) -> None:
        super().__init__(status)
        self.status = status
        self.arguments = list(arguments)


@dataclass(frozen=True, slots=True)
class ArgSpec:
    """One input argument: the field's name, its OPC UA data type, the field's types (to
    convert a variant), whether it may be left out (Null), and the text shown."""

    name: str
    data_type: ua.NodeId
    types: tuple[mi.Type, ...]
    required: bool
    description: str

    @property
    def nullable(self) -> bool:
        """Whether the field takes null as a value (a force job's value: unforce)."""
        return any(isinstance(t, mi.NoneType) for t in self.types)

    @property
    def array(self) -> bool:
        """Whether the field is a list (``set_steps``' steps): a one-dimensional array."""
        return any(isinstance(t, mi.ListType) for t in self.types)

    def argument(self) -> ua.Argument:
        text = self.description + ("" if self.required else " (may be Null: left out)")
        return ua.Argument(
            Name=self.name,
            DataType=self.data_type,
            ValueRank=ua.ValueRank.OneDimension if self.array else ua.ValueRank.Scalar,
            Description=ua.LocalizedText(text),
        )


@dataclass(frozen=True, slots=True)
class MethodSpec:
    """One op as a method: its struct, its browse name, where it hangs (``cpu``: on the
    CPU's object, sent for the CPU's first FB; ``fb``: on each FB's) and its arguments."""

    kind: type[Command]
    name: str
    where: str
    args: tuple[ArgSpec, ...]

    @property
    def op(self) -> str:
        return op_of(self.kind)

    @property
    def description(self) -> str:
        return f"{self.kind.does} (op {self.op}; lowest role: {self.kind.role})"

    @property
    def online(self) -> bool:
        """An engineering op: its answer carries lines, a version, removed steps, text."""
        return self.kind.where == "online"


def _data_type(types: tuple[mi.Type, ...]) -> ua.NodeId:
    real = [t for t in types if not isinstance(t, mi.NoneType)]
    if len(real) != 1:
        return _BASE_DATA_TYPE
    t = real[0]
    if isinstance(t, mi.ListType):  # an array of its items' type
        return _data_type((t.item_type,))
    if isinstance(t, mi.BoolType):
        return ua_id(ObjectIds.Boolean)
    if isinstance(t, mi.FloatType):
        return ua_id(ObjectIds.Double)
    if isinstance(t, mi.IntType):
        lo, hi = t.ge, t.le
        if lo is None or lo < 0:
            return ua_id(ObjectIds.Int64)
        if hi is not None and hi <= 0xFFFF:
            return ua_id(ObjectIds.UInt16)
        if hi is not None and hi <= 0xFFFF_FFFF:
            return ua_id(ObjectIds.UInt32)
        return ua_id(ObjectIds.UInt64)
    return ua_id(ObjectIds.String)


def _shown(t: mi.Type) -> str:
    if isinstance(t, mi.LiteralType):
        return "one of " + ", ".join(str(v) for v in t.values)
    if isinstance(t, mi.IntType):
        bounds = f" {t.ge}..{t.le}" if t.ge is not None and t.le is not None else ""
        return "integer" + bounds
    if isinstance(t, mi.ListType):
        return f"array of {t.min_length or 0}..{t.max_length}, each {_shown(t.item_type)}"
    names = {mi.BoolType: "Boolean", mi.FloatType: "number", mi.StrType: "text"}
    return names.get(type(t), "Null")


def _arg(field: mi.Field) -> ArgSpec:
    types = field.type.types if isinstance(field.type, mi.UnionType) else (field.type,)
    shown = " or ".join(_shown(t) for t in types)
    return ArgSpec(field.name, _data_type(types), types, field.required, f"{field.name}: {shown}")


def _fields(kind: type[Command]) -> tuple[mi.Field, ...]:
    args = next(f.type for f in mi.type_info(kind).fields if f.name == "args")  # type: ignore[attr-defined]
    assert isinstance(args, mi.StructType)
    return args.fields


def method_specs() -> tuple[MethodSpec, ...]:
    """Every op of the union as a method, in the union's order."""
    return tuple(
        MethodSpec(
            kind=kind,
            name=kind.__name__,
            where="cpu" if kind.where in ("cpu", "force") else "fb",
            args=tuple(_arg(f) for f in _fields(kind)),
        )
        for kind in COMMAND_TYPES
    )


def _convert(variant: ua.Variant, spec: ArgSpec) -> object:
    """The value of ``variant`` for argument ``spec``; ``TypeError`` when no type of the
    field takes it (ranges and choices are the struct's to check)."""
    value, vt = variant.Value, variant.VariantType
    if variant.is_array or isinstance(value, list):
        kind = next((t for t in spec.types if isinstance(t, mi.ListType)), None)
        if kind is None or not isinstance(value, list):
            raise TypeError(vt.name)
        item = ArgSpec(spec.name, spec.data_type, (kind.item_type,), True, "")
        most = kind.max_length if kind.max_length is not None else len(value)
        # one item past the most is enough for the struct to refuse the length
        return [_convert(ua.Variant(v, vt), item) for v in value[: most + 1]]
    for t in spec.types:
        if isinstance(t, mi.BoolType) and vt is ua.VariantType.Boolean:
            return bool(value)
        if isinstance(t, mi.IntType) and vt in INT_VARIANTS and isinstance(value, int):
            return int(value)
        if isinstance(t, mi.FloatType) and vt in FLOAT_VARIANTS and isinstance(value, float):
            return float(value)
        string = vt is ua.VariantType.String and isinstance(value, str)
        if isinstance(t, mi.StrType | mi.LiteralType) and string:
            return str(value)
    raise TypeError(vt.name)


def arguments_of(spec: MethodSpec, inputs: Sequence[Any]) -> Args:
    """The checked argument struct of a call of ``spec`` with ``inputs`` (variants);
    :class:`CallError` with the status codes when the call cannot be made.

    A Null leaves an argument out; for one that takes null (a force job's value) Null is
    that value, unless the other arguments want it left out (unforce every job)."""
    if len(inputs) > len(spec.args):
        raise CallError(StatusCodes.BadTooManyArguments)
    given: dict[str, object] = {}
    nulls: list[str] = []
    codes = [StatusCodes.Good] * len(inputs)
    for i, (variant, arg) in enumerate(zip(inputs, spec.args, strict=False)):
        if not isinstance(variant, ua.Variant):
            codes[i] = StatusCodes.BadTypeMismatch
            continue
        if variant.VariantType is ua.VariantType.Null or variant.Value is None:
            if arg.nullable:
                nulls.append(arg.name)
            continue
        try:
            given[arg.name] = _convert(variant, arg)
        except TypeError:
            codes[i] = StatusCodes.BadTypeMismatch
    if any(c != StatusCodes.Good for c in codes):
        raise CallError(StatusCodes.BadInvalidArgument, codes)
    missing = [a for a in spec.args if a.required and a.name not in given]
    if missing:
        raise CallError(StatusCodes.BadArgumentsMissing)
    tries = [given | dict.fromkeys(nulls), given] if nulls else [given]
    for attempt in tries:
        try:
            return args_of(spec.kind, attempt)
        except ValueError:
            continue
    raise CallError(StatusCodes.BadInvalidArgument)


def output_arguments(spec: MethodSpec) -> list[ua.Argument]:
    """The output arguments of ``spec``: the note of an applied command and its cycle;
    an engineering op's lines, chart version, removed steps and text besides."""

    def arg(name: str, oid: int, text: str, rank: int = ua.ValueRank.Scalar) -> ua.Argument:
        return ua.Argument(
            Name=name,
            DataType=ua_id(oid),
            ValueRank=rank,
            Description=ua.LocalizedText(text),
        )

    out = [
        arg("Reason", ObjectIds.String, "what the CPU noted of the applied command"),
        arg("Cycle", ObjectIds.UInt64, "the scan at whose boundary it was applied"),
    ]
    if spec.online:
        one = ua.ValueRank.OneDimension
        out += [
            arg("Lines", ObjectIds.String, "the change summary and diagnostics", one),
            arg("Version", ObjectIds.UInt64, "the chart version running (or previewed)"),
            arg("Removed", ObjectIds.UInt16, "active steps the change removes", one),
            arg("Text", ObjectIds.String, "the chart read (open)"),
        ]
    return out


def outputs(spec: MethodSpec, reply: CommandReply) -> list[ua.Variant]:
    """The output variants of an applied ``reply`` (as :func:`output_arguments` says)."""
    out = [
        ua.Variant(reply.reason, ua.VariantType.String),
        ua.Variant(reply.cycle or 0, ua.VariantType.UInt64),
    ]
    if spec.online:
        out += [
            ua.Variant(list(reply.lines), ua.VariantType.String),
            ua.Variant(reply.version or 0, ua.VariantType.UInt64),
            ua.Variant([min(s, 0xFFFF) for s in reply.removed], ua.VariantType.UInt16),
            ua.Variant(reply.text, ua.VariantType.String),
        ]
    return out


# Each kind of refusal (``web.bus.protocol.REFUSAL_KINDS``) in the words of OPC UA.
KIND_STATUS: Final[Mapping[str, int]] = {
    "access": StatusCodes.BadUserAccessDenied,
    "state": StatusCodes.BadInvalidState,
    "argument": StatusCodes.BadInvalidArgument,
    "not_found": StatusCodes.BadNotFound,
    "busy": StatusCodes.BadResourceUnavailable,
    "timeout": StatusCodes.BadTimeout,
    "communication": StatusCodes.BadCommunicationError,
    "acked": StatusCodes.BadConditionBranchAlreadyAcked,
    "no_event": StatusCodes.BadEventIdUnknown,
    "refused": StatusCodes.BadRequestNotAllowed,
}


# A refusal without a kind (from a CPU before ``kind``, or a site that gives none) by its
# words, one group per kind: the first pattern found in the reason wins.
_REFUSALS: Final[tuple[tuple[tuple[str, ...], int], ...]] = (
    # first: the rest of such a reason is whatever the peer that answered wrote
    (("answered with an error",), StatusCodes.BadCommunicationError),
    (
        (
            "may not",
            "not logged in",
            "invalid token",
            "token expired",
            "belongs to another user",
            "no longer exists",
            "reserved for",
        ),
        StatusCodes.BadUserAccessDenied,
    ),
    (("no answer from", "bus error", "unreadable answer"), StatusCodes.BadCommunicationError),
    (("not confirmed",), StatusCodes.BadTimeout),
    (
        ("queue full", "expired before", "conflicts with", "busy"),
        StatusCodes.BadResourceUnavailable,
    ),
    (("already acknowledged",), StatusCodes.BadConditionBranchAlreadyAcked),
    (("no message",), StatusCodes.BadEventIdUnknown),
    (("no step", "unknown fb", "unknown command", "unknown op"), StatusCodes.BadNotFound),
    (("invalid command", "must be one of", "needs argument"), StatusCodes.BadInvalidArgument),
    (
        (
            "not run",
            "in stop",
            "needs mode",
            "already active",
            "is not active",
            "waits for no",
            "no supervision fault",
            "persists",
            "not in stop",
            "not called yet",
            "needs stop",
        ),
        StatusCodes.BadInvalidState,
    ),
)


# The CPU's refusals of an argument's value — an address, a literal, a value too wide for
# its operand, a file name, a chart that does not parse —, anchored at the start: the rest
# is the client's own text, which may hold any of the words above.
_INVALID_ARGUMENT: Final = re.compile(
    r"bad (?:address|literal) |\S{1,80} does not fit the |'[^']*' is not a file name of "
    r"|the (?:chart|source) does not parse: "
)


def refusal_status(reason: str, kind: str = "") -> int:
    """The status code of a command the CPU refused with ``reason`` of ``kind``: the kind's
    (:data:`KIND_STATUS`) — access denied for a role or login, a communication error when
    the CPU did not answer, invalid state for a command the sequencer cannot take now, an
    invalid argument for a value the CPU cannot take (Part 4, "Call":
    ``BadInvalidArgument``) … Without a kind this reader knows, the reason's words decide,
    and ``BadRequestNotAllowed`` for the rest."""
    if kind in KIND_STATUS:
        return KIND_STATUS[kind]
    if "answered with an error" not in reason and _INVALID_ARGUMENT.match(reason):
        return StatusCodes.BadInvalidArgument
    text = reason.lower()
    for words, code in _REFUSALS:
        if any(w in text for w in words):
            return code
    return StatusCodes.BadRequestNotAllowed
