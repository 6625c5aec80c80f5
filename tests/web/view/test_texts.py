"""The panel's texts (``web.view.texts``): the permanent instructions with their values."""

from __future__ import annotations

from s7graph.web.bus.protocol import ChartLayout, PermanentInfo, StepStateUpdate
from s7graph.web.view.status_layer import VALUE_FALSE, VALUE_TRUE
from s7graph.web.view.texts import permanent_html


def layout(*permanent: PermanentInfo) -> ChartLayout:
    return ChartLayout(fb="FB", steps=[], transitions=[], sequences=[], permanent=list(permanent))


def hex_of(rgb: tuple[int, int, int]) -> str:
    return "#{:02x}{:02x}{:02x}".format(*rgb)


def test_the_permanent_instructions_are_listed_under_their_place_with_their_values() -> None:
    chart = layout(
        PermanentInfo(place="after", text='S "Lamp" := "Trip";', watch="Lamp"),
        PermanentInfo(place="before", text="low := level < 10;", watch="low"),
        PermanentInfo(place="after", text="CALL FC 3;"),
        PermanentInfo(place="after", text="n := n + 1;", watch="n"),
    )
    update = StepStateUpdate(
        cycle=1, t_ms=10, mode="AUTO", active=[], values={"low": True, "Lamp": False, "n": 7}
    )
    html = permanent_html(chart, update)
    order = ["Before the sequences", "low := level &lt; 10;", "After the sequences", "Lamp"]
    assert [html.index(part) for part in order] == sorted(html.index(part) for part in order)
    assert f'background:{hex_of(VALUE_TRUE)};padding:0 0.3em">TRUE' in html  # low
    assert f'background:{hex_of(VALUE_FALSE)};padding:0 0.3em">FALSE' in html  # Lamp
    assert '">7</span>' in html
    waiting = permanent_html(chart, None)  # before the first scan: the texts, no values
    assert "low := level &lt; 10;" in waiting and "TRUE" not in waiting and "FALSE" not in waiting


def test_a_chart_without_permanent_instructions_has_no_list() -> None:
    assert permanent_html(layout(), None) == ""
