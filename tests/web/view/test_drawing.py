"""The chart as the page draws it (``web.view.drawing``): texts fitted and wrapped, never cut
nor spilling; black text readable on every state colour; a 250-step chart wrapped into
columns and shown at a readable default zoom; the layout computed once per chart."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from s7graph.sequencer.text.model import Chart, Operand, Sequence, Step, Transition
from s7graph.web.bus.protocol import ChartLayout, StepDetail, StepStateUpdate
from s7graph.web.view import chart_view
from s7graph.web.view.chart_view import ChartView, make_server
from s7graph.web.view.drawing import (
    ACTIVE,
    BAR_H,
    BAR_W,
    BOX_H,
    BOX_W,
    DISCONNECTED,
    DISTURBED,
    FLAWED,
    INACTIVE,
    LINE,
    SELECTED,
    STEP_SIZES,
    TEXT_W,
    TILE_PX,
    TRANSITION_SIZE,
    Drawing,
    _width,
    camera_for,
    contrast,
    fit_text,
    joined,
    picture,
    scale_px,
    transition_text_at,
    wrap,
)
from s7graph.web.view.layout import FOLD_ROWS, place
from tests.web.helpers import wait_until

pytestmark = pytest.mark.timeout(60)


def long_chart(n: int = 250, name: str = "Step number {i} of the long sequence") -> Chart:
    steps = tuple(Step(i, name.format(i=i), initial=i == 1) for i in range(1, n + 1))
    transitions = tuple(
        Transition(i, f"T{i}", (i,), (i % n + 1,), Operand(f"Sensor_{i}_reached", quoted=True))
        for i in range(1, n + 1)
    )
    return Chart("LONG", sequences=(Sequence(1, "Long", steps, transitions),))


@pytest.mark.parametrize(
    "name",
    ["S1", "Fill", "Clamp work piece", "W" * 40, "x" * 128, " ".join(["Wide"] * 25)[:128]],
)
def test_a_step_name_fits_its_box_whole(name: str) -> None:
    """Names are never cut at 12 characters nor spill out of the box."""
    lines, size = fit_text(f"S12  {name}", BOX_W - 0.12, BOX_H - 0.08, STEP_SIZES)
    assert "".join(lines).replace(" ", "") == f"S12{name}".replace(" ", "")  # nothing cut
    assert all(_width(line, size) <= BOX_W - 0.12 for line in lines)  # nothing spills
    assert len(lines) * size * LINE <= BOX_H - 0.08


def test_a_long_condition_wraps_beside_its_bar_with_every_character() -> None:
    condition = " AND ".join(f'"Sensor_{i}_is_really_there"' for i in range(12))
    lines = wrap(condition, TEXT_W, TRANSITION_SIZE)
    assert len(lines) > 3 and all(_width(line, TRANSITION_SIZE) <= TEXT_W for line in lines)
    assert "".join(lines).replace(" ", "") == condition.replace(" ", "")


def test_black_text_reads_on_every_state_colour() -> None:
    """Text on red stays readable: WCAG contrast of at least 4.5 on every box colour."""
    for colour in (ACTIVE, DISTURBED, INACTIVE, DISCONNECTED, SELECTED, FLAWED):
        assert contrast((0, 0, 0), colour) >= 4.5, colour


def test_a_250_step_chart_wraps_into_columns_readable_at_the_default_zoom() -> None:
    p = place(long_chart())
    assert all(s.y < FOLD_ROWS for s in p.steps.values())  # each column at most FOLD_ROWS
    assert len({s.x for s in p.steps.values()}) >= 250 * 2 // FOLD_ROWS  # many columns
    assert len({(s.x, s.y) for s in p.steps.values()}) == 250  # no two steps overlap
    outs = {(c.source, c.target) for c in p.continuations if not c.incoming}
    ins = {(c.source, c.target) for c in p.continuations if c.incoming}
    assert outs == ins and len(outs) >= 250 * 2 // FOLD_ROWS - 1  # every line continues
    pic = picture(p)
    (_, _, z), _ = camera_for(pic)
    assert scale_px(z) >= 55.0  # text of 10-12 screen pixels at the default zoom
    (_, _, whole), _ = camera_for(pic, whole=True)
    assert whole > z  # "Whole chart" zooms out to all of it
    assert all(max(t.px) <= TILE_PX for t in pic.tiles)  # WebGL-sized text images


def test_a_small_chart_is_shown_whole() -> None:
    pic = picture(place(long_chart(5)))
    assert camera_for(pic) == camera_for(pic, whole=True)


def test_a_click_on_a_transitions_text_finds_that_transition_and_nothing_else() -> None:
    """A transition's text is clicked through the scene's click at that point (no invisible
    box over it, which would cost every frame its pixels); its bar and the step boxes are
    clicked as nodes of their own, so a point on them finds no transition."""
    pic = picture(place(long_chart(8, "S{i}")))
    for n, (tx, ty) in pic.transitions.items():
        cx, cy, w, h = pic.targets[n]
        assert transition_text_at(pic, tx + BAR_W / 2 + 0.2, ty) == n  # its text, beside
        assert transition_text_at(pic, cx + w / 2 - 0.01, cy + h / 2 - 0.01) == n
        assert transition_text_at(pic, tx, ty) is None  # the bar: its own click
        assert transition_text_at(pic, tx + BAR_W / 2 - 0.01, ty + BAR_H / 2 - 0.01) is None
        assert transition_text_at(pic, cx + w / 2 + 0.01, cy) != n
    for sx, sy in pic.steps.values():
        assert transition_text_at(pic, sx + BOX_W / 2 - 0.01, sy) is None
    _, x1, _, y1 = pic.bounds
    assert transition_text_at(pic, x1 + 5, y1 + 5) is None


def test_a_click_on_a_text_selects_the_step_under_it_or_the_transition_beside_it() -> None:
    """A clickable text hides what lies under it from the click: a point of a step box is
    that step, a transition's text that transition, a point that is neither nothing."""
    pic = picture(place(long_chart(4, "S{i}")))
    clicked: list[tuple[str, int]] = []
    server, _ = make_server(port=0)
    offset = (2.0, -1.0)
    try:
        drawing = Drawing(
            server.scene,
            pic,
            offset=offset,
            on_step=lambda n, _: clicked.append(("S", n)),
            on_transition=lambda n, _: clicked.append(("T", n)),
        )

        def click(x: float, y: float) -> None:  # a ray from above onto (x, y) of the picture
            ray = SimpleNamespace(
                ray_origin=(x + offset[0], y + offset[1], 5.0), ray_direction=(0.0, 0.0, -1.0)
            )
            drawing._clicked(ray)

        sx, sy = pic.steps[3]
        click(sx + BOX_W / 2 - 0.01, sy)
        tx, ty = pic.transitions[2]
        click(tx + BAR_W / 2 + 0.2, ty)
        _, x1, _, y1 = pic.bounds
        click(x1 + 5, y1 + 5)
        assert clicked == [("S", 3), ("T", 2)]
        drawing.remove()
        click(sx, sy)  # a removed drawing calls nobody
        assert clicked == [("S", 3), ("T", 2)]
    finally:
        server.stop()


def test_the_drawing_adds_no_invisible_node_and_frames_its_boxes_in_one_mesh() -> None:
    """Every node a live chart's drawing adds is seen: a transparent click target would
    cost software WebGL its pixels in every frame; and the step boxes' frames are one mesh
    (each segment of a line object costs a frame as a small mesh would)."""
    layout = ChartLayout.from_chart(long_chart(8, "S{i}"), version=1)
    server, _ = make_server(port=0)
    view = ChartView(server, layout, lambda c: None)  # type: ignore[arg-type, return-value]
    try:
        drawing = view.drawing
        assert drawing is not None
        nodes = drawing._nodes
        assert nodes and all(getattr(node, "opacity", None) != 0.0 for node in nodes)
        assert all(node.visible for node in nodes)
        # the boxes' frames are one mesh of quads, not hundreds of line segments
        frames = [n for n in nodes if n.name.endswith("/frames")]
        assert len(frames) == 1 and type(frames[0]).__name__ == "GlbHandle"
        pic = view.picture
        assert len(pic.frames) >= 4 * len(pic.steps) > len(pic.segments)
        # the transitions' texts are clicked as nodes of their own, not through a click on
        # the whole scene (which makes viser show the pointer cursor all over the canvas);
        # the other texts take none: a click (and the hover outline) on a step's name
        # reaches its box
        texts = {n.name.rsplit("/", 1)[1]: n for n in nodes if "/text" in n.name}
        clicks = {f"text{i}": t.click for i, t in enumerate(pic.tiles)}
        assert True in clicks.values() and False in clicks.values()
        assert {name: bool(n._impl.click_cb) for name, n in texts.items()} == clicks
        assert not server.scene._scene_pointer_cb
    finally:
        view.close()
        server.stop()


def test_the_layout_is_computed_once_per_chart_version() -> None:
    chart = long_chart(12, "S{i}")
    layout = ChartLayout.from_chart(chart, version=1)
    server, _ = make_server(port=0)
    view = ChartView(server, layout, lambda c: None)  # type: ignore[arg-type, return-value]
    try:
        first = view.picture
        for cycle in range(1, 6):
            view.apply(StepStateUpdate(cycle=cycle, t_ms=cycle * 10, mode="AUTO", active=[1]))
        assert wait_until(lambda: view.boxes[1].color == ACTIVE)
        assert view.picture is first  # the scans recolour; the layout stays
        view.apply_chart(layout)  # the same version again: nothing to redraw
        assert wait_until(lambda: view.boxes[1].color == ACTIVE) and view.picture is first
        changed = ChartLayout.from_chart(long_chart(13, "S{i}"), version=2)
        view.apply_chart(changed)
        assert wait_until(lambda: view.picture is not first)
        assert len(view.boxes) == 13 and view.layout.version == 2
    finally:
        view.close()
        server.stop()


def test_a_step_change_is_coloured_at_once_while_the_rest_keeps_its_rate(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(chart_view, "MAX_FPS", 0.05)  # a full render every 20 s at most
    layout = ChartLayout.from_chart(long_chart(8, "S{i}"), version=1)
    server, _ = make_server(port=0)
    view = ChartView(server, layout, lambda c: None)  # type: ignore[arg-type, return-value]
    status = view.status
    assert status is not None

    def at(cycle: int, step: int) -> StepStateUpdate:
        detail = StepDetail(number=step, t_ms=0, u_ms=0)
        return StepStateUpdate(
            cycle=cycle, t_ms=cycle, mode="AUTO", active=[step], details=[detail]
        )

    try:
        view.apply(at(1, 1))  # the first full render
        assert wait_until(lambda: ("times", 1) in status.shown_text())
        view.apply(at(2, 2))
        assert wait_until(lambda: view.boxes[2].color == ACTIVE, timeout=5.0)
        assert view.boxes[1].color == INACTIVE
        assert ("times", 1) in status.shown_text()  # the live layer waits its turn
        assert view.drawing is not None and not view.drawing.paint_steps({2: ACTIVE})
    finally:
        view.close()
        server.stop()


def test_lines_on_one_line_that_touch_are_drawn_as_one_segment() -> None:
    segments = np.array(
        [
            [[0, 0, 0], [0, -1, 0]],
            [[0, -1, 0], [0, -2, 0]],  # touches the first: one run 0..-2
            [[0, -3, 0], [0, -4, 0]],  # a gap: a run of its own
            [[1, 0, 0], [2, 0, 0]],
            [[2.5, 0, 0], [1.5, 0, 0]],  # overlaps, drawn backwards: one run 1..2.5
            [[0, 0, 0], [1, 1, 0]],  # a slant: as it is
        ],
        np.float32,
    )
    out = {tuple(map(tuple, s.round(3).tolist())) for s in joined(segments)}
    assert out == {
        ((0, -2, 0), (0, 0, 0)),
        ((0, -4, 0), (0, -3, 0)),
        ((1, 0, 0), (2.5, 0, 0)),
        ((0, 0, 0), (1, 1, 0)),
    }


def _on(point: tuple[float, float], seg: list[list[float]]) -> bool:
    (ax, ay, _), (bx, by, _) = seg
    px, py = point
    cross = (bx - ax) * (py - ay) - (by - ay) * (px - ax)
    inside = min(ax, bx) - 1e-3 <= px <= max(ax, bx) + 1e-3
    return abs(cross) < 1e-3 and inside and min(ay, by) - 1e-3 <= py <= max(ay, by) + 1e-3


@given(
    st.lists(
        st.tuples(st.integers(0, 3), st.integers(0, 6), st.integers(0, 6), st.booleans()),
        max_size=12,
    )
)
def test_joined_segments_cover_exactly_the_points_of_the_lines(
    spans: list[tuple[int, int, int, bool]],
) -> None:
    """Vertical (``True``) or horizontal segments on a grid of lines: every point of the
    lines is on a joined segment and every joined segment's points are on the lines."""
    raw = [
        [[at, a / 2, 0.0], [at, b / 2, 0.0]] if vertical else [[a / 2, at, 0.0], [b / 2, at, 0.0]]
        for at, a, b, vertical in spans
        if a != b
    ]
    out = joined(np.array(raw, np.float32).reshape(-1, 2, 3)).tolist()
    assert len(out) <= len(raw)
    for src, dst in ((raw, out), (out, raw)):
        for seg in src:
            (ax, ay, _), (bx, by, _) = seg
            for k in range(11):
                point = (ax + (bx - ax) * k / 10, ay + (by - ay) * k / 10)
                assert any(_on(point, other) for other in dst), (point, seg)
