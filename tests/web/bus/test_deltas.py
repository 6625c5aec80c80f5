"""One message per scan on ``deltas`` (web/bus/deltas.py), on a real zenoh over a unix socket:
a follower sees every FB's deltas in ``seq`` order and recovers from a lost message, a
reader of an FB's own ``fb/<fb>/delta`` still gets its deltas (and only then are they put
there), a scan that changes nothing sends nothing, and drops are counted."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import msgspec
import pytest
import zenoh

from s7graph.sequencer.text.model import Chart, Sequence, Step, Transition
from s7graph.web.bus.client import BusClient, StateFollower
from s7graph.web.bus.deltas import encode_parts
from s7graph.web.bus.protocol import ChartLayout, ScanDeltas, StepStateUpdate, decode
from s7graph.web.bus.publisher import BusPublisher
from s7graph.web.bus.session import open_session
from tests.web.helpers import wait_until

pytestmark = pytest.mark.timeout(60)

FBS = ("A", "B", "C")


def layout(fb: str) -> ChartLayout:
    steps = (Step(1, "Idle", initial=True), Step(2, "Run"))
    transitions = (Transition(1, "", (1,), (2,)), Transition(2, "", (2,), (1,)))
    return ChartLayout.from_chart(Chart(fb, sequences=(Sequence(1, "M", steps, transitions),)))


def state(cycle: int, step: int) -> StepStateUpdate:
    """An FB's scan in which it switched to ``step``."""
    return StepStateUpdate(
        cycle=cycle, t_ms=cycle * 10, mode="AUTO", active=[step], events=[("S1", step)]
    )


class Bus:
    """A CPU with the FBs A, B, C and a view's session, both on one unix socket."""

    def __init__(self, cpu: zenoh.Session, view: zenoh.Session) -> None:
        self.cpu = cpu
        self.view = view
        self.publisher = BusPublisher(cpu, "cpu1", {fb: layout(fb) for fb in FBS})
        self.client = BusClient(view, "cpu1")
        self.cycle = 0

    def scan(self, *changed: str) -> list[str]:
        """One scan in which the FBs ``changed`` switched."""
        self.cycle += 1
        c = self.cycle
        updates = [(fb, state(c, 1 + c % 2)) for fb in changed]
        return self.publisher.publish_scan(c, c * 10, updates)

    def sent(self) -> int:
        """Messages with deltas the CPU put so far (on ``deltas`` and the FBs' own keys),
        once its outbox is empty."""
        box, deltas = self.publisher.outbox, self.publisher.deltas
        assert deltas is not None and wait_until(lambda: box.pending() == 0)
        return deltas.put + deltas.put_own


def own_key_read(bus: Bus, fb: str) -> bool:
    deltas = bus.publisher.deltas
    assert deltas is not None
    return deltas.own_key_read(fb)


@pytest.fixture
def bus(tmp_path: Path) -> Iterator[Bus]:
    endpoint = f"unixsock-stream/{tmp_path}/bus.sock"
    with open_session(listen=[endpoint]) as cpu, open_session(connect=[endpoint]) as view:
        b = Bus(cpu, view)
        try:
            assert wait_until(lambda: b.client.chart("A") is not None)
            yield b
        finally:
            b.client.close()
            b.publisher.close()


def test_one_message_per_scan_carries_every_changed_fbs_delta(bus: Bus) -> None:
    got: list[ScanDeltas] = []

    def on_sample(sample: zenoh.Sample) -> None:
        got.append(decode(sample.payload.to_bytes(), ScanDeltas))

    sub = bus.view.declare_subscriber("s7graph/cpu1/deltas", on_sample)
    try:
        deltas = bus.publisher.deltas
        assert deltas is not None and wait_until(deltas.read)  # the CPU knows the reader
        before = bus.sent()
        assert bus.scan("A", "C") == ["A", "C"]
        assert bus.scan() == []  # nothing changed: nothing sent
        assert bus.scan("B") == ["B"]
        assert wait_until(lambda: len(got) == 2)
        assert bus.sent() == before + 2
        first, second = got
        assert (first.cycle, list(first.fbs), second.cycle, list(second.fbs)) == (
            1,
            ["A", "C"],
            3,
            ["B"],
        )
        assert second.seq == first.seq + 1
        assert [u.seq for u in first.fbs.values()] == [1, 1]  # each FB's own change count
    finally:
        sub.undeclare()  # type: ignore[no-untyped-call]


def test_followers_see_every_fbs_deltas_in_seq_order(bus: Bus) -> None:
    seen: dict[str, list[StepStateUpdate]] = {fb: [] for fb in FBS}
    followers = {fb: bus.client.follow(fb, seen[fb].append) for fb in FBS}
    plan = [("A", "B", "C"), ("A",), (), ("B", "C"), ("A", "C"), ("C",)] * 20
    for changed in plan:
        bus.scan(*changed)
    count = {fb: sum(fb in changed for changed in plan) for fb in FBS}
    assert wait_until(lambda: all(seen[fb] and seen[fb][-1].seq == count[fb] for fb in FBS))
    for fb in FBS:
        assert [u.seq for u in seen[fb]] == list(range(1, count[fb] + 1))
        assert followers[fb].gaps == 0
        assert seen[fb][-1] == msgspec.structs.replace(seen[fb][-1], seq=count[fb])


def test_a_lost_message_makes_the_followers_get_the_state_again(bus: Bus) -> None:
    seen: dict[str, list[StepStateUpdate]] = {fb: [] for fb in FBS}
    followers = {fb: bus.client.follow(fb, seen[fb].append) for fb in FBS}
    bus.scan("A", "B")
    assert wait_until(lambda: bool(seen["A"]) and bool(seen["B"]))
    box = bus.publisher.outbox
    box.limit = 0  # a congested outbox: the next scan's message is dropped
    bus.scan("A", "C")  # C's only change: it never changes again
    assert box.dropped == 2  # counted as the deltas it carried
    box.limit = 20_000
    bus.scan("B")  # the next message shows the gap: every follower gets its state again
    assert wait_until(lambda: bool(seen["C"]) and seen["C"][-1].seq == 1)
    assert wait_until(lambda: seen["A"][-1].seq == 2 and seen["B"][-1].seq == 2)
    assert seen["C"][-1].active == [1 + 2 % 2] and seen["C"][-1].cycle == 2
    assert followers["C"].gaps == 1 and followers["A"].gaps == 1
    for fb in FBS:
        assert [u.seq for u in seen[fb]] == sorted({u.seq for u in seen[fb]})


def test_a_reader_of_an_fbs_own_key_still_gets_its_deltas(bus: Bus) -> None:
    before = bus.sent()
    bus.scan("A", "B")
    assert bus.sent() == before + 1  # nobody reads fb/<fb>/delta: only the scan's message
    old: list[StepStateUpdate] = []
    reader = StateFollower(old.append)
    sub = bus.view.declare_subscriber("s7graph/cpu1/fb/A/delta", reader.on_sample)
    try:
        assert wait_until(lambda: own_key_read(bus, "A"))
        assert not own_key_read(bus, "B")
        before = bus.sent()
        for _ in range(10):
            bus.scan("A", "B")
        assert wait_until(lambda: len(old) == 10)
        assert [u.seq for u in old] == list(range(2, 12)) and reader.gaps == 0
        assert bus.sent() == before + 20  # the scan's message, and A's delta on its key
    finally:
        sub.undeclare()  # type: ignore[no-untyped-call]
    assert wait_until(lambda: not own_key_read(bus, "A"))
    before = bus.sent()
    bus.scan("A")
    assert bus.sent() == before + 1


def test_a_late_joiner_gets_the_state_then_newer_deltas_only(bus: Bus) -> None:
    bus.scan("A")
    bus.scan("A")
    bus.sent()  # both put before the follower subscribes (the outbox sends on its thread)
    seen: list[StepStateUpdate] = []
    follower = bus.client.follow("A", seen.append)
    assert [(u.seq, u.cycle) for u in seen] == [(2, 2)]  # the snapshot
    bus.scan("A")
    assert wait_until(lambda: len(seen) == 2)
    assert (seen[-1].seq, seen[-1].cycle) == (3, 3) and follower.gaps == 0


def test_unknown_fbs_are_refused_and_nothing_of_the_scan_counts(bus: Bus) -> None:
    with pytest.raises(KeyError, match="unknown FB 'Z'"):
        bus.publisher.publish_scan(1, 10, [("A", state(1, 2)), ("Z", state(1, 2))])
    assert bus.client.state("A") is None


def test_deltas_too_large_for_one_message_go_out_in_several_with_the_scans_seq() -> None:
    fbs = {f"FB{n}": state(1, 2) for n in range(9)}
    message = ScanDeltas(seq=4, cycle=1, t_ms=10, fbs=fbs)
    one = len(msgspec.json.encode(message))
    parts = [decode(data, ScanDeltas) for data in encode_parts(message, limit=one // 3)]
    assert len(parts) > 2 and {p.seq for p in parts} == {4}
    assert [fb for p in parts for fb in p.fbs] == list(fbs)
    assert all(len(msgspec.json.encode(p)) <= one // 3 for p in parts)


def test_a_scan_given_fb_by_fb_sends_a_message_every_part_with_the_scans_seq(
    bus: Bus,
) -> None:
    """``begin_scan``: the deltas leave in messages of ``part`` while the scan's others are
    still being given, each message with the scan's ``seq``; an unchanged FB sends nothing
    and the next scan's messages carry the next ``seq``; followers see every delta."""
    got: list[ScanDeltas] = []
    seen: dict[str, list[StepStateUpdate]] = {fb: [] for fb in FBS}
    for fb in FBS:
        bus.client.follow(fb, seen[fb].append)

    def on_sample(sample: zenoh.Sample) -> None:
        got.append(decode(sample.payload.to_bytes(), ScanDeltas))

    sub = bus.view.declare_subscriber("s7graph/cpu1/deltas", on_sample)
    try:
        deltas = bus.publisher.deltas
        assert deltas is not None and wait_until(deltas.read)
        out = bus.publisher.begin_scan(1, 10, part=2)
        assert out.add("A", state(1, 2)) and out.add("B", state(1, 2))
        assert bus.sent() == 1  # the first part left before the scan ended
        assert out.add("C", state(1, 2))
        quiet = msgspec.structs.replace(state(1, 2), events=[])
        assert not out.add("A", quiet)  # the same state without an event: no delta
        assert [fb for fb, _ in out.end()] == ["A", "B", "C"]
        assert bus.scan("A") == ["A"]
        assert wait_until(lambda: len(got) == 3)
        assert [(m.seq, list(m.fbs)) for m in got] == [(1, ["A", "B"]), (1, ["C"]), (2, ["A"])]
        assert wait_until(lambda: len(seen["A"]) == 2 and len(seen["C"]) == 1)
        with pytest.raises(KeyError, match="unknown FB 'Z'"):
            bus.publisher.begin_scan(2, 20).add("Z", state(2, 1))
    finally:
        sub.undeclare()  # type: ignore[no-untyped-call]


def test_a_follower_takes_the_states_of_a_cpu_that_started_anew(bus: Bus) -> None:
    """A restarted CPU counts its messages and each FB's changes from 1 again: a follower
    that kept the old counts took every new state for a stale one (``watch`` stayed silent
    for minutes after a restart) until the new counts passed the old."""
    seen: list[StepStateUpdate] = []
    bus.client.follow("A", seen.append)
    for _ in range(6):
        bus.scan("A", "B")
    assert wait_until(lambda: bool(seen) and seen[-1].seq == 6)
    bus.publisher.close()  # the CPU process ends; another starts on the same bus
    bus.publisher = BusPublisher(bus.cpu, "cpu1", {fb: layout(fb) for fb in FBS})
    bus.cycle = 0
    bus.scan("A")
    assert wait_until(lambda: (seen[-1].seq, seen[-1].cycle) == (1, 1))
    bus.scan("A")
    assert wait_until(lambda: (seen[-1].seq, seen[-1].cycle) == (2, 2))
