"""The command vocabulary (web.commands): one struct per op, and everything that names an
op — the role table, the pin maps, the protocol, the CLI, the page — reads it or is checked
against it here. Hostile commands are refused with a one-line ProtocolError."""

from __future__ import annotations

import ast
import json
from pathlib import Path
from typing import Any

import msgspec
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from s7graph.web.access.roles import COMMANDS, ROLES, lowest_role
from s7graph.web.bus.live import LEVEL_PINS, MODE_PINS, OP_PINS
from s7graph.web.bus.protocol import OPS, Command, ProtocolError, decode, encode
from s7graph.web.commands import (
    COMMAND_TYPES,
    Ack,
    AckMsg,
    AckStep,
    Args,
    DownloadArgs,
    Force,
    ForceArgs,
    Halt,
    Init,
    MessageArgs,
    ModeArgs,
    Off,
    OnArgs,
    SetMode,
    SetSteps,
    Start,
    StepArgs,
    StepOff,
    StepOn,
    StepsArgs,
    Stop,
    TPush,
    argument_field,
    checked,
    command_args,
    command_type,
    make_command,
    op_of,
    shell_markdown,
)
from tests.paths import ROOT


def test_every_op_is_one_struct_with_a_role_and_a_row() -> None:
    assert tuple(op_of(c) for c in COMMAND_TYPES) == OPS
    assert len(set(OPS)) == len(OPS) == len(COMMANDS)
    for kind in COMMAND_TYPES:
        assert issubclass(kind, Command) and kind.role in ROLES and kind.role != "viewer"
        assert lowest_role(op_of(kind)) == kind.role
        assert command_type(op_of(kind)) is kind
        args = next(f.type for f in msgspec.structs.fields(kind) if f.name == "args")
        assert isinstance(args, type) and issubclass(args, Args), op_of(kind)
    assert command_type("format_disk") is None


def test_the_pin_maps_are_the_vocabularys() -> None:
    assert OP_PINS == {
        "ack": "ACK_EF",
        "ack_step": "ACK_S",
        "init": "INIT_SQ",
        "off": "OFF_SQ",
        "step_on": "S_ON",
        "step_off": "S_OFF",
        "t_push": "T_PUSH",
    }
    assert LEVEL_PINS == {
        "halt": ("HALT_SQ", True),
        "en_il": ("EN_IL", False),
        "en_sv": ("EN_SV", False),
    }
    assert set(MODE_PINS) == {"AUTO", "MAN", "TAP", "TOP"}
    assert {c.op: c.pin for c in COMMANDS if c.pin} == {
        **OP_PINS,
        **{op: pin for op, (pin, _) in LEVEL_PINS.items()},
        "mode": "SW_AUTO/MAN/TAP/TOP",
    }


# What clients sent before the union (Command(op, args: dict)): each decodes to its op's
# struct and encodes to the same bytes.
WIRE = [
    b'{"op":"ack","fb":"FILL","user":"alice","token":"","origin":"","args":{}}',
    b'{"op":"ack_step","fb":"FILL","user":"","token":"","origin":"","args":{"step":2}}',
    b'{"op":"ack_msg","fb":"FILL","user":"","token":"","origin":"","args":{"msg_id":"a/b"}}',
    b'{"op":"mode","fb":"FILL","user":"","token":"t-1","origin":"shell","args":{"mode":"MAN"}}',
    b'{"op":"halt","fb":"FILL","user":"","token":"","origin":"","args":{"on":false}}',
    b'{"op":"force","fb":"FILL","user":"","token":"","origin":"","args":{"address":"I0.3","value":null}}',
    b'{"op":"force","fb":"FILL","user":"","token":"","origin":"","args":{"address":"MW10","value":-5}}',
    b'{"op":"force","fb":"FILL","user":"","token":"","origin":"","args":{"all":true}}',
    b'{"op":"download","fb":"FILL","user":"","token":"","origin":"","args":{"source":"x","base":3,"removed":"keep","preview":true}}',
    b'{"op":"undo_download","fb":"FILL","user":"","token":"","origin":"","args":{}}',
    b'{"op":"save","fb":"FILL","user":"","token":"","origin":"","args":{"file":"a.s7g","source":""}}',
    b'{"op":"open","fb":"FILL","user":"","token":"","origin":"","args":{"file":"a.xml"}}',
    b'{"op":"stop","fb":"FILL","user":"","token":"","origin":"","args":{}}',
]


@pytest.mark.parametrize("data", WIRE)
def test_the_wire_format_is_the_one_clients_send(data: bytes) -> None:
    command = decode(data, Command)
    raw = json.loads(data)
    assert type(command) is command_type(raw["op"]) and command.op == raw["op"]
    assert encode(command) == data
    assert dict(command.args) == raw["args"]
    assert Command(**raw) == command  # the former constructor builds the same struct


def test_a_command_built_the_old_way_is_the_typed_struct() -> None:
    c = Command(op="step_on", fb="FILL", user="bob", args={"step": 3})
    assert isinstance(c, StepOn) and c.step == 3 and c.args.step == 3 and c.mode is None
    d = Command(op="download", fb="FILL", args={"source": "x", "preview": True})
    assert isinstance(d.args, DownloadArgs) and "base" not in d.args and d.args.preview
    assert msgspec.structs.replace(c, token="x").op == "step_on"
    assert Command(op="ack", fb="FILL") == Command(op="ack", fb="FILL", args={})
    with pytest.raises(ValueError, match="takes no argument 'step'"):
        Command(op="ack", fb="FILL", args={"step": 1})
    with pytest.raises(ValueError, match="removed must be one of keep, init"):
        Command(op="undo_download", fb="FILL", args={"removed": "all"})
    with pytest.raises(ValueError, match=r"alone - at `\$\.args`"):
        Command(op="force", fb="FILL", args={"all": True, "address": "I0.1"})
    with pytest.raises(ValueError, match="alone"):  # a struct built directly checks too
        Force(fb="FILL", args=ForceArgs(all=True, address="I0.1"))


@pytest.mark.parametrize(
    ("payload", "reason"),
    [
        (b'{"op":"force","fb":"F","args":{"address":"I0.1"}}', "force takes"),
        (b'{"op":"force","fb":"F","args":{"all":false}}', "alone"),
        (b'{"op":"force","fb":"F"}', 'force takes {"address"'),
        (b'{"op":"force","fb":"F","args":{"address":"","value":1}}', "$.args.address"),
        (b'{"op":"force","fb":"F","args":{"address":"I0.1","value":[1]}}', "$.args.value"),
        (b'{"op":"download","fb":"F","args":{"source":"x","base":-1}}', "$.args.base"),
        (b'{"op":"download","fb":"F","args":{"source":"x","preview":1}}', "$.args.preview"),
        (b'{"op":"download","fb":"F","args":{"source":"x","removed":"zap"}}', "must be one of"),
        (b'{"op":"undo_download","fb":"F","args":{"source":"x"}}', "no argument 'source'"),
        (b'{"op":"save","fb":"F","args":{"file":"a.s7g"}}', "needs argument 'source'"),
        (b'{"op":"open","fb":"F","args":{"file":""}}', "$.args.file"),
        (b'{"op":"halt","fb":"F","args":{"on":"yes"}}', "$.args.on"),
        (b'{"op":"halt","fb":"F"}', "needs argument 'on'"),
        (b'{"op":7,"fb":"F"}', "$.op"),
        (b'{"fb":"F"}', "op"),
        (b'{"op":"ack","fb":"F","args":[]}', "$.args"),
    ],
)
def test_hostile_arguments_are_refused_in_one_line(payload: bytes, reason: str) -> None:
    with pytest.raises(ProtocolError) as err:
        decode(payload, Command)
    assert reason in str(err.value) and "\n" not in str(err.value)


_JSON = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=8),
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=8), inner),
    max_leaves=8,
)
_KEYS = st.sampled_from(
    [
        "step",
        "mode",
        "on",
        "msg_id",
        "address",
        "value",
        "all",
        "source",
        "base",
        "removed",
        "preview",
        "file",
        "x",
    ]
)


@settings(max_examples=300, deadline=None)
@given(
    op=st.sampled_from([*OPS, "nope"]) | st.text(max_size=8),
    args=st.dictionaries(_KEYS, _JSON, max_size=4) | _JSON,
    extra=st.dictionaries(st.sampled_from(["user", "token", "sudo", "fb"]), _JSON, max_size=2),
)
def test_any_message_decodes_or_is_refused_with_a_protocol_error(
    op: str, args: object, extra: dict[str, object]
) -> None:
    data = json.dumps({"op": op, "fb": "F", "args": args, **extra}).encode()
    try:
        command = decode(data, Command)
    except ProtocolError as exc:
        assert "\n" not in str(exc)
        return
    assert command.op == op and encode(command) is not None


# Ops without a shell command of their own (``s7graph send`` sends them): the levels (the
# page's Halt, a bus client), and the engineering ops an editor sends (the shell has
# ``download``, which previews first).
NOT_IN_THE_SHELL = {"halt", "en_il", "en_sv", "undo_download", "save", "open"}


def _structs_built(path: Path) -> set[str]:
    """The ops whose struct ``path`` builds by name (``StepOn(fb=...)``)."""
    names = {kind.__name__: op_of(kind) for kind in COMMAND_TYPES}
    return {
        names[node.func.id]
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8")))
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in names
    }


def _shell_commands() -> dict[str, Any]:
    """The click commands of ``s7graph``, by name."""
    from typer.main import get_command

    from s7graph.web.cli.root import app

    group: Any = get_command(app)  # typer's group (its own click)
    return dict(group.commands)


def test_the_shell_sends_the_vocabularys_ops() -> None:
    """Each op whose struct names a shell command (``shell``) has it, with its option."""
    commands = _shell_commands()
    sent = set()
    for kind in COMMAND_TYPES:
        if kind.shell is None:
            continue
        command = commands[kind.shell.name]
        options = {o for p in command.params for o in p.opts}
        assert not kind.shell.option or kind.shell.option in options, op_of(kind)
        sent.add(op_of(kind))
    assert set(OPS) - sent == NOT_IN_THE_SHELL


def test_the_shells_op_commands_are_the_structs() -> None:
    """A command the loop builds says what its struct's ``shell`` says and takes the op's
    one argument as its positional (``mode MODE``, ``step-on STEP``)."""
    commands = _shell_commands()
    for kind in COMMAND_TYPES:
        shell = kind.shell
        if shell is None or shell.by_hand or shell.option:
            continue
        command = commands[shell.name]
        assert command.help == shell.help
        positional = [p.name for p in command.params if p.param_type_name == "argument"]
        field = argument_field(kind)
        assert positional == ([field.name] if field is not None else []), shell.name
        assert {"--user", "--cpu", "--connect", "--fb", "--tls-ca"} <= {
            o for p in command.params for o in p.opts
        }


@pytest.mark.parametrize(
    ("words", "sent"),
    [
        (["ack"], Ack(fb="_")),
        (["ack", "--step", "2"], AckStep(fb="_", args=StepArgs(step=2))),
        (["ack", "--message", "17"], AckMsg(fb="_", args=MessageArgs(msg_id=17))),
        (
            ["ack", "--message", "FILL/DB1/S2/SV"],
            AckMsg(fb="_", args=MessageArgs(msg_id="FILL/DB1/S2/SV")),
        ),
        (["ack", "--step", "2", "--message", "x"], AckMsg(fb="_", args=MessageArgs(msg_id="x"))),
        (["mode", "man"], SetMode(fb="_", args=ModeArgs(mode="MAN"))),
        (["init"], Init(fb="_")),
        (["off"], Off(fb="_")),
        (["t-push"], TPush(fb="_")),
        (["step-on", "3"], StepOn(fb="_", args=StepArgs(step=3))),
        (["step-on", "S3"], StepOn(fb="_", args=StepArgs(step=3))),  # as S7-GRAPH names it
        (["ack", "--step", "S2"], AckStep(fb="_", args=StepArgs(step=2))),
        (["step-off", "4"], StepOff(fb="_", args=StepArgs(step=4))),
        (["set-steps", "3", "12"], SetSteps(fb="_", args=StepsArgs(steps=[3, 12]))),
        (["set-steps", "S3", "s12"], SetSteps(fb="_", args=StepsArgs(steps=[3, 12]))),
        (["stop"], Stop(fb="_")),
        (["start"], Start(fb="_")),
        (["send", "halt", "on=true"], Halt(fb="_", args=OnArgs(on=True))),
        (["force", "I0.3", "off"], Force(fb="_", args=ForceArgs(address="I0.3", value=None))),
        (["force", "--all", "off"], Force(fb="_", args=ForceArgs(all=True))),
    ],
)
def test_a_shell_command_sends_its_ops_struct(
    monkeypatch: pytest.MonkeyPatch, words: list[str], sent: Command
) -> None:
    import typer

    from s7graph.web.cli import root as cli

    seen: list[Command] = []

    def remote(kind: type[Command], args: Args, **bus: object) -> None:
        assert bus["user"] == "u" and bus["cpu"] == "cpu1"
        seen.append(kind(fb="_", args=args))
        raise typer.Exit(0)

    monkeypatch.setattr(cli, "_remote", remote)
    assert cli.main([*words, "--user", "u"]) == 0
    assert seen == [sent]


@pytest.mark.parametrize(
    ("words", "reason"),
    [
        (["mode", "fast"], "mode must be one of AUTO, MAN, TAP, TOP (see s7graph mode --help)"),
        (["step-on", "0"], ": step is at least 1 (see s7graph step-on --help)"),
        (["step-on", "three"], ": 'three' is not a step: write it S3 or 3, as S7-GRAPH numbers"),
        (["send", "halt", "on=yes"], ": on is true or false, not a text (see s7graph send --help)"),
        (["set-steps", "3", "0"], "s7graph: error: steps[1] is at least 1 (see s7graph set-steps"),
        (["ack", "--message", "0"], ": msg_id is at least 1 (see s7graph ack --help)"),
    ],
)
def test_a_shell_command_refuses_a_bad_argument_before_the_bus(
    capsys: pytest.CaptureFixture[str], words: list[str], reason: str
) -> None:
    """In words, with the help of the command to read, never the place msgspec names in
    the message (`` - at `$.args.on```) nor its own words (``Expected `int` ...``)."""
    from s7graph.web import cli

    assert cli.main([*words, "--user", "u"]) == 2
    err = capsys.readouterr().err
    assert reason in err and "give the bus" not in err
    assert "$." not in err and "Expected" not in err and len(err.splitlines()) == 1


def test_docs_cli_md_lists_each_op_as_the_union_says() -> None:
    table = shell_markdown()
    assert "| `s7graph step-on STEP` | `step_on` | operator | activate a step (MAN) |" in table
    assert "| `s7graph send halt on=…` | `halt` |" in table
    assert table in (ROOT / "docs" / "cli.md").read_text(encoding="utf-8")


def test_the_shells_send_reads_any_ops_arguments_before_sending() -> None:
    assert command_args("halt", ["on=true"]) == {"on": True}
    assert command_args("ack_msg", ["msg_id=17"]) == {"msg_id": 17}
    assert command_args("ack_msg", ["msg_id=FILL/DB1/S2/SV"]) == {"msg_id": "FILL/DB1/S2/SV"}
    assert command_args("force", ["address=I0.3", "value=null"]) == {
        "address": "I0.3",
        "value": None,
    }
    assert command_args("undo_download", ["preview=true"]) == {"preview": True}
    for op, words, reason in [
        ("nope", [], "unknown op 'nope'; one of ack,"),
        ("halt", ["on"], "NAME=VALUE"),
        ("halt", ["on=yes"], "$.args.on"),
        ("mode", ["mode=FAST"], "mode must be one of"),
        ("init", ["step=1"], "takes no argument 'step'"),
        ("ack_msg", ["msg_id=" + "[" * 5000 + "]" * 5000], "msg_id takes at most 128"),
        ("force", ["address=MD10", "value=Infinity"], "finite numbers only"),
    ]:
        with pytest.raises(ValueError) as err:
            command_args(op, words)
        assert reason in str(err.value)


def test_the_pages_buttons_send_the_vocabularys_ops() -> None:
    from s7graph.web.view.panel import _CONTROL_BUTTONS, _STEP_BUTTONS, _hint

    buttons = [kind for kind, *_ in (*_CONTROL_BUTTONS, *_STEP_BUTTONS)]
    sent = {op_of(kind) for kind in buttons}
    sent |= _structs_built(ROOT / "web/view/panel.py")
    sent |= _structs_built(ROOT / "web/view/alarms.py")  # a message's button, Acknowledge all
    assert {"ack", "init", "off", "t_push", "halt", "step_on", "ack_step", "ack_msg"} <= sent
    assert sent <= set(OPS)
    assert _hint(buttons[0]) == "INIT_SQ: activate the initial steps"  # the pin, the row


def test_who_carries_each_op_out_and_which_conflict() -> None:
    from s7graph.web.bus import live
    from s7graph.web.bus.online import ENGINEERING_OPS

    assert ENGINEERING_OPS == ("download", "undo_download", "save", "open")
    assert {op_of(c) for c in COMMAND_TYPES if c.where == "cpu"} == {"stop", "start", "mres"}
    assert {op_of(c) for c in COMMAND_TYPES if c.where == "force"} == {"force", "modify"}
    assert set(live.HANDLERS) == {c for c in COMMAND_TYPES if c.where == "fb"}
    assert live._GROUPS == {
        "mode": "mode",
        "step_on": "step",
        "step_off": "step",
        "set_steps": "step",
        "ack_step": "step",
        "init": "init",
        "off": "init",
    }


def test_the_role_tables_argument_examples_name_the_structs_fields() -> None:
    """The ``args`` column (docs/bus.md, docs/security.md) shows each op's arguments."""
    import re

    for kind in COMMAND_TYPES:
        args = next(f.type for f in msgspec.structs.fields(kind) if f.name == "args")
        fields = msgspec.structs.fields(args)
        shown = set(re.findall(r'"(\w+)":', kind.example))
        assert {f.name for f in fields if f.required} <= shown <= {f.name for f in fields}


def test_docs_bus_md_shows_each_ops_arguments_as_the_union_says() -> None:
    from s7graph.web.commands import arguments_markdown

    table = arguments_markdown()
    assert "| `step_on` | `step`: int 1..65535 |" in table
    assert table in (ROOT / "docs" / "bus.md").read_text(encoding="utf-8")


def test_the_shell_and_the_page_send_structs_not_op_names() -> None:
    """web/view and web/cli build the struct of each op they send, so mypy checks the op and
    its arguments: no sender is given an op's name."""
    senders = {"_remote", "send", "command", "_command", "engineer_command", "send_command"}
    built: set[str] = set()
    for path in sorted([*(ROOT / "web/view").glob("*.py"), *(ROOT / "web/cli").glob("*.py")]):
        built |= _structs_built(path)
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if not isinstance(node, ast.Call) or not node.args:
                continue
            name = getattr(node.func, "id", None) or getattr(node.func, "attr", None)
            first = node.args[0]
            owner = getattr(getattr(node.func, "value", None), "id", "")
            if name not in senders or owner.endswith("app"):
                continue  # not a send, or a typer command's name (@app.command("import"))
            assert not isinstance(first, ast.Constant), (
                f"{path.name}:{node.lineno}: {first.value!r}"
            )
    assert {
        "mode",
        "halt",
        "ack_msg",
        "force",
        "download",
        "undo_download",
        "save",
        "open",
    } <= built


def test_a_struct_built_in_python_is_checked_before_it_is_sent() -> None:
    """msgspec checks constraints when it decodes, not when a struct is built: ``checked``
    refuses what the bus would, with its reason."""
    good = StepOn(fb="FILL", args=StepArgs(step=3))
    assert checked(good) == good and type(checked(good)) is StepOn
    with pytest.raises(ValueError, match=r"\$\.args\.step"):
        checked(StepOn(fb="FILL", args=StepArgs(step=0)))
    with pytest.raises(ValueError, match=r"\$\.fb"):
        checked(Ack(fb="bad name"))


@pytest.mark.parametrize(
    "args",
    [
        ForceArgs(address="MD10", value=1.0),
        {"address": "MD10", "value": float("inf")},
        {"address": "MD10", "value": float("nan")},
        {"address": "M\udcff", "value": True},
    ],
)
def test_a_value_or_text_json_cannot_carry_is_refused_not_changed(args: object) -> None:
    """JSON carries infinity and NaN as null — for ``force``, *unforce* — and cannot carry
    a lone surrogate (what Python makes of bytes that are not UTF-8): refused before the
    bus, for ``force`` and ``modify`` alike."""
    for op in ("force", "modify"):
        if isinstance(args, ForceArgs):
            assert make_command(op=op, fb="F", args=msgspec.to_builtins(args)).args.value == 1.0
            continue
        with pytest.raises(ValueError, match=r"finite numbers only|not valid Unicode"):
            make_command(op=op, fb="F", args=args)
