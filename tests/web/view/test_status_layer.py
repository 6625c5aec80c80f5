"""The status view's live layer (``web.view.status_layer``) without a browser: its nodes
made with the chart (as many as one active step per sequence shows), then per state update
only shown, hidden, moved or recoloured — pooled, so a step change in a long chart creates
no scene node — and its colours readable under black text."""

from __future__ import annotations

from typing import Any

import pytest

from s7graph.sequencer.text.parse import parse_chart
from s7graph.web.bus.protocol import (
    ChartLayout,
    Contact,
    StepDetail,
    StepStateUpdate,
    TransitionCriteria,
)
from s7graph.web.view.criteria import CONTACT_FAILS, CONTACT_PASSES
from s7graph.web.view.drawing import INK, contrast, picture
from s7graph.web.view.layout import place
from s7graph.web.view.status_layer import (
    TIMES_PERIOD,
    VALUE_FALSE,
    VALUE_PLAIN,
    VALUE_TRUE,
    StatusLayer,
    value_text,
)

pytestmark = pytest.mark.timeout(60)


class Node:
    """A scene node that records every property the layer sets on it."""

    def __init__(self, log: list[tuple[str, str]], name: str, **props: Any) -> None:
        object.__setattr__(self, "_log", log)
        object.__setattr__(self, "name", name)
        object.__setattr__(self, "visible", props.pop("visible", True))
        for key, value in props.items():
            object.__setattr__(self, key, value)

    def __setattr__(self, key: str, value: Any) -> None:
        self._log.append((self.name, key))
        object.__setattr__(self, key, value)

    def remove(self) -> None:
        self._log.append((self.name, "remove"))


class Scene:
    def __init__(self) -> None:
        self.log: list[tuple[str, str]] = []
        self.made: list[str] = []

    def add_image(self, name: str, image: Any, **props: Any) -> Node:
        self.made.append(name)
        return Node(self.log, name, image=image, **props)


def loop(n: int) -> str:
    steps = "\n".join(
        f'  {"INITIAL_STEP" if k == 1 else "STEP"} S{k} "Step {k}":\n    N "Out{k}";\n  END_STEP'
        for k in range(1, n + 1)
    )
    transitions = "\n".join(
        f'  TRANSITION T{k} FROM S{k} TO S{k % n + 1} := "In{k}" AND NOT "Stop";'
        for k in range(1, n + 1)
    )
    return (
        'FUNCTION_BLOCK "Loop" FB 1 DB 1\n  PARAMETERS := STANDARD;\n'
        f'SEQUENCE 1 "Loop"\n{steps}\n{transitions}\nEND_SEQUENCE\nEND_FUNCTION_BLOCK\n'
    )


def active(step: int, t_ms: int = 1500, first_ok: bool = False) -> StepStateUpdate:
    """Step ``step`` active for ``t_ms``: its action's operand on, its transition blocked by
    its first contact (unless ``first_ok``)."""
    contacts = [Contact(text=f'"In{step}"', ok=first_ok), Contact(text='NOT "Stop"', ok=True)]
    return StepStateUpdate(
        cycle=t_ms // 10,
        t_ms=t_ms,
        mode="AUTO",
        active=[step],
        values={f"Out{step}": True},
        details=[
            StepDetail(
                number=step,
                t_ms=t_ms,
                u_ms=t_ms,
                transitions=[TransitionCriteria(number=step, holds=False, contacts=contacts)],
            )
        ],
    )


@pytest.fixture(scope="module")
def pic() -> Any:
    return picture(place(ChartLayout.from_chart(parse_chart(loop(30), "loop.s7g"))))


def test_a_step_change_moves_the_nodes_it_shows_and_creates_none(pic: Any) -> None:
    scene = Scene()
    layer = StatusLayer(scene, pic)
    # made with the chart, hidden: T/U, a value, two contacts of two colours each
    assert len(scene.made) == 6
    layer.show(active(1), connected=True)
    assert layer.shown_text() == {
        ("times", 1): ("T 1.5 s", "U 1.5 s"),
        ("value", 1, 0): ("TRUE",),
    }
    assert layer.shown_contacts() == {
        (("T", 1), 0, 0): CONTACT_FAILS,
        (("T", 1), 1, 0): CONTACT_PASSES,
    }
    made = len(scene.made)
    assert made == 6  # none more
    for step in range(2, 31):
        scene.log.clear()
        layer.show(active(step), connected=True)
        assert len(scene.made) == made  # taken over, not created
        shown = layer.shown_text()
        assert ("times", step) in shown and ("times", step - 1) not in shown
        # moved (a contact resized): no image sent again, no node shown or hidden
        assert {prop for _, prop in scene.log} <= {"position", "render_width", "render_height"}
        assert len(scene.log) <= 10, scene.log
    scene.log.clear()
    layer.show(active(30), connected=True)  # nothing changed: nothing sent
    assert scene.log == []
    layer.show(active(30, t_ms=2500), connected=True)  # T and U: that image alone
    assert {name for name, _ in scene.log} == {"/chart/live/label/n0"}


def test_a_contact_changing_colour_is_shown_by_its_other_image_none_sent(pic: Any) -> None:
    scene = Scene()
    layer = StatusLayer(scene, pic)
    layer.show(active(2), connected=True)
    scene.log.clear()
    layer.show(active(2, first_ok=True), connected=True)
    assert layer.shown_contacts()[(("T", 2), 0, 0)] == CONTACT_PASSES
    # no image sent: one hidden, the other placed and shown
    assert {prop for _, prop in scene.log} <= {
        "visible",
        "position",
        "render_width",
        "render_height",
    }
    assert [prop for _, prop in scene.log].count("visible") == 2
    scene.log.clear()
    layer.show(active(2), connected=True)  # and back: both placed already
    assert {prop for _, prop in scene.log} == {"visible"} and len(scene.log) == 2


def test_an_active_steps_times_are_redrawn_at_most_every_times_period(pic: Any) -> None:
    scene = Scene()
    layer = StatusLayer(scene, pic)
    layer.show(active(5, t_ms=1000), connected=True, now=10.0)
    assert layer.shown_text()[("times", 5)] == ("T 1.0 s", "U 1.0 s")
    scene.log.clear()
    layer.show(active(5, t_ms=1200), connected=True, now=10.0 + TIMES_PERIOD - 0.01)
    assert layer.shown_text()[("times", 5)] == ("T 1.0 s", "U 1.0 s")  # not yet
    assert scene.log == []
    layer.show(active(5, t_ms=1500), connected=True, now=10.0 + TIMES_PERIOD)
    assert layer.shown_text()[("times", 5)] == ("T 1.5 s", "U 1.5 s")
    layer.show(active(6, t_ms=0), connected=True, now=10.0 + TIMES_PERIOD + 0.01)
    assert layer.shown_text()[("times", 6)] == ("T 0.0 s", "U 0.0 s")  # a new step: at once


def test_a_node_shown_again_for_its_element_is_only_made_visible(pic: Any) -> None:
    scene = Scene()
    layer = StatusLayer(scene, pic)
    layer.show(active(3), connected=True)
    layer.show(None, connected=False)  # disconnected: nothing live shown
    assert layer.shown_text() == {} and layer.shown_contacts() == {}
    scene.log.clear()
    layer.show(active(3), connected=True)
    assert {key for _, key in scene.log} == {"visible"}


def test_transitions_that_hold_are_returned_for_their_bars(pic: Any) -> None:
    update = active(4)
    detail = update.details[0]
    holds = TransitionCriteria(number=4, holds=True, contacts=[])
    update = StepStateUpdate(
        cycle=1,
        t_ms=10,
        mode="AUTO",
        active=[4],
        details=[StepDetail(number=4, transitions=[holds], t_ms=detail.t_ms)],
    )
    assert StatusLayer(Scene(), pic).show(update, connected=True) == {4}


def test_live_values_read_as_the_table_shows_them() -> None:
    assert value_text(True) == ("TRUE", VALUE_TRUE)
    assert value_text(False) == ("FALSE", VALUE_FALSE)
    assert value_text(42) == ("42", VALUE_PLAIN)
    assert value_text(0.1 + 0.2) == ("0.3", VALUE_PLAIN)


@pytest.mark.parametrize("colour", [CONTACT_PASSES, CONTACT_FAILS, VALUE_TRUE, VALUE_FALSE])
def test_black_text_stays_readable_on_every_live_colour(colour: tuple[int, int, int]) -> None:
    assert contrast(INK, colour) >= 4.5
