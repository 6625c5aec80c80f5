"""The bus's outbox: what the scan thread publishes is sent by a thread of its own, so a
blocked put never holds up a scan; in order, ``seq`` set when sent, overflow dropped and
counted — and a view that joins late, or misses deltas, still ends at the CPU's state."""

from __future__ import annotations

import threading
import time
from pathlib import Path

import pytest

from s7graph.sequencer.text.model import Chart, Sequence, Step, Transition
from s7graph.web.bus.client import BusClient
from s7graph.web.bus.outbox import Outbox
from s7graph.web.bus.protocol import ChartLayout, StepStateUpdate, decode
from s7graph.web.bus.publisher import BusPublisher
from s7graph.web.bus.session import open_session
from tests.web.helpers import wait_until

pytestmark = pytest.mark.timeout(60)


class Blocked:
    """A zenoh publisher stand-in whose ``put`` waits until released."""

    def __init__(self) -> None:
        self.release = threading.Event()
        self.sent: list[bytes] = []

    def put(self, data: bytes) -> None:
        self.release.wait()
        self.sent.append(data)


def update(cycle: int) -> StepStateUpdate:
    return StepStateUpdate(cycle=cycle, t_ms=cycle * 10, mode="AUTO", active=[1 + cycle % 2])


def test_posting_never_waits_for_a_blocked_put_and_order_and_seq_hold() -> None:
    pub = Blocked()
    box = Outbox(limit=100)
    try:
        t0 = time.monotonic()
        for n in range(1, 51):
            assert box.post(pub, update(n), seq=n)  # type: ignore[arg-type]
        assert time.monotonic() - t0 < 1.0 and pub.sent == []  # the put is stuck, not us
        pub.release.set()
        assert wait_until(lambda: len(pub.sent) == 50)
        got = [decode(data, StepStateUpdate) for data in pub.sent]
        assert [(u.seq, u.cycle) for u in got] == [(n, n) for n in range(1, 51)]
        assert (box.sent, box.dropped) == (50, 0)
    finally:
        pub.release.set()
        box.close()


def test_a_full_outbox_drops_and_counts_and_close_sends_what_waits() -> None:
    pub = Blocked()
    box = Outbox(limit=10)
    try:
        results = [box.post(pub, update(n), seq=n) for n in range(1, 31)]  # type: ignore[arg-type]
        assert results.count(False) == box.dropped >= 19
    finally:
        pub.release.set()
        box.close()
    assert box.sent == 30 - box.dropped and box.pending() == 0


def layout() -> ChartLayout:
    steps = (Step(1, "A", initial=True), Step(2, "B"))
    transitions = (Transition(1, "", (1,), (2,)), Transition(2, "", (2,), (1,)))
    return ChartLayout.from_chart(Chart("FLIP", sequences=(Sequence(1, "M", steps, transitions),)))


def test_a_late_joiner_and_a_view_that_missed_deltas_end_at_the_cpus_state(
    tmp_path: Path,
) -> None:
    endpoint = f"unixsock-stream/{tmp_path}/bus.sock"
    with open_session(listen=[endpoint]) as cpu, open_session(connect=[endpoint]) as view:
        publisher = BusPublisher(cpu, "cpu1", {"FLIP": layout()})
        client = BusClient(view, "cpu1")
        try:
            assert wait_until(lambda: client.chart("FLIP") is not None)
            early: list[StepStateUpdate] = []
            client.follow("FLIP", early.append)
            for n in range(1, 1001):  # every scan switches: 1000 deltas back to back
                assert publisher.publish("FLIP", update(n))
                if n == 500:
                    late: list[StepStateUpdate] = []
                    follower = client.follow("FLIP", late.append)  # joins mid-burst
            assert wait_until(lambda: bool(late) and late[-1].seq == 1000)
            assert wait_until(lambda: bool(early) and early[-1].seq == 1000)
            for seen in (early, late):
                assert [u.seq for u in seen] == sorted({u.seq for u in seen})  # in order
                assert (seen[-1].cycle, seen[-1].active) == (1000, [1])
            assert follower.latest == late[-1]
            assert publisher.outbox.dropped == 0
        finally:
            client.close()
            publisher.close()


def test_a_job_runs_in_order_on_the_outbox_thread_and_counts_as_its_weight() -> None:
    pub = Blocked()
    box = Outbox(limit=9)
    ran: list[str] = []

    def job() -> int:
        ran.append(threading.current_thread().name)
        pub.put(b"job")
        return 1

    try:
        assert box.post(pub, update(1), seq=1)  # type: ignore[arg-type]
        assert box.run(job, weight=8)
        assert box.pending() == 9
        assert not box.run(job, weight=3)  # 9 wait: the limit, dropped as 3
        assert not box.post(pub, update(2), seq=2)  # type: ignore[arg-type]
        assert box.dropped == 4
        pub.release.set()
        assert wait_until(lambda: box.pending() == 0)
        assert pub.sent[1] == b"job" and len(pub.sent) == 2
        assert ran == ["s7graph-bus-out"] and box.sent == 2
        assert box.post(pub, update(3), seq=3)  # type: ignore[arg-type]
    finally:
        pub.release.set()
        box.close()
