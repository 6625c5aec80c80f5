"""Where an empty place of the edited chart inserts, and how a step's row table pages
(docs/online-change.md, "Editing in the browser"): pure rules, no page."""

from __future__ import annotations

from s7graph.sequencer.text.parse import parse_chart
from s7graph.web.bus.protocol import ChartLayout
from s7graph.web.view.drawing import BOX_W, Picture, picture
from s7graph.web.view.editor_place import column_transition
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
