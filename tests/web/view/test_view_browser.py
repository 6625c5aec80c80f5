"""The live view in a real headless Chromium: a real viser server and a real zenoh bus on
loopback; only the scans are test data. One browser for the whole module (CI has 2 cores)."""

from __future__ import annotations

import os
import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pytest

from s7graph.sequencer.text.model import Chart, Operand, Sequence, Step, Transition
from s7graph.web.bus.protocol import ChartLayout, Command, StepStateUpdate
from s7graph.web.view.chart_view import ACTIVE, DISTURBED, INACTIVE, ChartView
from s7graph.web.view.drawing import BAR_W, BOX_H, BOX_W, TEXT_TOP
from s7graph.web.wiring.web_edge import WebEdge, serve_view
from tests.web.helpers import (
    chromium_page,
    fill,
    log_in,
    needs_chromium,
    page_point,
    wait_until,
)
from tests.web.toy_feed import ToySequencer

if TYPE_CHECKING:
    from playwright.sync_api import Page

pytestmark = [
    pytest.mark.timeout(90),
    needs_chromium,
]
pytest.importorskip("playwright.sync_api", reason="playwright is not installed")


def small_chart() -> Chart:
    """Fill, then heat and stir side by side, drain; jump back to the start."""
    return Chart(
        "MIXER",
        sequences=(
            Sequence(
                1,
                "Mixer",
                (
                    Step(1, "Idle", initial=True),
                    Step(2, "Fill", interlock=Operand("Inlet_ok", quoted=True)),
                    Step(3, "Heat", supervision=Operand("Too_long", quoted=True)),
                    Step(4, "Stir"),
                    Step(5, "Drain"),
                ),
                (
                    Transition(1, "Start", (1,), (2,), Operand("Start", quoted=True)),
                    Transition(2, "Full", (2,), (3, 4), Operand("Level_high", quoted=True)),
                    Transition(3, "Hot", (3, 4), (5,), Operand("Temp_ok", quoted=True)),
                    Transition(4, "Empty", (5,), (1,), Operand("Level_low", quoted=True)),
                ),
            ),
        ),
    )


FEED = [  # the fake scans: S3 and S4 active, S3 with a latched supervision error
    StepStateUpdate(cycle=1, t_ms=10, mode="AUTO", active=[1], events=[("S1", 1)]),
    StepStateUpdate(cycle=2, t_ms=20, mode="AUTO", active=[2], events=[("S0", 1), ("S1", 2)]),
    StepStateUpdate(
        cycle=3,
        t_ms=30,
        mode="AUTO",
        active=[3, 4],
        disturbed=[3],
        latched=[3],
        events=[("S0", 2), ("S1", 3), ("S1", 4), ("V1", 3)],
    ),
]


@pytest.fixture(scope="module")
def edge() -> Iterator[WebEdge]:
    with serve_view(small_chart(), None, port=0) as running:
        for update in FEED:
            running.publisher.publish("MIXER", update)
        yield running


@pytest.fixture(scope="module")
def page(edge: WebEdge) -> Iterator[Page]:
    with chromium_page(edge.url) as pg:
        pg.get_by_role("button", name="Acknowledge", exact=True).wait_for(timeout=30_000)
        yield pg


def test_control_sequencer_panel_offers_every_command(page: Page) -> None:
    for name in (
        "AUTO",
        "MAN",
        "TAP",
        "TOP",
        "Initialize",
        "Disable (OFF)",
        "Acknowledge",
        "T_PUSH (Continue)",
        "Activate",
        "Deactivate",
        "Only this step",
    ):
        assert page.get_by_role("button", name=name, exact=True).count() == 1, name
    assert page.get_by_text("Control Sequencer").count() >= 1


def test_steps_are_coloured_from_the_bus_state(edge: WebEdge) -> None:
    view = edge.view
    assert wait_until(lambda: view.boxes[4].color == ACTIVE)
    assert view.boxes[3].color == DISTURBED  # latched supervision error wins over active
    assert view.boxes[1].color == INACTIVE
    assert wait_until(lambda: any("cycle 3" in p.status.content for p in view.panels.values()))
    # the current mode is highlighted on its button, on every page
    panels = list(view.panels.values())
    assert wait_until(lambda: all(p.mode_buttons["AUTO"].color == "green" for p in panels))
    assert all(p.mode_buttons["MAN"].color is None for p in panels)


def test_acknowledge_click_reaches_the_cpu_queue_and_is_answered(
    page: Page,
    edge: WebEdge,
    tmp_path: Path,
) -> None:
    acknowledge = page.get_by_role("button", name="Acknowledge", exact=True)
    assert acknowledge.is_disabled()  # a page is a viewer until it logs in
    log_in(page, "olga")
    assert wait_until(acknowledge.is_enabled)
    acknowledge.click()
    received = []
    assert wait_until(lambda: received.extend(edge.publisher.drain_commands()) or received)
    (pending,) = received
    command = pending.command
    assert (command.op, command.fb, command.user) == ("ack", "MIXER", "olga")
    assert command.token and command.origin.startswith("unixsock-stream/")  # the transport's
    assert pending.note.startswith("claimed origin: page ")  # what the page's view says
    pending.resolve(True, cycle=4)
    assert wait_until(lambda: bool(edge.view.replies))
    assert edge.view.replies[-1].applied
    page.get_by_text("acknowledge applied").first.wait_for(timeout=30_000)

    shot = tmp_path / "view.png"
    page.screenshot(path=str(shot))
    assert shot.stat().st_size > 10_000
    keep = os.environ.get("S7GRAPH_SCREENSHOT")
    if keep:  # for a human to look at the chart
        shutil.copy(shot, keep)


def test_only_this_step_sends_set_steps_with_the_step_field(page: Page, edge: WebEdge) -> None:
    if not page.get_by_text("logged in as olga").count():  # one page for the module
        log_in(page, "olga")
    only = page.get_by_role("button", name="Only this step", exact=True)
    assert wait_until(only.is_enabled)
    fill(page, "Step", "2")
    (panel,) = edge.view.panels.values()
    assert wait_until(lambda: panel.step_number.value == 2)
    only.click()
    received: list[Any] = []
    assert wait_until(lambda: received.extend(edge.publisher.drain_commands()) or received)
    (pending,) = received
    assert (pending.command.op, pending.command.args.steps) == ("set_steps", [2])
    pending.resolve(True, cycle=4)


def test_demo_feed_applies_commands_between_scans() -> None:
    """serve_view with a feed: a mode command from a bus client lands between two scans."""
    toy = ToySequencer(ChartLayout.from_chart(small_chart()), hold=1000)
    with serve_view(small_chart(), toy.run(5), port=0, apply_command=toy.apply) as running:
        login = running.client.login("tom")
        assert login.ok, login.reason
        reply = running.client.send(
            Command(op="mode", fb="MIXER", user="tom", token=login.token, args={"mode": "MAN"})
        )
        assert reply.applied, reply.reason
        assert wait_until(lambda: running.follower.latest and running.follower.latest.mode == "MAN")
        refused = running.client.send(
            Command(op="t_push", fb="MIXER", user="tom", token=login.token)
        )
        assert not refused.applied and "TAP and TOP" in refused.reason


def screen_point(view: ChartView, x: float, y: float) -> tuple[int, int]:
    """Where the scene point ``(x, y)`` shows on the (one) page."""
    (panel,) = view.panels.values()
    return page_point(panel.client, x, y)


def cursor(page: Page) -> str:
    """The cursor viser shows over its scene's canvas (the page's largest)."""
    return str(
        page.evaluate(
            """() => Array.from(document.querySelectorAll('canvas'))
                .sort((a, b) => b.width * b.height - a.width * a.height)[0].style.cursor"""
        )
    )


def test_a_click_on_a_transition_shows_its_whole_condition(page: Page, edge: WebEdge) -> None:
    """Transitions are clickable like steps, on their bar or their text: the details show
    name and whole condition. The pointer cursor shows over what a click finds, not over
    the empty canvas."""
    view = edge.view
    tx, ty = view.picture.transitions[2]
    x1 = view.picture.bounds[1]
    page.mouse.move(*screen_point(view, x1 + 0.5, ty))  # right of the chart: nothing there
    page.mouse.move(*screen_point(view, x1 + 0.6, ty))
    assert wait_until(lambda: cursor(page) in ("", "auto")), cursor(page)
    px, py = screen_point(view, tx + BAR_W / 2 + 0.25, ty + TEXT_TOP - 0.1)  # its first line
    page.mouse.move(px, py)
    assert wait_until(lambda: cursor(page) == "pointer"), cursor(page)
    page.mouse.click(px, py)
    assert wait_until(
        lambda: any(int(p.detail_transition.value) == 2 for p in view.panels.values())
    )
    page.get_by_text('"Level_high"').first.wait_for(timeout=30_000)
    page.get_by_text("from S2 to S3, S4").first.wait_for(timeout=30_000)
    sx, sy = view.picture.steps[5]
    page.mouse.click(*screen_point(view, sx, sy))  # a step again: its details
    assert wait_until(lambda: any(int(p.detail_step.value) == 5 for p in view.panels.values()))
    # the click's callback clears the transition just after it sets the step
    panels = view.panels.values()
    assert wait_until(lambda: all(int(p.detail_transition.value) == 0 for p in panels))


def test_the_pointer_on_a_steps_name_outlines_its_box(page: Page, edge: WebEdge) -> None:
    """A step's name lets the pointer through to its box: the box shows viser's hover
    outline (yellow) around it, as over the rest of the box, and the pointer cursor."""
    from io import BytesIO

    from PIL import Image

    view = edge.view
    sx, sy = view.picture.steps[5]

    def outlined() -> int:
        """On how many of the box's four sides the outline shows: a yellow pixel within 12
        pixels outside its frame, off the link (the camera read each time: the page may
        still be aiming it)."""
        shot = Image.open(BytesIO(page.screenshot())).convert("RGB")
        sides = 0
        for dx, dy in ((-1, 0), (1, 0), (-0.5, -1), (0.5, 1)):
            x, y = screen_point(view, sx + dx * BOX_W / 2, sy + dy * BOX_H / 2)
            step = (0, -dy) if dy else (dx, 0)  # outwards on the page (its y grows down)
            pixels = [shot.getpixel((x + k * step[0], y + k * step[1])) for k in range(2, 13)]
            sides += any(min(r, g) > 150 and b < r - 40 for r, g, b in pixels)  # yellow
        return sides

    def pointing(x: float, y: float, outlines: int) -> bool:
        page.mouse.move(*screen_point(view, x, y))
        return outlined() == outlines

    x1 = view.picture.bounds[1]
    assert wait_until(lambda: pointing(x1 + 0.5, sy, 0), 30, poll=0.5)  # nothing there
    assert wait_until(lambda: pointing(sx, sy, 4), 30, poll=0.5)  # its name: "S5  Drain"
    assert cursor(page) == "pointer"
    assert wait_until(lambda: pointing(x1 + 0.5, sy, 0), 30, poll=0.5)


def test_every_step_shows_its_state_colour_itself_on_the_page(page: Page, edge: WebEdge) -> None:
    """The chart is lit flat (``FLAT_LIGHT``: one ambient light, no shadows, no environment
    map), so a box's pixels are its state's RGB — active, disturbed, inactive — not a shaded
    or darkened version of it (each channel within 20 of the colour: the page's tone
    mapping shifts it a little; with directional lights alone the boxes came out dark grey)."""
    from io import BytesIO

    from PIL import Image

    view = edge.view
    assert wait_until(lambda: view.boxes[4].color == ACTIVE)
    wanted = {1: INACTIVE, 4: ACTIVE, 3: DISTURBED, 5: INACTIVE}
    corners = {}
    for n in wanted:
        x, y = view.picture.steps[n]
        px, py = screen_point(view, x - BOX_W / 2 + 0.06, y + BOX_H / 2 - 0.06)
        corners[n] = (round(px), round(py))
    seen: dict[int, tuple[int, ...]] = {}

    def shown() -> bool:
        shot = Image.open(BytesIO(page.screenshot())).convert("RGB")
        seen.update({n: shot.getpixel(corners[n]) for n in wanted})
        return all(
            all(abs(a - b) <= 20 for a, b in zip(seen[n], rgb, strict=True))
            for n, rgb in wanted.items()
        )

    assert wait_until(shown, 30, poll=0.5), seen


# Where the page shows its notices: the union of the boxes of viser's (Mantine's)
# notifications, as {x, y, width, height} (null: none drawn).
NOTICES_BOX = """() => {
    const all = document.querySelectorAll('.mantine-Notification-root');
    const rs = Array.from(all).map(e => e.getBoundingClientRect())
        .filter(r => r.width > 0 && r.height > 0);
    if (!rs.length) return null;
    const x = Math.min(...rs.map(r => r.left)), y = Math.min(...rs.map(r => r.top));
    const w = Math.max(...rs.map(r => r.right)) - x, h = Math.max(...rs.map(r => r.bottom)) - y;
    return {x: x, y: y, width: w, height: h};
}"""


def test_a_command_notice_shows_below_the_chart_not_over_its_first_step(
    page: Page, edge: WebEdge
) -> None:
    """A command's verdict (viser puts its notices at the canvas's top-left, where the chart
    opens) shows at the bottom-left of the canvas: even a refusal of three lines leaves the
    first step's box clear, and the whole notice is on the page."""
    view = edge.view
    (panel,) = view.panels.values()
    reason = "the CPU refuses: " + "a reason long enough to wrap over several lines " * 3
    panel.notify("CPU to STOP refused", reason, ok=False)
    page.get_by_text("CPU to STOP refused").first.wait_for(timeout=30_000)
    boxes: list[Any] = [None]

    def settled() -> bool:  # the notice slides in from the left: until it is in, at rest
        boxes.append(page.evaluate(NOTICES_BOX))
        box = boxes[-1]
        return box is not None and box["x"] >= 0 and box == boxes[-2]

    assert wait_until(settled, 30, poll=0.3), boxes
    box = boxes[-1]
    assert box["height"] > 70  # the reason wrapped: the notice is as tall as it gets
    sx, sy = view.picture.steps[1]
    left, top = screen_point(view, sx - BOX_W / 2, sy + BOX_H / 2)
    right, bottom = screen_point(view, sx + BOX_W / 2, sy - BOX_H / 2)
    apart = (
        box["x"] + box["width"] <= left
        or box["x"] >= right
        or box["y"] + box["height"] <= top
        or box["y"] >= bottom
    )
    assert apart, (box, (left, top, right, bottom))
    height = page.viewport_size["height"] if page.viewport_size else 0
    assert box["y"] >= 0 and box["y"] + box["height"] <= height, box
