"""``LiveGraph.changed``: the scan thread's cheap path builds an update only when the FB may
have changed — judged from the FB's own events, pins, words and step times — and the deltas
that leave are exactly those of building every scan and comparing whole states."""

from __future__ import annotations

import random
from collections.abc import Iterator
from pathlib import Path

import pytest

from s7graph.web.bus.live import PROBE, WASTED, LiveGraph, watch_names
from s7graph.web.bus.protocol import Command, StepStateUpdate
from tests.web.helpers import chart_session

# T1's two contacts change without a switch while "Start" is off ("Full" toggling): a
# change of CRIT alone; S2 has an interlock and a supervision on its U.
CHART = """\
FUNCTION_BLOCK "Fill" FB 1 DB 1
  PARAMETERS := STANDARD;
  ACK_REQUIRED := TRUE;
SYMBOLS
  "Start" : I0.0 : BOOL;
  "Full" : I0.1 : BOOL;
  "Door" : I0.2 : BOOL;
  "Pump" : Q0.0 : BOOL;
END_SYMBOLS
SEQUENCE 1 "Main"
  INITIAL_STEP S1 "Idle":
  END_STEP
  STEP S2 "Fill":
    INTERLOCK := "Door";
    SUPERVISION := S2.U > T#1S;
    N C "Pump";
  END_STEP
  STEP S3 "Done":
  END_STEP
  TRANSITION T1 "Go" FROM S1 TO S2 := "Start" AND NOT "Full";
  TRANSITION T2 "Full" FROM S2 TO S3 := "Full";
  TRANSITION T3 "Back" FROM S3 TO S1 := NOT "Start";
END_SEQUENCE
END_FUNCTION_BLOCK
"""


class Side:
    """A session of the chart with its LiveGraph and the deltas a publisher would send."""

    def __init__(self, tmp_path: Path, *, cheap: bool) -> None:
        tmp_path.mkdir()
        self.session, table, self.clock, self.store = chart_session(tmp_path, "fill.s7g", CHART)
        self.live = LiveGraph(
            self.session.graph,
            read=self.session.get,
            reader=self.session.reader,
            watch=watch_names(table),
        )
        self.cheap = cheap
        self.last: StepStateUpdate | None = None
        self.deltas: list[StepStateUpdate] = []
        self.session.start()

    def scan(self, ms: float = 10.0) -> StepStateUpdate | None:
        """One scan; the delta it sends (None: none)."""
        self.clock.advance(ms)
        record = self.session.scan()
        update = self.live.changed(record) if self.cheap else self.live.update(record)
        if update is None or not update.changed_from(self.last):
            return None
        self.last = update
        self.deltas.append(update)
        return update

    def cmd(self, op: str, **args: object) -> bool:
        command = Command(op=op, fb="Fill", user="alice", args=args)  # type: ignore[arg-type]
        return self.live.apply(command)[0]


@pytest.fixture
def side(tmp_path: Path) -> Iterator[Side]:
    s = Side(tmp_path / "cheap", cheap=True)
    try:
        yield s
    finally:
        s.store.close()


def test_a_scan_that_changes_nothing_builds_nothing(side: Side) -> None:
    assert side.scan() is not None  # the first scan: the whole state
    quiet = side.live.quiet
    for _ in range(20):  # S1 waits for "Start": nothing moves but its T, under a second
        assert side.scan() is None
    assert side.live.quiet == quiet + 20
    assert side.live.step_details.built == 1


def test_what_changes_without_a_step_event_still_makes_a_delta(side: Side) -> None:
    side.scan()
    side.session.set("Full", True)  # T1's contact NOT "Full" opens: CRIT alone changes
    update = side.scan()
    assert update is not None and update.events == [] and update.active == [1]
    assert [c.ok for c in update.details[0].transitions[0].contacts] == [False, False]
    assert update.values["Full"] is True  # a watched operand
    assert side.scan() is None
    for _ in range(96):  # S1's T reaches 1 s in scan 100: a whole second is a change
        assert side.scan() is None
    update = side.scan()
    assert update is not None and (update.cycle, update.details[0].t_ms) == (100, 1000)
    assert side.cmd("halt", on=True)  # a level pin held by a command
    update = side.scan()
    assert update is not None and update.halted and update.overrides == {"HALT_SQ": True}
    assert side.cmd("mode", mode="MAN")
    update = side.scan()
    assert update is not None and update.mode == "MAN"


def test_the_scan_after_a_switch_builds_nothing_when_only_the_fired_tt_clears(
    side: Side,
) -> None:
    """The transition that fired clears its TT in the next scan; no view shows the TT of a
    transition whose step is no longer active, so that scan builds no update."""
    side.scan()
    side.session.set("Door", True)
    side.session.set("Start", True)
    update = side.scan()
    assert update is not None and update.active == [2] and update.events
    quiet = side.live.quiet
    for _ in range(5):
        assert side.scan() is None
    assert side.live.quiet == quiet + 5


def test_the_cheap_path_sends_exactly_the_deltas_of_the_whole_state_compare(
    tmp_path: Path,
) -> None:
    """800 scans of random inputs, scan times and commands on two sessions of one chart:
    one LiveGraph builds every scan and compares whole states, the other takes the cheap
    path; both send the same deltas, and the cheap one builds far fewer updates."""
    full, cheap = Side(tmp_path / "full", cheap=False), Side(tmp_path / "cheap", cheap=True)
    rng = random.Random(7)
    commands = [
        ("mode", {"mode": "MAN"}),
        ("mode", {"mode": "AUTO"}),
        ("halt", {"on": True}),
        ("halt", {"on": False}),
        ("en_il", {"on": False}),
        ("en_il", {"on": True}),
        ("ack", {}),
        ("step_on", {"step": 3}),
    ]
    try:
        for n in range(800):
            if rng.random() < 0.08:
                name = rng.choice(("Start", "Full", "Door"))
                value = not full.session.get(name)
                for s in (full, cheap):
                    s.session.set(name, value)
            if rng.random() < 0.02:
                op, args = rng.choice(commands)
                assert full.cmd(op, **args) == cheap.cmd(op, **args)
            ms = rng.choice((1.0, 10.0, 10.0, 40.0))
            assert full.scan(ms) == cheap.scan(ms), f"scan {n}"
        assert full.deltas == cheap.deltas and len(full.deltas) > 50
        assert cheap.live.quiet > 400
    finally:
        full.store.close()
        cheap.store.close()


def test_an_online_change_or_a_new_state_builds_the_update_again(side: Side) -> None:
    side.scan()
    assert side.scan() is None
    live = side.live
    live.switch(live.prepare(live.cc, version=2))  # a new chart version described
    assert live.changed(side.session.scan()) is not None
    assert live.changed(side.session.scan()) is None


def test_an_fb_that_changes_every_scan_stops_keeping_copies_until_it_is_quiet(
    tmp_path: Path,
) -> None:
    """ "Full" toggled every scan changes T1's CRIT every scan: after ``WASTED`` copies that
    each found a change, only every ``PROBE``-th scan keeps one; once the FB is quiet
    again, the next probe's copy makes its scans build nothing. The deltas are those of
    the whole-state compare throughout."""
    full, cheap = Side(tmp_path / "full", cheap=False), Side(tmp_path / "cheap", cheap=True)
    try:
        for s in (full, cheap):
            s.scan()
        copies = cheap.live.copies
        for n in range(6 * PROBE):  # S1's T stays under a second (100 scans)
            for s in (full, cheap):
                s.session.set("Full", n % 2 == 0)
            assert full.scan() == cheap.scan() is not None, f"scan {n}"
        assert cheap.live.copies - copies <= WASTED + 6
        quiet = cheap.live.quiet
        for n in range(2 * PROBE):
            assert full.scan() == cheap.scan() is None, f"quiet scan {n}"
        assert cheap.live.quiet - quiet >= PROBE - 1
        assert full.deltas == cheap.deltas
    finally:
        full.store.close()
        cheap.store.close()
