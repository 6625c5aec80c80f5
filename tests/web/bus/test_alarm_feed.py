"""A program of blocks' message list on a real bus (docs/bus.md, "Keys"): the ALARM_SQ and
ALARM_S messages its blocks raise go out on ``alarms`` and ``alarms/list`` as a chart's
do, and ``ack_msg`` acknowledges one — an operator's command, audited in the state file,
refused with the reason for a viewer, an unknown or an already acknowledged message."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

from s7graph.engine import CallContext, Cpu, ob
from s7graph.engine.clock import SystemClock
from s7graph.engine.persistence import StateStore
from s7graph.sfb import install
from s7graph.web.access.audit import read_audit
from s7graph.web.bus.client import BusClient
from s7graph.web.bus.protocol import AlarmList, Command, CommandReply
from tests.web.helpers import program_client, wait_until

pytestmark = pytest.mark.timeout(120)


@ob(1)
def main(ctx: CallContext) -> None:
    """MW0 counts scans; the tank message (ALARM_SQ, EV_ID 7) comes at 5 and goes at 10,
    the pump message (ALARM_S, EV_ID 8) comes at 5 and stays."""
    n = min(int(ctx.mem.get("MW0")) + 1, 32767)
    ctx.mem.set("MW0", n)
    ctx.call("ALARM_SQ", SIG=5 <= n < 10, ID=0xEEEE, EV_ID=7, SD="P#MW0 WORD 1")
    ctx.call("ALARM_S", SIG=n >= 5, ID=0xEEEE, EV_ID=8, SD="")


@dataclass
class Plant:
    cpu: Cpu
    client: BusClient
    store: StateStore

    def send(self, msg_id: object, *, user: str = "olga", login: bool = True) -> CommandReply:
        token = self.client.login(user).token if login else ""
        command = Command(op="ack_msg", fb="cpu1", user=user, token=token, args={"msg_id": msg_id})
        return self.client.send(command, timeout=8.0)


@pytest.fixture
def plant(tmp_path: Path) -> Iterator[Plant]:
    """The program scanned every 10 ms by a runner, on the bus, audited in its state file."""
    cpu = Cpu(SystemClock(), max_cycle_ms=5000)
    install(cpu)
    cpu.load(main)
    with program_client(cpu, tmp_path) as (run, client):
        yield Plant(cpu, client, run.store)


def _entries(alarms: AlarmList | None) -> dict[object, tuple[str, bool, bool]]:
    if alarms is None:
        return {}
    return {e.msg_id: (e.state, e.ack_required, e.acked) for e in alarms.entries}


def test_a_programs_messages_go_on_the_bus_and_an_operator_acknowledges_one(
    plant: Plant,
) -> None:
    seen: list[AlarmList] = []
    plant.client.on_alarms(seen.append)
    gone = ("outgoing", True, False)
    assert wait_until(lambda: _entries(plant.client.alarms()).get(7) == gone, 30)
    listed = _entries(plant.client.alarms())
    assert listed[8] == ("incoming", False, True)  # ALARM_S: acknowledged implicitly
    assert wait_until(lambda: any(_entries(a).get(7) == gone for a in seen), 10)

    refused = plant.send(7, user="", login=False)
    assert not refused.applied and refused.reason.startswith("not logged in")

    reply = plant.send(7)
    assert reply.applied, reply.reason
    assert wait_until(lambda: 7 not in _entries(plant.client.alarms()), 10)
    assert wait_until(lambda: seen and 7 not in _entries(seen[-1]), 10)

    again = plant.send(7)
    assert (again.applied, again.reason) == (False, "no message 7 in the message list")
    assert plant.send(8).reason == "message 8 is already acknowledged"
    assert plant.send(99).reason == "no message 99 in the message list"
    audited = [(r.op, r.outcome, r.user) for r in read_audit(plant.store.path)]
    assert ("ack_msg", "applied", "olga (unverified)") in audited
    assert sum(1 for op, outcome, _ in audited if (op, outcome) == ("ack_msg", "refused")) >= 3
