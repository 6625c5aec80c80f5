"""Where an empty place of the edited chart inserts, how a step's row table pages, and where
the form floats beside the element it edits (docs/online-change.md, "Editing in the
browser"): pure rules, no page."""

from __future__ import annotations

from s7graph.sequencer.text.elements import StepRef, TransitionRef
from s7graph.sequencer.text.parse import parse_chart
from s7graph.web.bus.protocol import ChartLayout
from s7graph.web.view.drawing import BAR_W, BOX_H, BOX_W, Picture, picture, same_canvas
from s7graph.web.view.editor_place import (
    GAP,
    MIN_WIDTH,
    PLACE_WIDTH,
    Box,
    Placed,
    column_transition,
    element_box,
    place_window,
    screen_box,
)
from s7graph.web.view.editor_rows import pages_of
from s7graph.web.view.layout import place
from s7graph.web.view.texts import rows_note
from tests.web.bus.test_online_change import CHART


def drawn() -> Picture:
    return picture(place(ChartLayout.from_chart(parse_chart(CHART, "fill.s7g"))))


def test_an_empty_place_in_a_column_inserts_after_the_transition_above_it() -> None:
    pic = drawn()
    x, _ = pic.steps[1]
    below = {n: pic.transitions[n][1] - 0.3 for n in (1, 2, 3)}
    assert [column_transition(pic, x, y) for y in below.values()] == [1, 2, 3]
    assert column_transition(pic, x + BOX_W / 3, below[3]) == 3  # within the box's width


def test_an_empty_place_above_or_beside_every_column_inserts_in_the_chart() -> None:
    pic = drawn()
    x, y = pic.steps[1]
    assert column_transition(pic, x, y + 1.0) is None  # above the first transition
    assert column_transition(pic, x + 2 * BOX_W, pic.transitions[3][1] - 0.3) is None


def test_the_row_table_pages_by_sixteen_and_says_which_rows_it_shows() -> None:
    assert pages_of(0) == ["1–16"] and pages_of(5) == ["1–5"] and pages_of(16) == ["1–16"]
    assert pages_of(17) == ["1–16", "17–17"]
    assert pages_of(40) == ["1–16", "17–32", "33–40"]
    assert "rows 17–21 of 21" in rows_note(5, 21, 16)
    assert "3 action rows" in rows_note(3, 3)
    assert "no action rows" in rows_note(0, 0)


CANVAS = (492.0, 800.0)  # a 1280 × 800 page with the editor's panel left, the page's right


def step_at(left: float, top: float) -> Box:
    """A step box at the default zoom (55 pixels per scene unit) on the canvas."""
    return (left, top, left + 104.0, top + 33.0)


def overlaps(p: Placed, box: Box) -> bool:
    x0, y0, x1, y1 = box
    return p.left < x1 and x0 < p.left + p.width and p.top < y1 and y0 < p.top + p.height


def test_the_form_floats_right_of_an_element_with_room_there() -> None:
    box = step_at(20, 300)
    placed = place_window(box, CANVAS)
    assert placed.side == "right" and placed.left == 20 + 104 + GAP
    assert placed.width == PLACE_WIDTH and placed.pan == (0.0, 0.0)
    assert not overlaps(placed, box)


def test_an_element_at_the_right_edge_has_the_form_on_its_left() -> None:
    box = step_at(492 - 110, 300)
    placed = place_window(box, CANVAS)
    assert placed.side == "left" and placed.left + placed.width == 492 - 110 - GAP
    assert not overlaps(placed, box)


def test_an_element_at_the_left_edge_has_the_form_on_its_right() -> None:
    box = step_at(2, 40)
    placed = place_window(box, (800.0, 600.0))
    assert placed.side == "right" and placed.left == 2 + 104 + GAP
    assert placed.top >= 8 and not overlaps(placed, box)


def test_on_a_narrow_canvas_the_form_narrows_on_the_roomier_side() -> None:
    box = step_at(260, 300)  # 128 free on its right, 248 on its left
    placed = place_window(box, CANVAS)
    assert placed.side == "left" and MIN_WIDTH <= placed.width < PLACE_WIDTH
    assert placed.left >= 0 and not overlaps(placed, box)


def test_with_no_room_beside_the_chart_pans_to_make_room_when_placing_is_asked() -> None:
    box = step_at(194, 200)  # the middle of the canvas: under 240 pixels on either side
    placed = place_window(box, CANVAS, reveal=True)
    dx, dy = placed.pan
    assert dy == 0 and -60 < dx < 0  # the least way: 240 pixels free on its right
    moved = (box[0] + dx, box[1], box[2] + dx, box[3])
    assert placed.side == "right" and placed.width == MIN_WIDTH
    assert placed.left + placed.width <= 492 and not overlaps(placed, moved)


def test_with_no_room_beside_the_form_goes_below_or_above_the_element() -> None:
    box = step_at(194, 200)  # following the user's panning: the chart stays
    below = place_window(box, CANVAS)
    assert below.side == "below" and below.top == 233 + GAP and not overlaps(below, box)
    assert below.top + below.height <= 800 and below.pan == (0.0, 0.0)
    low = step_at(194, 700)  # near the bottom: above it
    above = place_window(low, CANVAS)
    assert above.side == "above" and above.top + above.height == 700 - GAP
    assert not overlaps(above, low)
    narrow = step_at(30, 200)  # a canvas narrower than a step and the form
    assert place_window(narrow, (300.0, 800.0), reveal=True).side == "below"


def test_with_no_room_at_all_the_form_covers_the_element_and_the_chart_pans_it_aside() -> None:
    box = step_at(150, 120)
    canvas = (300.0, 300.0)  # too narrow beside it, too low above and below
    placed = place_window(box, canvas, reveal=True)
    assert placed.side == "over" and overlaps(placed, box)
    assert placed.left + placed.width == 300 and placed.width == MIN_WIDTH
    dx, dy = placed.pan
    assert (box[0] + dx, dy) == (0.0, 0.0)  # to the canvas's left edge, the part left free
    assert place_window(box, canvas).pan == (0.0, 0.0)  # not while following the user


def test_an_element_off_the_canvas_is_panned_onto_it_only_when_placing_is_asked() -> None:
    box = step_at(600, 300)  # right of a 492 pixels wide canvas
    placed = place_window(box, CANVAS, reveal=True)
    dx, dy = placed.pan
    assert dx == 492 - 8 - 704 and dy == 0  # the least way: at the right edge, inside
    moved = (box[0] + dx, box[1], box[2] + dx, box[3])
    assert placed.side == "left" and not overlaps(placed, moved)
    assert place_window(box, CANVAS).pan == (0.0, 0.0)


def test_a_transitions_box_holds_its_text_and_a_steps_its_box() -> None:
    pic = drawn()
    x, y = pic.steps[2]
    assert element_box(pic, StepRef(2), (0.0, 0.0)) == (
        x - BOX_W / 2,
        y - BOX_H / 2,
        x + BOX_W / 2,
        y + BOX_H / 2,
    )
    tx, ty = pic.transitions[2]  # "T2 Full", "full": the text, not the lane it may fill
    box = element_box(pic, TransitionRef(2), (0.0, -2000.0))
    assert box is not None and box[0] == tx - BOX_W / 2 and box[2] > tx + BAR_W / 2 + 0.3
    assert box[2] - box[0] < pic.targets[2][2] and box[1] < -2000 + ty < box[3]
    assert element_box(pic, StepRef(99), (0.0, 0.0)) is None
    assert element_box(pic, (1.0, 2.0), (0.0, 0.0)) == (1.0, 2.0, 1.0, 2.0)


def test_a_scene_box_shows_on_the_canvas_around_the_cameras_point_y_down() -> None:
    left, top, right, bottom = screen_box((1.0, -1.0, 2.0, 0.5), (0.0, 0.0, 10.0), (400, 300))
    assert (left, top, right, bottom) == (210.0, 145.0, 220.0, 160.0)


def test_a_canvas_drawn_at_a_lower_resolution_is_the_same_canvas() -> None:
    assert same_canvas((492, 800), (369, 600))  # viser's page at 0.75 of its pixel ratio
    assert same_canvas((492, 800), (492, 800)) and same_canvas((1001, 800), (750, 600))
    assert not same_canvas((492, 800), (876, 800))  # a panel undocked: another canvas
    assert not same_canvas((492, 800), (492, 700)) and not same_canvas((0, 0), (492, 800))
