"""What the page's *Synchronization* shows of a report (docs/view.md, "Synchronization"): the
steps found, likely ones first, then the others with why they do not fit; an error as
it came; names escaped."""

from __future__ import annotations

from s7graph.web.bus.protocol import SyncReport, SyncStepInfo
from s7graph.web.view.drawing import BOX_W
from s7graph.web.view.sync_view import found, mark_segments, sync_html

REPORT = SyncReport(
    fb="Seq",
    cycle=7,
    state="RUN",
    mode="MAN",
    steps=[
        SyncStepInfo(number=1, name="Ready", sequence=1, done=[1]),
        SyncStepInfo(number=2, name="<b>Clamp</b>", sequence=1, fits=True, active=True),
        SyncStepInfo(number=3, name="Drill", sequence=1, fits=True, entered=True, likely=True),
        SyncStepInfo(number=4, name="Lift", sequence=2, interlock=False),
    ],
)


def test_the_steps_found_come_likely_first_then_in_chart_order() -> None:
    assert [s.number for s in found(REPORT)] == [3, 2]


def test_the_table_lists_the_found_steps_first_and_says_why_the_others_do_not_fit() -> None:
    shown = sync_html(REPORT)
    order = [shown.index(t) for t in ("S3 Drill", "S2 &lt;b&gt;Clamp", "S1 Ready", "S4 Lift")]
    assert order == sorted(order)
    assert "2 of 4 steps fit" in shown and "cycle 7 · RUN · MAN" in shown
    assert "done (T1 holds)" in shown and "interlock not held" in shown
    assert "<b>Clamp</b>" not in shown and "<b>active</b>" in shown


def test_an_error_is_shown_as_it_came_and_nothing_asked_says_what_the_button_does() -> None:
    assert "no answer &lt;here&gt;" in sync_html(SyncReport(error="no answer <here>"))
    assert "Find steps" in sync_html(None)


def test_a_frame_of_four_sides_stands_just_outside_each_step_found_that_is_drawn() -> None:
    segments = mark_segments({1: (0.0, 0.0), 2: (5.0, -3.0)}, [2, 9])  # S9 is not drawn
    assert segments.shape == (4, 2, 3)
    xs = sorted({float(x) for x in segments[:, :, 0].ravel()})
    assert xs[0] < 5.0 - BOX_W / 2 and xs[-1] > 5.0 + BOX_W / 2
    assert mark_segments({}, [1]).shape == (0, 2, 3)
