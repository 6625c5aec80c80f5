"""Forcing over a real zenoh bus (a unix socket) against a chart on the virtual clock: the
role table makes ``force`` an engineer's op, the gate audits every force command, applied
or refused, and an applied force job acts in the scan, shows in ``status`` (the FRCE LED)
and on ``forces``, and goes again with ``unforce``. Level overrides show in the state."""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from s7graph.engine.diagnostics import EventId
from s7graph.web.access.audit import read_audit
from s7graph.web.bus.client import BusClient
from s7graph.web.bus.protocol import Command, CommandReply
from tests.web.helpers import PASSWORD, OnlineRig, logged_in, online_client, wait_until

if TYPE_CHECKING:
    from tests.conftest import BusCerts

pytestmark = pytest.mark.timeout(90)

CHART = """FUNCTION_BLOCK "Seq_lamp" FB 1 DB 1
SYMBOLS
  "Start" : I0.0 : BOOL;
  "Lamp"  : Q1.0 : BOOL;
  "Speed" : MW20 : INT;
END_SYMBOLS
SEQUENCE 1 "Lamp"
  INITIAL_STEP S1 "Idle":
  END_STEP
  STEP S2 "Lit":
    N "Lamp";
  END_STEP
  TRANSITION T1 "Go" FROM S1 TO S2 := "Start";
  TRANSITION T2 "Done" FROM S2 TO S1 := NOT "Start";
END_SEQUENCE
END_FUNCTION_BLOCK
"""


@dataclass
class Bus:
    rig: OnlineRig
    client: BusClient
    tokens: dict[str, str]

    def send(self, user: str, op: str, **args: object) -> CommandReply:
        command = Command(
            op=op,
            fb="Seq_lamp",
            user=user,
            token=self.tokens[user],  # type: ignore[arg-type]
            origin="shell test",
            args=args,
        )
        return self.client.send(command)

    def active(self) -> list[int]:
        g = self.rig.session.graph
        return sorted(g.cc.step_numbers[i] for i in g.state.active)


@pytest.fixture
def bus(tmp_path: Path, bus_certs: BusCerts) -> Iterator[Bus]:
    users = {"olga": "operator", "eng": "engineer", "vic": "viewer"}
    with online_client(
        tmp_path, CHART, certs=bus_certs, users=users, user=None, name="lamp.s7g"
    ) as on:
        assert wait_until(lambda: on.client.status() is not None)
        tokens = {user: logged_in(on.client, user, origin="shell test") for user in users}
        yield Bus(on.rig, on.client, tokens)


def _force_rows(rig: OnlineRig) -> list[tuple[str, str, str, str]]:
    return [(r.user, r.role, r.outcome, r.reason) for r in read_audit(rig.state) if r.op == "force"]


def test_an_operator_is_refused_force_and_audited(bus: Bus) -> None:
    for user, role in (("olga", "operator"), ("vic", "viewer")):
        reply = bus.send(user, "force", address="Start", value=True)
        assert not reply.applied
        assert reply.reason == f"role {role} may not force (needs engineer)"
    assert len(bus.rig.session.cpu.forces) == 0 and bus.active() == [1]
    assert _force_rows(bus.rig) == [
        ("olga", "operator", "refused", "role operator may not force (needs engineer)"),
        ("vic", "viewer", "refused", "role viewer may not force (needs engineer)"),
    ]


def test_an_engineers_force_acts_in_the_scan_and_shows_in_the_status_until_unforced(
    bus: Bus,
) -> None:
    seen: list[int] = []
    bus.client.on_status(lambda status: seen.append(status.forces))
    listed = []
    bus.client.on_forces(listed.append)
    reply = bus.send("eng", "force", address="Start", value=True)
    assert reply.applied, reply.reason
    assert wait_until(lambda: bus.active() == [2])  # OB1 read the forced input
    status = bus.client.status()
    assert status is not None and status.forces == 1 and 1 in seen
    forces = bus.client.forces()
    assert forces is not None and [
        (e.address, e.value, e.symbol, e.user) for e in forces.entries
    ] == [("I0.0", "TRUE", "Start", "eng")]
    assert wait_until(lambda: listed and listed[-1].entries)
    cpu = bus.rig.session.cpu
    assert any(e.event_id == EventId.FORCE_STARTED and e.address == "I0.0" for e in cpu.diagnostics)
    assert bus.send("eng", "force", address="QB1", value="B#16#00").applied  # Lamp off
    assert wait_until(lambda: cpu.mem.periph_out[1] == 0)
    assert bus.active() == [2]  # S2 still sets "Lamp": the module gets the force value

    assert bus.send("eng", "force", address="Start", value=None).applied
    assert wait_until(lambda: bus.active() == [1])  # the module's FALSE again
    assert bus.send("eng", "force", all=True).applied
    assert wait_until(lambda: (s := bus.client.status()) is not None and s.forces == 0)
    assert len(cpu.forces) == 0
    rows = _force_rows(bus.rig)
    assert [(u, role, outcome) for u, role, outcome, _ in rows] == [
        ("eng", "engineer", "applied")
    ] * 4
    details = [r.detail for r in read_audit(bus.rig.state) if r.op == "force"]
    assert 'force "Start" (I0.0) = TRUE; 1 active' in details[0]
    assert "unforce all (QB1 = B#16#00)" in details[-1]


@pytest.mark.parametrize(
    ("args", "reason"),
    [
        ({"address": "DB1.DBX0.0", "value": True}, "DB1.DBX0.0 cannot be forced"),
        ({"address": "Nowhere", "value": True}, "not an S7 address or a symbol"),
        ({"address": "MW20", "value": 70000}, "70000 does not fit the word MW20"),
        ({"address": "Speed", "value": "T#5S"}, "T#5S is a TIME (32 bits), not a value for"),
        ({"address": "I0.0", "value": 3}, "3 does not fit the bit I0.0: force TRUE or FALSE"),
        ({"address": "Q1.0", "value": None}, "Q1.0 is not forced"),
    ],
)
def test_bad_force_commands_are_refused_naming_the_problem_and_audited(
    bus: Bus, args: dict[str, object], reason: str
) -> None:
    reply = bus.send("eng", "force", **args)
    assert not reply.applied and reason in reply.reason
    ((user, _, outcome, audited),) = _force_rows(bus.rig)
    assert (user, outcome) == ("eng", "refused") and reason in audited


@pytest.mark.parametrize(
    ("payload", "reason"),
    [
        (b'{"op":"force","fb":"Seq_lamp","args":{"address":"I0.0"}}', "force takes"),
        (b'{"op":"force","fb":"Seq_lamp","args":{"all":false}}', '{"all": true} alone'),
        (
            b'{"op":"force","fb":"Seq_lamp","args":{"address":"' + b"I" * 65 + b'","value":1}}',
            "at `$.args.address`",
        ),
        (
            b'{"op":"force","fb":"Seq_lamp","args":{"address":"I0.0","value":"'
            + b"1" * 65
            + b'"}}',
            "at `$.args.value`",
        ),
        (b'{"op":"force","fb":"Seq_lamp","args":{"address":"I0.0","value":[1]}}', "$.args"),
    ],
)
def test_hostile_force_messages_are_refused_before_the_scan(
    bus: Bus, payload: bytes, reason: str
) -> None:
    reply = bus.client.send_raw(payload)
    assert reply is not None and not reply.applied and reason in reply.reason
    assert len(bus.rig.session.cpu.forces) == 0
    assert bus.rig.session.cpu.mode.value == "RUN"


def test_level_overrides_show_in_the_fb_state(bus: Bus) -> None:
    assert bus.send("eng", "en_il", on=False).applied
    assert bus.send("olga", "halt", on=True).applied
    state = [None]

    def held() -> bool:
        state[0] = bus.client.state("Seq_lamp")  # type: ignore[assignment]
        return state[0] is not None and state[0].overrides == {  # type: ignore[attr-defined]
            "EN_IL": False,
            "HALT_SQ": True,
        }

    assert wait_until(held)
    assert bus.send("olga", "halt", on=False).applied
    assert wait_until(
        lambda: (s := bus.client.state("Seq_lamp")) is not None and s.overrides == {"EN_IL": False}
    )


def _shell(
    rig: OnlineRig, *args: str, password: str = PASSWORD
) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [
            sys.executable,
            "-m",
            "s7graph",
            "force",
            *args,
            "--cpu",
            "cpu1",
            *rig.bus,
        ],
        capture_output=True,
        text=True,
        timeout=60,
        env={**os.environ, "S7GRAPH_PASSWORD": password},
    )


def test_the_force_command_forces_lists_and_unforces_from_a_shell(bus: Bus) -> None:
    rig = bus.rig
    refused = _shell(rig, "I0.0", "TRUE", "--user", "olga")
    assert refused.returncode == 1
    assert "force refused: role operator may not force (needs engineer)" in refused.stderr
    forced = _shell(rig, "Speed", "-5", "--user", "eng")  # a negative value, not an option
    assert forced.returncode == 0, forced.stderr
    assert _shell(rig, "Start", "TRUE", "--user", "eng").returncode == 0
    assert wait_until(lambda: bus.active() == [2])
    listed = _shell(rig, "--list")
    assert listed.returncode == 0, listed.stderr
    assert listed.stdout.splitlines() == [
        'I0.0 = TRUE  "Start"  (eng)',
        'MW20 = -5  "Speed"  (eng)',
    ]
    bad = _shell(rig, "Speed", "1.5", "--user", "eng")
    assert bad.returncode == 1
    assert '1.5 is not an integer for INT (to force the INT "Speed" (MW20))' in bad.stderr
    assert _shell(rig, "Start", "off", "--user", "eng").returncode == 0
    assert _shell(rig, "--all", "off", "--user", "eng").returncode == 0
    assert _shell(rig, "--list").stdout == "no force job active on cpu1\n"
    usage = _shell(rig, "I0.0", "--user", "eng")
    assert usage.returncode == 2 and "give ADDRESS VALUE" in usage.stderr
