"""The ops of the command union as OPC UA methods (``web.opcua.methods``): one per op,
named as its struct, one typed argument per field of its argument struct; input variants
become the op's checked arguments or a status code; the CPU's refusals become status
codes an OPC UA client can act on."""

from __future__ import annotations

import msgspec
import pytest
from asyncua import ua

from s7graph.web.bus.protocol import (
    REFUSAL_KINDS,
    CommandReply,
    Refusal,
    SyncReport,
    decode,
    encode,
    refusal_reply,
)
from s7graph.web.commands import COMMAND_TYPES, ForceArgs, ModeArgs, StepArgs, StepsArgs
from s7graph.web.opcua.methods import (
    KIND_STATUS,
    CallError,
    arguments_of,
    method_specs,
    output_arguments,
    outputs,
    refusal_status,
)
from s7graph.web.opcua.sync import sync_result

SPECS = {s.name: s for s in method_specs()}


def test_every_op_of_the_union_is_one_method_with_its_structs_fields() -> None:
    assert [s.kind for s in method_specs()] == list(COMMAND_TYPES)
    for spec in method_specs():
        args = next(f.type for f in msgspec.structs.fields(spec.kind) if f.name == "args")
        assert [a.name for a in spec.args] == list(args.__struct_fields__), spec.name
        assert spec.where == ("cpu" if spec.kind.where in ("cpu", "force") else "fb")
        assert spec.kind.role in spec.description
    types = {a.name: a.data_type for s in method_specs() for a in s.args}
    assert types["step"] == ua.NodeId(ua.ObjectIds.UInt16)
    assert types["on"] == ua.NodeId(ua.ObjectIds.Boolean)
    assert types["mode"] == ua.NodeId(ua.ObjectIds.String)
    assert types["msg_id"] == ua.NodeId(ua.ObjectIds.BaseDataType)  # a number or a text
    assert types["base"] == ua.NodeId(ua.ObjectIds.UInt64)
    steps = SPECS["SetSteps"].args[0].argument()  # an array of step numbers
    assert (steps.DataType, steps.ValueRank) == (ua.NodeId(ua.ObjectIds.UInt16), 1)
    assert SPECS["AckStep"].args[0].argument().ValueRank == ua.ValueRank.Scalar


def test_input_variants_become_the_checked_arguments() -> None:
    assert arguments_of(SPECS["AckStep"], [ua.Variant(3, ua.VariantType.UInt16)]) == StepArgs(
        step=3
    )
    assert arguments_of(SPECS["AckStep"], [ua.Variant(3)]) == StepArgs(step=3)  # any integer
    assert arguments_of(SPECS["SetMode"], [ua.Variant("TAP")]) == ModeArgs(mode="TAP")
    force = SPECS["Force"]
    assert arguments_of(force, [ua.Variant("I0.3"), ua.Variant(True)]) == ForceArgs(
        address="I0.3", value=True
    )
    assert arguments_of(force, [ua.Variant("I0.3"), ua.Variant(None)]) == ForceArgs(
        address="I0.3",
        value=None,  # Null for a value that takes null: unforce
    )
    steps = ua.Variant([3, 12], ua.VariantType.UInt16)
    assert arguments_of(SPECS["SetSteps"], [steps]) == StepsArgs(steps=[3, 12])
    everything = [ua.Variant(None), ua.Variant(None), ua.Variant(True)]
    assert arguments_of(force, everything) == ForceArgs(all=True)  # Null left out


@pytest.mark.parametrize(
    ("name", "inputs", "status", "per_argument"),
    [
        ("AckStep", [ua.Variant("3")], "BadInvalidArgument", ["BadTypeMismatch"]),
        ("AckStep", [ua.Variant(0)], "BadInvalidArgument", []),
        ("AckStep", [ua.Variant(70000)], "BadInvalidArgument", []),
        ("AckStep", [], "BadArgumentsMissing", []),
        ("AckStep", [ua.Variant(1), ua.Variant(2)], "BadTooManyArguments", []),
        ("AckStep", [ua.Variant([1, 2])], "BadInvalidArgument", ["BadTypeMismatch"]),
        ("AckStep", ["not a variant"], "BadInvalidArgument", ["BadTypeMismatch"]),
        ("SetMode", [ua.Variant("FAST")], "BadInvalidArgument", []),
        ("SetSteps", [ua.Variant(3)], "BadInvalidArgument", ["BadTypeMismatch"]),
        ("SetSteps", [ua.Variant(["3"])], "BadInvalidArgument", ["BadTypeMismatch"]),
        ("SetSteps", [ua.Variant([], ua.VariantType.UInt16)], "BadInvalidArgument", []),
        ("SetSteps", [ua.Variant([0], ua.VariantType.UInt16)], "BadInvalidArgument", []),
        ("SetSteps", [ua.Variant(list(range(1, 66)))], "BadInvalidArgument", []),
        ("SetSteps", [ua.Variant([1] * 1_000_000)], "BadInvalidArgument", []),
        ("Halt", [ua.Variant(1)], "BadInvalidArgument", ["BadTypeMismatch"]),
        ("Save", [ua.Variant("../x.s7g"), ua.Variant("x" * 2_000_000)], "BadInvalidArgument", []),
        (
            "Force",
            [ua.Variant("I0.3"), ua.Variant(True), ua.Variant(True)],
            "BadInvalidArgument",
            [],
        ),
        # JSON has no inf or NaN: carried as null, a force of inf would be an unforce
        ("Force", [ua.Variant("MD10"), ua.Variant(float("inf"))], "BadInvalidArgument", []),
        ("Force", [ua.Variant("MD10"), ua.Variant(float("nan"))], "BadInvalidArgument", []),
        ("Modify", [ua.Variant("MD10"), ua.Variant(float("-inf"))], "BadInvalidArgument", []),
        ("Modify", [ua.Variant("M\udcff"), ua.Variant(1)], "BadInvalidArgument", []),
    ],
)
def test_wrong_inputs_are_a_status_code(
    name: str, inputs: list[object], status: str, per_argument: list[str]
) -> None:
    with pytest.raises(CallError) as refused:
        arguments_of(SPECS[name], inputs)
    assert refused.value.status == getattr(ua.StatusCodes, status)
    shown = [ua.StatusCode(c).name for c in refused.value.arguments if c != ua.StatusCodes.Good]
    assert shown == per_argument


@pytest.mark.parametrize(
    ("reason", "status"),
    [
        ("role viewer may not init (needs operator)", "BadUserAccessDenied"),
        ("token expired: log in again", "BadUserAccessDenied"),
        ("no answer from CPU 'cpu1' within 5 s", "BadCommunicationError"),
        ("no answer from CPU 'cpu1': the bus ended the request after", "BadCommunicationError"),
        ("s7graph/cpu1/cmd: the CPU answered with an error: you may not", "BadCommunicationError"),
        ("s7graph/cpu1/cmd: unreadable answer: malformed JSON", "BadCommunicationError"),
        ("step_on needs mode MAN (S7-GRAPH Control Sequencer)", "BadInvalidState"),
        ("the CPU is in STOP, not RUN", "BadInvalidState"),
        ("the CPU is in RUN: a memory reset needs STOP (stop it first)", "BadInvalidState"),
        ("no step S9 in Seq_mix", "BadNotFound"),
        ("nothing to change: S1 already active, no other step active in", "BadInvalidState"),
        ("message 'x' is already acknowledged by olga", "BadConditionBranchAlreadyAcked"),
        ("mode conflicts with mode MAN, queued for the same scan; retry", "BadResourceUnavailable"),
        ("not confirmed: applied in cycle 7, but the state file failed", "BadTimeout"),
        ("bad address 'XYZ': not an S7 address or a symbol", "BadInvalidArgument"),
        ("70000 does not fit the word MW20 (0..65535, or -32768..32767)", "BadInvalidArgument"),
        ("'../x' is not a file name of the project directory (a bare name", "BadInvalidArgument"),
        ("the chart does not parse: unexpected 'garbage'", "BadInvalidArgument"),
        # the client's own text in a reason decides nothing
        ("no message 'bad address x' in the message list", "BadEventIdUnknown"),
        (
            "s7graph/cpu1/cmd: the CPU answered with an error: bad address 'x'",
            "BadCommunicationError",
        ),
        ("something nobody foresaw", "BadRequestNotAllowed"),
    ],
)
def test_a_refusal_without_a_kind_is_a_status_code_by_its_words(reason: str, status: str) -> None:
    assert refusal_status(reason) == getattr(ua.StatusCodes, status)


def test_every_kind_of_refusal_has_its_status_code() -> None:
    assert set(KIND_STATUS) == set(REFUSAL_KINDS)
    assert len(set(KIND_STATUS.values())) == len(KIND_STATUS)  # no two kinds alike


@pytest.mark.parametrize(
    ("kind", "reason", "status"),
    [
        # the words of another kind in the reason (the client's own text) decide nothing
        (
            "no_event",
            "no message 'may not, not logged in' in the message list",
            "BadEventIdUnknown",
        ),
        ("state", "S3 is not active; no answer from CPU 'x'; bad address 'y'", "BadInvalidState"),
        ("access", "role viewer may not open (needs engineer): no step S9", "BadUserAccessDenied"),
        ("not_found", "no file 'busy, already acknowledged' in the directory", "BadNotFound"),
        (
            "communication",
            "s7graph/cpu1/cmd: the CPU answered with an error: busy",
            "BadCommunicationError",
        ),
        ("refused", "this CPU has no RUN/STOP switch", "BadRequestNotAllowed"),
        # a kind this reader does not know (a later CPU's): the words decide
        ("a later kind", "no step S9 in Seq_mix", "BadNotFound"),
    ],
)
def test_the_kind_of_a_refusal_decides_its_status_code(kind: str, reason: str, status: str) -> None:
    assert refusal_status(reason, kind) == getattr(ua.StatusCodes, status)


def test_a_reply_without_a_kind_still_reads_and_one_with_it_reads_anywhere() -> None:
    """A reply of a CPU from before ``kind``: read, its kind "" (the words decide); a
    reply with ``kind`` read by a reader from before it (which ignores the field)."""
    old = b'{"applied":false,"reason":"no step S9 in Seq_mix","op":"step_on","fb":"Seq_mix"}'
    reply = decode(old, CommandReply)
    assert (reply.kind, refusal_status(reply.reason, reply.kind)) == (
        "",
        ua.StatusCodes.BadNotFound,
    )

    class PreviousCommandReply(msgspec.Struct, kw_only=True):
        applied: bool
        reason: str = ""
        op: str = ""
        fb: str = ""

    new = encode(refusal_reply(Refusal("state", "S3 is not active"), op="step_off"))
    assert decode(new, CommandReply).kind == "state"
    assert decode(new, PreviousCommandReply).reason == "S3 is not active"
    with pytest.raises(ValueError, match="refusal kind 'nope': not one of access, state"):
        Refusal("nope", "x")


@pytest.mark.parametrize(
    ("report", "status"),
    [
        (SyncReport(fb="Seq_busy", error="Seq_busy: not called yet"), "BadInvalidState"),
        (
            SyncReport(error="busy: 16 synchronization queries are waiting"),
            "BadResourceUnavailable",
        ),
        (SyncReport(error="no answer from CPU 'busy' within 5 s"), "BadCommunicationError"),
    ],
)
def test_a_synchronization_refused_is_a_status_code_whatever_the_fb_is_named(
    report: SyncReport, status: str
) -> None:
    got, out = sync_result(report)
    assert ua.StatusCode(got).name == status and out == []


def test_an_applied_commands_outputs() -> None:
    reply = CommandReply(applied=True, reason="S3 stays latched", cycle=42)
    assert [v.Value for v in outputs(SPECS["Ack"], reply)] == ["S3 stays latched", 42]
    download = SPECS["Download"]
    names = [a.Name for a in output_arguments(download)]
    assert names == ["Reason", "Cycle", "Lines", "Version", "Removed", "Text"]
    reply = CommandReply(applied=True, cycle=5, lines=["T2: condition"], version=2, removed=[3])
    values = [v.Value for v in outputs(download, reply)]
    assert values == ["", 5, ["T2: condition"], 2, [3], ""]
