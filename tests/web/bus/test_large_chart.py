"""A chart too large for one bus message goes in parts (docs/bus.md, "A large chart"): the
1,000-step chart of ``bench/big_charts.py`` (every step with its action table, 2.7 MB of
JSON) is served as a head and parts each within the message limit; the client, a view's
subscription to a new version and the browser view all get the whole layout."""

from __future__ import annotations

import threading
from collections.abc import Iterator
from dataclasses import dataclass

import msgspec
import pytest
import zenoh

from bench.big_charts import huge_chart
from s7graph.sequencer.text.parse import parse_chart
from s7graph.web.bus.client import BusClient
from s7graph.web.bus.cpu_side import CpuSide
from s7graph.web.bus.protocol import (
    MAX_MESSAGE_BYTES,
    MAX_PERMANENT,
    PART_BYTES,
    ChartLayout,
    ChartPart,
    PermanentInfo,
    ProtocolError,
    encode,
    join_layout,
    layout_problem,
    split_layout,
)
from s7graph.web.bus.session import BusEnds, open_session
from s7graph.web.view.edge import ViewSide
from tests.web.helpers import wait_until

pytestmark = pytest.mark.timeout(240)
FB = "Seq_drill"


@pytest.fixture(scope="module")
def big() -> ChartLayout:
    """The 1,000-step chart's layout, version 1."""
    return ChartLayout.from_chart(parse_chart(huge_chart()), version=1)


def test_a_layout_over_the_message_limit_is_cut_into_parts_and_joined_whole(
    big: ChartLayout,
) -> None:
    assert len(big.steps) == 1000 and len(encode(big)) > MAX_MESSAGE_BYTES
    assert sum(len(s.actions) for s in big.steps) > 30_000
    head, parts = split_layout(big)
    assert head.parts == len(parts) > 1 and len(encode(head)) <= PART_BYTES
    assert all(len(encode(p)) <= PART_BYTES for p in parts)
    assert [s.number for s in head.steps] == [s.number for s in big.steps]  # the structure
    assert not any(s.actions for s in head.steps) and head.transitions == big.transitions
    assert join_layout(head, list(reversed(parts))) == big
    assert layout_problem(big) is None

    small_head, small_parts = split_layout(big, limit=50_000)  # the head itself too large
    assert small_head.steps == [] and small_head.transitions == []
    assert join_layout(small_head, small_parts) == big

    with pytest.raises(ProtocolError, match=f"{len(parts) - 1} of {len(parts)} parts"):
        join_layout(head, parts[1:])
    older = msgspec.structs.replace(parts[0], version=0)
    with pytest.raises(ProtocolError, match="part 0 is of Seq_drill version 0, not"):
        join_layout(head, [older, *parts[1:]])
    whole, none = split_layout(ChartLayout(fb="S", steps=[], transitions=[], sequences=[]))
    assert none == [] and whole.parts == 0


def test_the_permanent_instructions_travel_in_the_head_of_a_layout_in_parts(
    big: ChartLayout,
) -> None:
    permanent = [
        PermanentInfo(place="after", text=f"M{i}.0 := I{i}.0 AND NOT I{i}.1;", watch=f"M{i}.0")
        for i in range(MAX_PERMANENT)
    ]
    layout = msgspec.structs.replace(big, permanent=permanent)
    for limit in (PART_BYTES, 50_000):  # the head with its steps, and without them
        head, parts = split_layout(layout, limit=limit)
        assert head.permanent == permanent and parts
        assert join_layout(head, parts) == layout


@dataclass
class Bus:
    side: CpuSide
    session: zenoh.Session
    client: BusClient


@pytest.fixture
def bus(big: ChartLayout) -> Iterator[Bus]:
    side = CpuSide({FB: big}, cpu="cpu1")
    try:
        with (
            open_session(connect=[side.endpoint]) as session,
            BusClient(session, "cpu1") as client,
        ):
            yield Bus(side, session, client)
    finally:
        side.close()


def test_the_client_and_a_subscriber_get_a_large_chart_whole(big: ChartLayout, bus: Bus) -> None:
    assert wait_until(lambda: bus.client.chart(FB) is not None, 30)
    assert bus.client.chart(FB) == big
    got: list[ChartLayout] = []
    came = threading.Event()

    def on_chart(layout: ChartLayout) -> None:
        got.append(layout)
        came.set()

    bus.client.on_chart(FB, on_chart)
    assert not came.wait(0.5)  # the subscription is in place: nothing until a new version
    second = msgspec.structs.replace(big, version=2, steps=[*big.steps[:-1], big.steps[0]])
    bus.side.publisher.set_chart(FB, second)
    assert came.wait(30)
    assert got[-1] == second and got[-1].parts == 0
    assert bus.client.chart(FB) == second

    key = f"s7graph/cpu1/fb/{FB}/chart/part"
    for bad in ("", "?k=x", "?k=99"):
        replies = list(bus.session.get(key + bad, timeout=5))
        assert len(replies) == 1 and replies[0].ok is None
        assert "give a part, 0 to" in replies[0].err.payload.to_string()
    part = next(iter(bus.session.get(key + "?k=0", timeout=5))).ok
    assert part is not None and len(part.payload.to_bytes()) <= PART_BYTES
    assert msgspec.json.decode(part.payload.to_bytes(), type=ChartPart).k == 0
    # a wildcard gets every read-only key's message, none of them an error (docs/bus.md)
    every = list(bus.session.get("s7graph/**", target=zenoh.QueryTarget.ALL, timeout=5))
    assert every and all(r.ok is not None for r in every)
    assert not any(str(r.ok.key_expr).endswith("/part") for r in every if r.ok is not None)


def test_a_chart_in_one_message_says_it_has_no_parts(bus: Bus) -> None:
    """A chart small enough for one message has no parts: asking for one says so."""
    small = ChartLayout(fb=FB, version=2, steps=[], transitions=[], sequences=[])
    bus.side.publisher.set_chart(FB, small)
    assert wait_until(lambda: bus.client.chart(FB) == small, 30)
    (reply,) = list(bus.session.get(f"s7graph/cpu1/fb/{FB}/chart/part?k=0", timeout=5))
    assert reply.ok is None
    assert reply.err.payload.to_string() == (
        "the chart is whole, in one message: read chart, it has no parts"
    )


def test_the_browser_view_opens_a_1000_step_chart_whole(big: ChartLayout, bus: Bus) -> None:
    view = ViewSide(cpu="cpu1", fb=FB, ends=BusEnds(connect=[bus.side.endpoint]), port=0)
    try:
        assert view.view.layout == big
        assert sum(len(s.actions) for s in view.view.layout.steps) > 30_000
    finally:
        view.close()
