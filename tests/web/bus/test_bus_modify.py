"""Modify over a real zenoh bus (a unix socket) against a chart on the virtual clock: the
role table makes ``modify`` an engineer's op, the gate audits every modify command, applied
or refused; a modified input is read by the next scan, a modified output is written over
by the program in the next scan (a modify is not held, a force is), a forced operand is
refused; and the shell's ``s7graph modify``."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from s7graph.web.access.audit import read_audit
from tests.web.bus.test_bus_force import Bus, bus  # noqa: F401  (the fixture)
from tests.web.helpers import PASSWORD, OnlineRig, wait_until

pytestmark = pytest.mark.timeout(90)


def _rows(rig: OnlineRig) -> list[tuple[str, str, str, str]]:
    audit = read_audit(rig.state)
    return [(r.user, r.outcome, r.reason, r.detail) for r in audit if r.op == "modify"]


def test_an_operator_is_refused_modify_and_audited(bus: Bus) -> None:  # noqa: F811
    for user, role in (("olga", "operator"), ("vic", "viewer")):
        reply = bus.send(user, "modify", address="Start", value=True)
        assert not reply.applied
        assert reply.reason == f"role {role} may not modify (needs engineer)"
    assert bus.active() == [1] and not bus.rig.session.cpu.mem.periph_in[0]
    assert [(u, o) for u, o, _, _ in _rows(bus.rig)] == [("olga", "refused"), ("vic", "refused")]


def test_an_engineers_modify_is_written_once_and_not_held(bus: Bus) -> None:  # noqa: F811
    cpu = bus.rig.session.cpu
    reply = bus.send("eng", "modify", address="Start", value=True)
    assert reply.applied, reply.reason
    assert wait_until(lambda: bus.active() == [2])  # OB1 read the modified input
    assert wait_until(lambda: cpu.mem.periph_out[1] & 1)  # S2: N "Lamp"
    assert bus.send("eng", "modify", address="Lamp", value=False).applied
    assert bus.active() == [2]
    assert wait_until(lambda: cpu.mem.periph_out[1] & 1)  # S2 writes it again: not held
    assert bus.send("eng", "modify", address="Speed", value="-5").applied
    assert wait_until(lambda: cpu.mem.get("Speed") == -5)
    assert bus.send("eng", "modify", address="Start", value="FALSE").applied
    assert wait_until(lambda: bus.active() == [1])
    assert len(cpu.forces) == 0
    details = [d for u, o, _, d in _rows(bus.rig) if (u, o) == ("eng", "applied")]
    wanted = [
        'modify "Start" (I0.0) = TRUE',
        'modify "Lamp" (Q1.0) = FALSE',
        'modify "Speed" (MW20) = -5',
        'modify "Start" (I0.0) = FALSE',
    ]
    assert len(details) == len(wanted)
    assert all(f": {want};" in detail for want, detail in zip(wanted, details, strict=True))


@pytest.mark.parametrize(
    ("args", "reason"),
    [
        ({"address": "T1", "value": 1}, "T1 cannot be modified"),
        ({"address": "Nowhere", "value": True}, "not an S7 address or a symbol"),
        ({"address": "DB99.DBW0", "value": 1}, "DB99 does not exist"),
        ({"address": "MW20", "value": 70000}, "70000 does not fit the word MW20"),
        ({"address": "I0.0", "value": 3}, "3 does not fit the bit I0.0: modify TRUE or FALSE"),
    ],
)
def test_bad_modify_commands_are_refused_naming_the_problem_and_audited(
    bus: Bus,  # noqa: F811
    args: dict[str, object],
    reason: str,
) -> None:
    reply = bus.send("eng", "modify", **args)
    assert not reply.applied and reason in reply.reason
    ((user, outcome, audited, _),) = _rows(bus.rig)
    assert (user, outcome) == ("eng", "refused") and reason in audited


def test_a_forced_operand_is_not_modified(bus: Bus) -> None:  # noqa: F811
    assert bus.send("eng", "force", address="Start", value=True).applied
    reply = bus.send("eng", "modify", address="I0.0", value=False)
    assert not reply.applied
    assert "I0.0 is forced" in reply.reason and "unforce I0.0 first" in reply.reason
    assert wait_until(lambda: bus.active() == [2])


@pytest.mark.parametrize(
    ("payload", "reason"),
    [
        (b'{"op":"modify","fb":"Seq_lamp","args":{"address":"M0.0"}}', "needs argument 'value'"),
        (b'{"op":"modify","fb":"Seq_lamp","args":{"address":"M0.0","value":null}}', "$.args"),
        (b'{"op":"modify","fb":"Seq_lamp","args":{"address":"M0.0","value":1,"x":1}}', "x"),
    ],
)
def test_hostile_modify_messages_are_refused_before_the_scan(
    bus: Bus,  # noqa: F811
    payload: bytes,
    reason: str,
) -> None:
    reply = bus.client.send_raw(payload)
    assert reply is not None and not reply.applied and reason in reply.reason
    assert bus.rig.session.cpu.mode.value == "RUN"


def _shell(rig: OnlineRig, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "s7graph", "modify", *args, "--cpu", "cpu1", *rig.bus],
        capture_output=True,
        text=True,
        timeout=60,
        env={**os.environ, "S7GRAPH_PASSWORD": PASSWORD},
    )


def test_the_modify_command_writes_once_from_a_shell(bus: Bus) -> None:  # noqa: F811
    rig = bus.rig
    refused = _shell(rig, "M0.0", "TRUE", "--user", "olga")
    assert refused.returncode == 1
    assert "modify refused: role operator may not modify (needs engineer)" in refused.stderr
    done = _shell(rig, "Speed", "-7", "--user", "eng")  # a negative value, not an option
    assert done.returncode == 0, done.stderr
    assert wait_until(lambda: rig.session.cpu.mem.get("Speed") == -7)
    usage = _shell(rig, "M0.0", "--user", "eng")
    assert usage.returncode == 2 and "give ADDRESS VALUE" in usage.stderr


def test_an_instance_db_pin_is_modified_by_name_through_the_gate(bus: Bus) -> None:  # noqa: F811
    reply = bus.send("olga", "modify", address='"Seq_lamp".SW_MAN', value=True)
    assert not reply.applied and "needs engineer" in reply.reason
    reply = bus.send("eng", "modify", address='"Seq_lamp".SW_MAN', value="TRUE")
    assert reply.applied, reply.reason
    graph = bus.rig.session.graph
    assert wait_until(lambda: graph.state.mode == "MAN")  # the FB read its input
    assert bus.send("eng", "modify", address="DB1.SW_AUTO", value=True).applied
    assert wait_until(lambda: graph.state.mode == "AUTO")
    reply = bus.send("eng", "modify", address="DB1.SW_MAN", value=2)
    assert not reply.applied and "TRUE or FALSE" in reply.reason
    details = [d for u, o, _, d in _rows(bus.rig) if (u, o) == ("eng", "applied")]
    assert [d.split(": ", 1)[1].split(";")[0] for d in details] == [
        'modify "Seq_lamp".SW_MAN = TRUE',
        "modify DB1.SW_AUTO = TRUE",
    ]
