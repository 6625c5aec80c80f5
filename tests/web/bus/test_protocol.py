"""Wire messages: every struct round-trips; unknown fields and hostile values are refused
with a message that says where and why, never with an exception other than ProtocolError."""

from __future__ import annotations

import msgspec
import pytest

from s7graph.sequencer.text.format import format_expr
from s7graph.sequencer.text.model import (
    Binary,
    Chart,
    Const,
    Operand,
    Sequence,
    Step,
    StepAttr,
    Transition,
    Unary,
)
from s7graph.web.bus import protocol
from s7graph.web.bus.protocol import (
    MAX_MESSAGE_BYTES,
    PROTOCOL,
    AlarmEntry,
    AlarmList,
    ChartLayout,
    Command,
    CommandReply,
    Contact,
    CpuStatus,
    CycleStats,
    DiagEvent,
    LoginRequest,
    ProtocolError,
    StepDetail,
    StepStateUpdate,
    TransitionCriteria,
    condition_text,
    decode,
    encode,
)
from s7graph.web.commands import COMMAND_TYPES, Args

pytestmark = pytest.mark.timeout(30)


def chart() -> Chart:
    cond = Binary("AND", Operand("Start", quoted=True), Unary("NOT", StepAttr(3, "X")))
    return Chart(
        "FILL",
        sequences=(
            Sequence(
                1,
                "Main",
                (
                    Step(1, "Idle", initial=True),
                    Step(2, "Fill", interlock=Operand("ok"), supervision=Operand("late")),
                    Step(3, "Drain"),
                ),
                (
                    Transition(1, "Go", (1,), (2,), cond),
                    Transition(2, "", (2,), (3,), None),
                    Transition(3, "", (3,), ()),
                ),
            ),
        ),
    )


SAMPLES = [
    ChartLayout.from_chart(chart()),
    StepStateUpdate(
        seq=3,
        cycle=12,
        t_ms=120,
        mode="TAP",
        active=[2],
        disturbed=[2],
        latched=[2],
        events=[("V1", 2), ("S1", 2)],
        values={"level": 1.5, "run": True, "n": 3, "name": "x", "none": None},
    ),
    Command(op="ack", fb="FILL", user="alice"),
    Command(op="mode", fb="FILL", args={"mode": "MAN"}),
    Command(op="step_on", fb="FILL", args={"step": 3}),
    CommandReply(applied=False, reason="no error to acknowledge", op="ack", fb="FILL", cycle=9),
    CpuStatus(cpu="cpu1", state="STOP", cycle=4, t_ms=40, fbs=["FILL"]),
    Command(op="ack_msg", fb="FILL", user="bob", args={"msg_id": "FILL/DB1/S2/SV"}),
    Command(op="ack_msg", fb="FILL", args={"msg_id": 17}),
    StepStateUpdate(
        cycle=5,
        t_ms=50,
        mode="AUTO",
        active=[2],
        details=[
            StepDetail(
                number=2,
                t_ms=1200,
                u_ms=700,
                interlock_ok=False,
                interlock_error=True,
                interlock=[Contact(text="ok", ok=False)],
                transitions=[
                    TransitionCriteria(
                        number=2,
                        name="Full",
                        holds=False,
                        contacts=[Contact(text='"A"', ok=True), Contact(text='NOT "B"', ok=False)],
                    )
                ],
            )
        ],
    ),
    AlarmList(
        seq=2,
        cycle=9,
        entries=[
            AlarmEntry(
                msg_id="FILL/DB1/S2/SV",
                event_id=1,
                state="outgoing",
                text="<b>late</b>",
                source="S7-Graph",
                came_ms=1_700_000_000_000,
                went_ms=1_700_000_000_500,
                acked=True,
                ack_user="bob",
                ack_ms=1_700_000_000_900,
                fb="FILL",
                db=1,
                step=2,
                kind="SV",
            ),
            AlarmEntry(msg_id=17, event_id=2, state="incoming", came_ms=5),
        ],
    ),
]


@pytest.mark.parametrize("message", SAMPLES, ids=lambda m: type(m).__name__)
def test_every_struct_round_trips_through_json(message: object) -> None:
    assert decode(encode(message), type(message)) == message  # type: ignore[arg-type]


def test_chart_layout_describes_steps_transitions_and_sequences() -> None:
    layout = ChartLayout.from_chart(chart())
    assert layout.fb == "FILL"
    idle, fill, _ = layout.steps
    assert idle.initial and not idle.interlock
    assert fill.interlock and fill.supervision
    go, _, stop = layout.transitions
    assert (go.sources, go.targets, go.condition) == ([1], [2], '"Start" AND NOT S3.X')
    assert stop.targets == []
    assert layout.sequences[0].steps == [1, 2, 3]


def test_condition_text_keeps_precedence_with_parentheses() -> None:
    expr = Binary("AND", Binary("OR", Operand("a"), Operand("b")), Const(5, "INT", "5"))
    assert condition_text(expr) == "(a OR b) AND 5"
    assert condition_text(None) == ""


def test_condition_text_is_the_chart_writers_printer_with_flat_chains() -> None:
    """One precedence table (``sequencer.text.format``): a chain reads without inner
    parentheses, arithmetic keeps the grammar's precedence, otherwise the writer's text."""
    a, b, c = Operand("a"), Operand("b"), Operand("c")
    chain = Binary("AND", a, Binary("AND", b, c))
    assert condition_text(chain) == "a AND b AND c"
    assert format_expr(chain) == "a AND (b AND c)"  # the writer keeps the tree
    assert condition_text(Binary("*", Binary("+", a, b), c)) == "(a + b) * c"
    assert condition_text(Binary("+", a, Binary("*", b, c))) == "a + b * c"
    mixed = Binary("OR", Unary("NOT", Binary("AND", a, b)), Binary("=", c, Const(5, "INT", "5")))
    assert condition_text(mixed) == format_expr(mixed) == "NOT (a AND b) OR c = 5"
    assert condition_text(Const(7, "INT", "")) == "7"


@pytest.mark.parametrize(
    ("payload", "reason"),
    [
        (b'{"op":"ack","fb":"FILL","sudo":true}', "unknown field `sudo`"),
        (b'{"op":"format_disk","fb":"FILL"}', "$.op"),
        (b'{"op":"ack","fb":"s7graph/**"}', "$.fb"),
        (b'{"op":"ack","fb":"FILL","user":"' + b"x" * 100 + b'"}', "$.user"),
        (b'{"op":"mode","fb":"FILL","args":{"mode":"TURBO"}}', "$.args.mode"),
        (b'{"op":"mode","fb":"FILL"}', "needs argument 'mode'"),
        (b'{"op":"ack","fb":"FILL","args":{"step":1}}', "takes no argument 'step'"),
        (b'{"op":"step_on","fb":"FILL","args":{"step":-1}}', "$.args.step"),
        (b'{"op":"step_on","fb":"FILL","args":{"step":true}}', "$.args.step"),
        (b'{"op":"step_on","fb":"FILL","args":{"step":"3"}}', "$.args.step"),
        (b'{"op":"step_on","fb":"FILL","args":{"step":1e999}}', "out of range"),
        (b'{"op":"ack","fb":"FILL","args":{"a":[1,[2]]}}', "$.args"),
        (b'{"op":"ack_msg","fb":"FILL"}', "needs argument 'msg_id'"),
        (b'{"op":"ack_msg","fb":"FILL","args":{"msg_id":true}}', "$.args.msg_id"),
        (b'{"op":"ack_msg","fb":"FILL","args":{"msg_id":0}}', "$.args.msg_id"),
        (b'{"op":"ack_msg","fb":"FILL","args":{"msg_id":""}}', "$.args.msg_id"),
        (b'{"op":"ack_msg","fb":"FILL","args":{"msg_id":"' + b"m" * 129 + b'"}}', "$.args.msg_id"),
        (b'{"op":"ack_msg","fb":"FILL","args":{"msg_id":1,"step":2}}', "no argument 'step'"),
        (b'["ack","FILL"]', "Expected `object`"),
        (b"[" * 50_000, "Expected `object`"),
        (b"\xff\xfe\x00", "malformed JSON"),
        (b"", "malformed JSON"),
        (b" " * (MAX_MESSAGE_BYTES + 1), "too large"),
    ],
)
def test_hostile_command_is_refused_with_a_clear_reason(payload: bytes, reason: str) -> None:
    with pytest.raises(ProtocolError) as err:
        decode(payload, Command)
    assert reason in str(err.value)


@pytest.mark.parametrize(
    "payload",
    [
        b'{"cycle":-1,"t_ms":0,"mode":"AUTO","active":[1]}',
        b'{"cycle":1,"t_ms":0,"mode":"FAST","active":[1]}',
        b'{"cycle":1,"t_ms":0,"mode":"AUTO","active":[70000]}',
        b'{"cycle":1,"t_ms":0,"mode":"AUTO","active":[1],"events":[["X9",1]]}',
        b'{"cycle":1,"t_ms":0,"mode":"AUTO","active":[1],"values":{"a":{"b":1}}}',
    ],
)
def test_hostile_state_update_is_refused(payload: bytes) -> None:
    with pytest.raises(ProtocolError):
        decode(payload, StepStateUpdate)


def test_building_a_bad_command_in_python_fails_too() -> None:
    with pytest.raises(ValueError, match="mode must be one of"):
        Command(op="mode", fb="FILL", args={"mode": "FAST"})


def test_unchanged_scan_is_not_a_change_but_an_event_is() -> None:
    a = StepStateUpdate(cycle=1, t_ms=10, mode="AUTO", active=[1])
    b = StepStateUpdate(cycle=2, t_ms=20, mode="AUTO", active=[1])
    assert a.changed_from(None)
    assert not b.changed_from(a)
    assert StepStateUpdate(
        cycle=3, t_ms=30, mode="AUTO", active=[1], events=[("S1", 1)]
    ).changed_from(b)
    assert StepStateUpdate(cycle=3, t_ms=30, mode="MAN", active=[1]).changed_from(b)


def test_changed_criteria_of_an_active_step_are_a_change() -> None:
    def update(ok: bool) -> StepStateUpdate:
        crit = TransitionCriteria(number=1, holds=ok, contacts=[Contact(text="x", ok=ok)])
        detail = StepDetail(number=1, transitions=[crit])
        return StepStateUpdate(cycle=1, t_ms=0, mode="AUTO", active=[1], details=[detail])

    assert update(True).changed_from(update(False))
    assert not update(True).changed_from(update(True))


def test_pending_alarms_are_those_waiting_for_an_acknowledgement() -> None:
    entries = [
        AlarmEntry(msg_id=1, event_id=1, state="incoming", came_ms=0),
        AlarmEntry(msg_id=2, event_id=2, state="incoming", came_ms=0, acked=True),
        AlarmEntry(msg_id=3, event_id=3, state="incoming", came_ms=0, ack_required=False),
    ]
    assert [e.msg_id for e in AlarmList(entries=entries).pending()] == [1]
    with pytest.raises(ProtocolError, match="state"):
        decode(b'{"entries":[{"msg_id":1,"event_id":1,"state":"gone","came_ms":0}]}', AlarmList)


# ---------------------------------------------------------------- how messages evolve


class PreviousCpuStatus(msgspec.Struct, frozen=True, kw_only=True):
    """``status`` as a reader built before ``stop``, ``cause`` and ``v`` knew it."""

    cpu: str
    state: str = "RUN"
    cycle: int = 0
    t_ms: int = 0
    fbs: list[str] = []
    stats: CycleStats | None = None
    login: str = "demo"
    forces: int = 0
    reason: str = ""


class StrictPreviousCpuStatus(PreviousCpuStatus, frozen=True, forbid_unknown_fields=True):
    """The same reader from before readers ignored unknown fields."""


def _stopped() -> CpuStatus:
    stop = DiagEvent(number=7, event_id=0x4562, text="STOP caused by a programming error")
    cause = DiagEvent(number=6, event_id=0x25FF, info="OB1: ZeroDivisionError")
    return CpuStatus(
        cpu="cpu1",
        state="STOP",
        cycle=9,
        reason="OB1: ZeroDivisionError",
        stop=stop,
        cause=cause,
        stats=CycleStats(last_ms=1.5),
    )


def test_a_reader_of_the_previous_status_reads_a_new_one_with_stop_and_cause() -> None:
    new = _stopped()
    data = encode(msgspec.structs.replace(new, v=PROTOCOL))
    old = decode(data, PreviousCpuStatus)
    assert (old.cpu, old.state, old.cycle, old.reason) == ("cpu1", "STOP", 9, new.reason)
    assert old.stats == new.stats
    # and a field a later CPU adds is ignored the same way
    later = data[:-1] + b',"lamp":"red","leds":{"SF":true}}'
    assert decode(later, CpuStatus) == new
    assert decode(later, PreviousCpuStatus) == old


def test_a_status_leaves_out_its_defaults_so_strict_old_readers_read_it_while_it_runs() -> None:
    running = CpuStatus(cpu="cpu1", cycle=5, fbs=["FILL"], stats=CycleStats(last_ms=1.0))
    data = encode(running)
    assert b'"stop"' not in data and b'"v"' not in data and b'"state"' not in data
    assert decode(data, StrictPreviousCpuStatus).fbs == ["FILL"]
    assert decode(data, CpuStatus) == running and decode(data, CpuStatus).v == PROTOCOL
    with pytest.raises(ProtocolError, match="unknown field `stop`"):
        decode(encode(_stopped()), StrictPreviousCpuStatus)  # the one it cannot read


def _messages() -> dict[str, type[msgspec.Struct]]:
    return {
        name: kind
        for name, kind in vars(protocol).items()
        if isinstance(kind, type)
        and issubclass(kind, msgspec.Struct)
        and kind.__module__ == protocol.__name__
        and not name.startswith("_")
    }


TAKEN_BY_THE_CPU = {"LoginRequest", "WatchRequest"}


def test_what_the_cpu_takes_is_strict_and_what_it_says_ignores_unknown_fields() -> None:
    for name, kind in _messages().items():
        strict = kind.__struct_config__.forbid_unknown_fields
        assert strict == (name in TAKEN_BY_THE_CPU), name
    args: list[type[msgspec.Struct]] = [Args]
    for kind in args:  # every argument struct, however deep
        args.extend(kind.__subclasses__())
    for kind in (*COMMAND_TYPES, *args):
        assert kind.__struct_config__.forbid_unknown_fields, kind
    with pytest.raises(ProtocolError, match="unknown field `evil`"):
        decode(b'{"op":"login","evil":1}', LoginRequest)


# The required fields of each message the CPU says: a field added later has a default, so
# a reader never needs what an older CPU does not send; this list only ever shrinks.
REQUIRED = {
    "ActionInfo": ("qualifier", "operand"),
    "AlarmEntry": ("msg_id", "event_id", "state", "came_ms"),
    "AlarmEvent": ("id", "t_ms", "msg_id", "state"),
    "AuditEntry": ("id", "t_ms", "user", "op", "outcome"),
    "BlockInterface": ("kind", "number"),
    "BlockPin": ("name", "direction", "type"),
    "BlockSource": ("label",),
    "ChartLayout": ("fb", "steps", "transitions", "sequences"),
    "ChartPart": ("fb",),
    "ChartSource": ("fb", "text"),
    "CommandReply": ("applied",),
    "Contact": ("text", "ok"),
    "CpuStatus": ("cpu",),
    "DiagEvent": ("number", "event_id"),
    "ForceEntry": ("address", "value"),
    "LoginReply": ("ok",),
    "OperandInfo": ("name", "type"),
    "ProjectFile": ("name", "format"),
    "ScanDeltas": ("cycle", "t_ms"),
    "SequenceInfo": ("number", "steps", "transitions"),
    "StepDetail": ("number",),
    "StepInfo": ("number",),
    "StepStateUpdate": ("cycle", "t_ms", "mode", "active"),
    "SyncStepInfo": ("number",),
    "TransitionCriteria": ("number", "holds"),
    "TransitionInfo": ("number", "sources", "targets"),
    "WatchValue": ("address",),
}


def test_no_message_the_cpu_says_gains_a_required_field() -> None:
    for name, kind in _messages().items():
        if name in TAKEN_BY_THE_CPU:
            continue
        fields = msgspec.inspect.type_info(kind).fields  # type: ignore[attr-defined]
        required = tuple(f.name for f in fields if f.required)
        assert set(required) <= set(REQUIRED.get(name, ())), (name, required)


@pytest.mark.parametrize(
    ("data", "reason"),
    [
        (b'{"op": ' + b"[" * 5000 + b"]" * 5000 + b"}", "nested too deeply"),
        ('{"op": "ack", "fb": "\ud800"}', "text that is not valid UTF-8"),
    ],
)
def test_a_message_python_cannot_read_is_refused_in_words(data: bytes | str, reason: str) -> None:
    """Deep nesting and text that is no UTF-8: what is wrong, in words — never Python's
    ``RecursionError`` or ``UnicodeEncodeError``."""
    with pytest.raises(ProtocolError) as refused:
        decode(data, Command)
    said = str(refused.value)
    assert said.startswith("invalid Command: ") and reason in said and "Error" not in said
