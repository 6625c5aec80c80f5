"""``publish_fbs``: the deltas of a CPU's several GRAPH FBs after a scan, on a real zenoh
over a unix socket — the FBs whose steps switched go out first, each FB asked once, the
messages every ``part`` changed FBs, and a view ends with every FB's whole state."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from s7graph.engine.clock import VirtualClock
from s7graph.engine.cpu import Cpu
from s7graph.engine.record import ScanRecord
from s7graph.sequencer.compile import compile_chart
from s7graph.sequencer.fb import GraphFB, install_all
from s7graph.sequencer.text.parse import parse_chart
from s7graph.web.bus.client import BusClient
from s7graph.web.bus.fb_deltas import publish_fbs
from s7graph.web.bus.live import LiveGraph
from s7graph.web.bus.protocol import StepStateUpdate
from s7graph.web.bus.publisher import BusPublisher
from s7graph.web.bus.scan_events import ScanEvents
from s7graph.web.bus.session import open_session
from tests.web.helpers import wait_until

pytestmark = pytest.mark.timeout(60)


def chart(fb: int) -> str:
    """FB ``fb``: S1 → S2 when I0.<fb> and I1.<fb> (two contacts: one alone changes CRIT)."""
    return f"""\
FUNCTION_BLOCK "Line{fb}" FB {fb} DB {fb}
  PARAMETERS := STANDARD;
SEQUENCE 1 "Main"
  INITIAL_STEP S1 "Idle":
  END_STEP
  STEP S2 "Run":
  END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.{fb} AND I1.{fb};
  TRANSITION T2 FROM S2 TO S1 := NOT I0.{fb};
END_SEQUENCE
END_FUNCTION_BLOCK
"""


class Plant:
    """Three GraphFBs on one CPU, each seen by a LiveGraph, and a view following them."""

    def __init__(self, cpu_session: object, view_session: object) -> None:
        self.clock = VirtualClock()
        self.cpu = Cpu(self.clock)
        graphs = [GraphFB(compile_chart(parse_chart(chart(n), f"<FB{n}>"))) for n in (1, 2, 3)]
        install_all(self.cpu, graphs)
        self.cpu.start("warm")
        events = ScanEvents()
        self.lives = [LiveGraph(g, events=events) for g in graphs]
        charts = {live.fb: live.layout for live in self.lives}
        self.publisher = BusPublisher(cpu_session, "cpu1", charts)  # type: ignore[arg-type]
        self.client = BusClient(view_session, "cpu1")  # type: ignore[arg-type]
        self.seen: dict[str, list[StepStateUpdate]] = {fb: [] for fb in charts}
        for fb in charts:
            self.client.follow(fb, self.seen[fb].append)

    def scan(self, *, part: int = 16, **inputs: int) -> list[str]:
        """One scan with the input bytes ``IB0``/``IB1`` given; the FBs that changed."""
        mem = self.cpu.mem
        for name, value in inputs.items():
            mem.periph_in[int(name[2:])] = value
        self.clock.advance(10)
        record = self.cpu.scan()
        return [fb for fb, _ in publish_fbs(self.publisher, self.lives, record, part=part)]


@pytest.fixture
def plant(tmp_path: Path) -> Iterator[Plant]:
    endpoint = f"unixsock-stream/{tmp_path}/bus.sock"
    with open_session(listen=[endpoint]) as cpu, open_session(connect=[endpoint]) as view:
        p = Plant(cpu, view)
        try:
            yield p
        finally:
            p.client.close()
            p.publisher.close()


def test_the_fbs_whose_steps_switched_go_out_before_those_that_only_refreshed(
    plant: Plant,
) -> None:
    assert plant.scan() == ["Line1", "Line2", "Line3"]  # the first scan: every whole state
    assert plant.scan() == []  # nothing changed: nothing sent
    # Line1's first contact closes (CRIT alone); Line3's both: it switches to S2
    changed = plant.scan(part=1, IB0=0b1010, IB1=0b1000)
    assert changed == ["Line3", "Line1"]
    assert plant.scan(part=1) == ["Line3"]  # T2 of its new step evaluated: its CRIT
    assert plant.scan(part=1) == []
    assert wait_until(lambda: [len(plant.seen[fb]) for fb in plant.seen] == [2, 1, 3])
    line1, line3 = plant.seen["Line1"][-1], plant.seen["Line3"][-2]
    assert (line1.active, line1.events, line3.active) == ([1], [], [2])
    assert line3.events and plant.seen["Line3"][-1].active == [2]
    assert [c.ok for c in line1.details[0].transitions[0].contacts] == [True, False]


def test_each_fb_is_asked_once_per_scan_whatever_its_order(plant: Plant) -> None:
    asked: list[str] = []
    for live in plant.lives:
        changed = live.changed

        def counted(record: ScanRecord, fb: str = live.fb, changed: Any = changed) -> Any:
            asked.append(fb)
            return changed(record)

        live.changed = counted  # type: ignore[method-assign]
    plant.scan()
    for n in range(40):  # Line1 and Line3 switch back and forth, Line2 every other scan
        on = 0b1110 if n % 2 else 0b1010
        asked.clear()
        plant.scan(part=2, IB0=on, IB1=on)
        assert sorted(asked) == ["Line1", "Line2", "Line3"], f"scan {n}"
    assert wait_until(lambda: plant.publisher.outbox.pending() == 0)
    for live in plant.lives:  # the view ends where the FB is
        st = live.graph.state
        assert plant.seen[live.fb][-1].active == sorted(
            live.graph.cc.step_numbers[i] for i in st.active
        )
