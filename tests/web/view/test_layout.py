"""Chart placement as S7-GRAPH draws it: a pure function from a chart to grid positions."""

from __future__ import annotations

from pathlib import Path

import pytest

from s7graph.sequencer.text.model import Chart, Sequence, Step, Transition
from s7graph.sequencer.text.parse import ChartSyntaxError, parse_chart
from s7graph.web.bus.protocol import ChartLayout
from s7graph.web.view.layout import place
from tests.paths import ROOT

pytestmark = pytest.mark.timeout(30)


def seq(
    number: int, steps: list[int], transitions: list[tuple], initial: int | None = None
) -> Sequence:
    first = initial if initial is not None else steps[0]
    return Sequence(
        number,
        f"Seq{number}",
        tuple(Step(n, f"S{n}", initial=n == first) for n in steps),
        tuple(Transition(t, "", tuple(src), tuple(dst)) for t, src, dst in transitions),
    )


def chart(*sequences: Sequence) -> Chart:
    return Chart("FB", sequences=sequences)


def test_a_linear_sequence_runs_top_down_in_one_column() -> None:
    p = place(chart(seq(1, [1, 2, 3], [(1, [1], [2]), (2, [2], [3])])))
    assert [(p.steps[n].x, p.steps[n].y) for n in (1, 2, 3)] == [(0, 0), (0, 2), (0, 4)]
    assert [(p.transitions[n].x, p.transitions[n].y) for n in (1, 2)] == [(0, 1), (0, 3)]
    assert all(len(link.points) == 2 for link in p.links)  # straight vertical lines


def test_alternative_branches_stand_side_by_side_and_converge_below_both() -> None:
    # S1 -T1-> S2 -T3-> S4 ; S1 -T2-> S3 -T4-> S4 (alternative divergence and convergence)
    c = chart(seq(1, [1, 2, 3, 4], [(1, [1], [2]), (2, [1], [3]), (3, [2], [4]), (4, [3], [4])]))
    p = place(c)
    assert p.steps[2].x == 0 and p.steps[3].x == 1
    assert p.steps[2].y == p.steps[3].y == 2
    assert p.transitions[1].y == p.transitions[2].y == 1
    assert p.steps[4].x == 0 and p.steps[4].y == 4
    divergence = [link for link in p.links if link.transition == 2 and len(link.points) == 4]
    assert divergence and divergence[0].points[1][1] == 0.5  # the line right under S1
    assert not any(link.double for link in p.links)


def test_simultaneous_branches_use_double_lines_and_join_below_the_longest() -> None:
    # S1 -T1-> (S2 | S3); S2 -T2-> S4; (S4, S3) -T3-> S5
    c = chart(
        seq(1, [1, 2, 3, 4, 5], [(1, [1], [2, 3]), (2, [2], [4]), (3, [4, 3], [5])]),
    )
    p = place(c)
    assert (p.steps[2].x, p.steps[3].x) == (0, 1)
    assert p.transitions[3].y > p.steps[4].y > p.steps[3].y - 1
    assert p.steps[5].y == p.transitions[3].y + 1
    doubles = [link for link in p.links if link.double]
    assert {link.transition for link in doubles} == {1, 3}


def test_a_jump_back_is_an_arrow_with_the_target_number_not_a_line() -> None:
    p = place(chart(seq(1, [1, 2], [(1, [1], [2]), (2, [2], [1])])))
    (jump,) = p.jumps
    assert (jump.transition, jump.target) == (2, 1)
    assert jump.x == p.transitions[2].x and jump.y > p.transitions[2].y
    (incoming,) = p.incoming_jumps
    assert (incoming.step, incoming.transition) == (1, 2)
    assert not any(link.transition == 2 and link.points[-1][1] < 2 for link in p.links)


def test_a_branch_stop_is_marked_under_its_transition() -> None:
    p = place(chart(seq(1, [1, 2], [(1, [1], [2]), (2, [2], [])])))
    (stop,) = p.stops
    assert stop.transition == 2 and stop.y > p.transitions[2].y


def test_sequences_are_columns_and_a_jump_between_them_is_an_arrow() -> None:
    c = chart(
        seq(1, [1, 2], [(1, [1], [2]), (2, [2], [10])]),
        seq(2, [10, 11], [(10, [10], [11]), (11, [11], [1])]),
    )
    p = place(c)
    first, second = p.sequences
    assert first.x1 < second.x0
    assert p.steps[10].x == second.x0 and p.steps[10].y == 0
    assert {(j.transition, j.target) for j in p.jumps} == {(2, 10), (11, 1)}


def test_steps_unreachable_from_the_initial_step_still_get_a_place() -> None:
    p = place(chart(seq(1, [1, 2, 3], [(1, [1], [2])])))
    assert set(p.steps) == {1, 2, 3}
    assert p.steps[3].x != p.steps[1].x


def test_placement_is_the_same_for_a_chart_and_its_layout_message() -> None:
    c = chart(seq(1, [1, 2, 3], [(1, [1], [2, 3]), (2, [2, 3], [1])]))
    assert place(c) == place(ChartLayout.from_chart(c))
    assert place(c) == place(c)  # deterministic


def test_no_two_steps_share_a_place() -> None:
    c = chart(
        seq(
            1,
            [1, 2, 3, 4, 5, 6, 7],
            [
                (1, [1], [2]),
                (2, [2], [3]),
                (3, [2], [4]),
                (4, [3], [5, 6]),
                (5, [5, 6], [7]),
                (6, [4], [7]),
                (7, [7], [1]),
            ],
        )
    )
    p = place(c)
    spots = [(s.x, s.y) for s in p.steps.values()]
    assert len(spots) == len(set(spots))


def test_an_imported_beremiz_chart_lays_out_without_a_staircase() -> None:
    """Beremiz's traffic light: every step's first (highest-priority) branch jumps back to
    the start, the second goes on. The path that goes on keeps its lane; the jumps stand
    in one lane beside it, free at their rows — two lanes, not one more per step."""
    from tests.sequencer.exchange.helpers import imported

    chart = imported("plcopen/beremiz_traffic_light.xml").chart
    assert chart is not None
    p = place(chart)
    main = [1, 2, 3, 4, 5, 6]  # Standstill, ORANGE, RED, PEDESTRIAN_GREEN/RED, GREEN
    assert {p.steps[n].x for n in main} == {0.0}
    assert [p.steps[n].y for n in main] == sorted(p.steps[n].y for n in main)
    jumps_back = [2, 4, 6, 8, 11]  # NOT SWITCH_BUTTON: back to S1
    assert {p.transitions[n].x for n in jumps_back} == {1.0}
    assert p.width <= 2.0


@pytest.mark.parametrize(
    "relative",
    [
        "plcopen/beremiz_traffic_light.xml",
        "plcopen/beremiz_test_svgui.xml",
        "plcopen/beremiz_first_steps.xml",
        "iec-text/matiec_annexF_gravel.txt",
    ],
)
def test_imported_charts_stand_in_no_more_lanes_than_their_widest_branching(
    relative: str,
) -> None:
    """No sequence of an imported chart is wider than its widest divergence plus one lane
    for its jumps back (a staircase would be as wide as the chart is long)."""
    from tests.sequencer.exchange.helpers import imported

    chart = imported(relative).chart
    assert chart is not None
    p = place(chart)
    for q in chart.sequences:
        leaving: dict[int, int] = {}
        for t in q.transitions:
            for s in t.sources:
                leaving[s] = leaving.get(s, 0) + 1
        widest = max([*leaving.values(), *(len(t.targets) for t in q.transitions), 1])
        column = next(c for c in p.sequences if c.number == q.number)
        assert column.x1 - column.x0 + 1 <= widest + 1, (q.number, column)


def _charts() -> list[Path]:
    return sorted([*ROOT.glob("examples/*/*.s7g"), *ROOT.glob("tests/sequencer/*/*.s7g")])


@pytest.mark.parametrize("path", _charts(), ids=lambda p: p.name)
def test_every_chart_is_placed_with_no_two_elements_in_one_place(path: Path) -> None:
    """Every chart the tests and examples hold (the broken ones too: a join of two
    alternatives, a branch that jumps back beside a join) is placed, each step and each
    transition in a place of its own."""
    try:
        c = parse_chart(path.read_text(encoding="utf-8"), str(path))
    except ChartSyntaxError:
        pytest.skip("does not parse")
    p = place(c)
    spots = [(s.x, s.y) for s in p.steps.values()] + [(t.x, t.y) for t in p.transitions.values()]
    assert len(spots) == len(set(spots))
