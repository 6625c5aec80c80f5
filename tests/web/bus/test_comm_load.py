"""Scan cycle load from communication (S7 HW Config, Cycle/Clock Memory: 20 % by default):
the commands applied at one scan boundary take at most that share of the cycle, the rest
wait for the next boundary in order (web/bus/publisher.py ``apply_commands(until_ns=...)``,
engine/runner.py ``COMM_LOAD_PCT``). A real zenoh bus on a unix socket."""

from __future__ import annotations

import threading
import time

import pytest

from s7graph.engine.clock import VirtualClock
from s7graph.engine.cpu import Cpu
from s7graph.engine.runner import COMM_LOAD_PCT, Runner
from s7graph.web.bus.client import BusClient
from s7graph.web.bus.protocol import Command, CommandReply
from s7graph.web.bus.publisher import BusPublisher
from tests.web.bus import test_bus
from tests.web.helpers import wait_until

pytestmark = pytest.mark.timeout(30)
bus = test_bus.bus  # the fixture: a CPU's bus and a view's client on one unix socket


def _send_steps(
    publisher: BusPublisher, client: BusClient, steps: range
) -> tuple[list[threading.Thread], list[CommandReply]]:
    """One command per step number, each sent once the one before is queued (so the queue
    holds them in this order)."""
    login = client.login("bob")
    assert login.ok, login.reason
    replies: list[CommandReply] = []
    threads = []
    for k, n in enumerate(steps, 1):
        command = Command(op="step_on", fb="FILL", user="bob", token=login.token, args={"step": n})
        thread = threading.Thread(target=lambda c=command: replies.append(client.send(c)))
        thread.start()
        threads.append(thread)
        assert wait_until(lambda k=k: publisher.queued == k, 5.0, poll=0.005)
    return threads, replies


def test_commands_beyond_the_share_of_the_cycle_wait_for_the_next_boundary_in_order(
    bus: tuple[BusPublisher, BusClient],
) -> None:
    publisher, client = bus
    threads, replies = _send_steps(publisher, client, range(1, 6))
    applied: list[int | None] = []

    def apply(command: Command) -> tuple[bool, str]:
        applied.append(command.step)
        return True, ""

    spent = time.perf_counter_ns()  # the share is used up before the first command
    assert publisher.apply_commands(apply, cycle=1, until_ns=spent) == 1
    assert applied == [1] and publisher.comm_limited == 1 and publisher.queued == 4
    assert publisher.apply_commands(apply, cycle=2, until_ns=spent) == 1
    assert publisher.comm_limited == 2
    assert publisher.apply_commands(apply, cycle=3) == 3  # no limit: the rest at once
    assert applied == [1, 2, 3, 4, 5] and publisher.comm_limited == 2
    for t in threads:
        t.join(5)
    assert sorted(r.cycle for r in replies) == [1, 2, 3, 3, 3]
    assert all(r.applied for r in replies)


def test_a_boundary_within_its_share_takes_every_command_and_counts_nothing(
    bus: tuple[BusPublisher, BusClient],
) -> None:
    publisher, client = bus
    threads, replies = _send_steps(publisher, client, range(1, 4))
    later = time.perf_counter_ns() + 10_000_000_000
    assert publisher.apply_commands(lambda c: (True, ""), cycle=7, until_ns=later) == 3
    assert publisher.comm_limited == 0
    for t in threads:
        t.join(5)
    assert [r.cycle for r in replies] == [7, 7, 7]


def test_the_runner_gives_communication_its_share_of_the_cycle_time() -> None:
    cpu = Cpu(VirtualClock())
    assert COMM_LOAD_PCT == 20  # S7's default
    assert Runner(cpu, cycle_ms=10).comm_budget_ns == 2_000_000
    assert Runner(cpu, cycle_ms=100, comm_load_pct=50).comm_budget_ns == 50_000_000
    for wrong in (0, 101):
        with pytest.raises(ValueError, match="communication load must be 1-100 %"):
            Runner(cpu, comm_load_pct=wrong)
