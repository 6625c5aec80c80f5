"""The live view's event list names each step as the chart it belongs to names it, also
across an online change whose first scans reach the view before the new chart does (the
CPU publishes the chart after the swap, the scan thread its next scan at once)."""

from __future__ import annotations

from s7graph.sequencer.text.model import Chart, Sequence, Step, Transition
from s7graph.web.bus.protocol import ChartLayout, StepStateUpdate
from s7graph.web.view.chart_view import ChartView, make_server
from tests.web.helpers import wait_until


def chain(names: dict[int, str]) -> Chart:
    numbers = list(names)
    steps = tuple(Step(n, name, initial=i == 0) for i, (n, name) in enumerate(names.items()))
    transitions = tuple(
        Transition(i + 1, f"T{i + 1}", (n,), (numbers[(i + 1) % len(numbers)],))
        for i, n in enumerate(numbers)
    )
    return Chart("Seq", sequences=(Sequence(1, "Chain", steps, transitions),))


def update(cycle: int, active: list[int], events: list[tuple[str, int]]) -> StepStateUpdate:
    return StepStateUpdate(cycle=cycle, t_ms=cycle * 10, mode="AUTO", active=active, events=events)  # type: ignore[arg-type]


def test_events_of_a_new_step_that_come_before_its_chart_are_named_by_it() -> None:
    old = ChartLayout.from_chart(chain({1: "Idle", 6: "Six", 7: "Seven"}), version=1)
    new = ChartLayout.from_chart(chain({1: "Idle", 6: "Six", 8: "Eight", 7: "Seven"}), version=2)
    server, _ = make_server(port=0)
    view = ChartView(server, old, lambda c: None)  # type: ignore[arg-type, return-value]
    try:
        view.apply(update(1, [6], [("S1", 6)]))
        view.apply(update(2, [8], [("S0", 6), ("S1", 8)]))  # the new chart's first scan
        assert view.events()[0] == "cycle 2: S1 S8"  # not yet known: no name
        view.apply_chart(new)
        assert view.events() == ["cycle 2: S1 S8 Eight", "cycle 2: S0 S6 Six", "cycle 1: S1 S6 Six"]
        view.apply(update(3, [7], [("S0", 8), ("S1", 7)]))  # named at once, drawn or not
        assert view.events()[:2] == ["cycle 3: S1 S7 Seven", "cycle 3: S0 S8 Eight"]
        assert wait_until(lambda: sorted(view.boxes) == [1, 6, 7, 8])
        view.apply(update(4, [1], [("S0", 7), ("S1", 1)]))
        assert view.events()[0] == "cycle 4: S1 S1 Idle"
    finally:
        view.close()
        server.stop()
