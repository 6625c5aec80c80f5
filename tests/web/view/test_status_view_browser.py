"""S7-GRAPH's status view on the page, in a real headless Chromium: a chart of two
sequences on the virtual clock, on a real bus, its inputs driven from the test as a plant
would. Beside the active step its action table shows each operand's live value, T and U
advance under its box, the contacts of the transition leaving it change colour with its
inputs, each sequence can be shown on its own, and the permanent instructions are listed
with the values they write. One browser for the module."""

from __future__ import annotations

import io
import re
import time
from collections import Counter
from collections.abc import Iterator
from typing import TYPE_CHECKING

import numpy as np
import pytest

from s7graph.web.view.chart_view import ChartView
from s7graph.web.view.criteria import CONTACT_FAILS, CONTACT_PASSES
from s7graph.web.view.drawing import BOX_H, BOX_W, INACTIVE
from s7graph.web.view.status_layer import VALUE_TRUE
from tests.web.helpers import (
    OnlineRig,
    canvas_box,
    chromium_page,
    needs_chromium,
    online_cpu,
    page_point,
    wait_until,
)

if TYPE_CHECKING:
    from playwright.sync_api import Page

pytestmark = [pytest.mark.timeout(240), needs_chromium]
pytest.importorskip("playwright.sync_api", reason="playwright is not installed")

CHART = """\
FUNCTION_BLOCK "Plant" FB 1 DB 1
  PARAMETERS := STANDARD;
VAR
  count : INT := 0;
  busy : BOOL := FALSE;
END_VAR
SYMBOLS
  "Start" : I0.0 : BOOL;
  "Full" : I0.1 : BOOL;
  "Door" : I0.2 : BOOL;
  "Go2" : I0.3 : BOOL;
  "Pump" : Q0.0 : BOOL;
  "Valve" : Q0.1 : BOOL;
END_SYMBOLS
PERMANENT AFTER
  busy := "Start" AND "Door";
END_PERMANENT
SEQUENCE 1 "Fill"
  INITIAL_STEP S1 "Idle":
  END_STEP
  STEP S2 "Fill":
    INTERLOCK := "Door";
    N "Pump";
    S1 S "Valve";
    N count := count + 1;
  END_STEP
  TRANSITION T1 "Go" FROM S1 TO S2 := "Start";
  TRANSITION T2 "Full" FROM S2 TO S1 := "Full" AND NOT "Start";
END_SEQUENCE
SEQUENCE 2 "Mix"
  INITIAL_STEP S11 "Wait":
  END_STEP
  STEP S12 "Stir":
  END_STEP
  TRANSITION T11 FROM S11 TO S12 := "Go2";
  TRANSITION T12 FROM S12 TO S11 := S12.T > T#1S;
END_SEQUENCE
END_FUNCTION_BLOCK
"""

if TYPE_CHECKING:
    from tests.conftest import BusCerts


@pytest.fixture(scope="module")
def cpu(tmp_path_factory: pytest.TempPathFactory, bus_certs: BusCerts) -> Iterator[OnlineRig]:
    tmp = tmp_path_factory.mktemp("status")
    with online_cpu(tmp, CHART, serve=True, users={}, certs=bus_certs, name="plant.s7g") as rig:
        rig.session.set("Door", True)
        yield rig


def view_of(cpu: OnlineRig) -> ChartView:
    assert cpu.edge.edge is not None
    return cpu.edge.edge.view


@pytest.fixture(scope="module")
def page(cpu: OnlineRig) -> Iterator[Page]:
    with chromium_page(cpu.edge.url) as pg:
        pg.get_by_role("button", name="Log in", exact=True).wait_for(timeout=30_000)
        view = view_of(cpu)
        assert wait_until(lambda: len(view.panels) == 1)
        time.sleep(1.0)  # the page has docked its panel and said its canvas
        yield pg


def client_of(cpu: OnlineRig) -> object:
    (panel,) = view_of(cpu).panels.values()
    return panel.client


def aim_at_chart(cpu: OnlineRig) -> None:
    """The page's camera at the readable zoom (where the view itself just put it)."""
    (panel,) = view_of(cpu).panels.values()
    panel.aim(whole=False)
    time.sleep(0.5)


def active(cpu: OnlineRig) -> list[int]:
    g = cpu.session.graph
    return [n for n, x in zip(g.cc.step_numbers, g.state.x, strict=True) if x]


def back_to_idle(cpu: OnlineRig) -> None:
    cpu.session.set("Start", False)
    cpu.session.set("Full", True)
    assert wait_until(lambda: 2 not in active(cpu))
    cpu.session.set("Full", False)


@pytest.fixture(autouse=True)
def idle(cpu: OnlineRig) -> None:
    """Each test starts with S2 idle and nothing live drawn under it, whatever the last
    one left."""
    back_to_idle(cpu)
    layer = view_of(cpu).status
    assert layer is not None
    assert wait_until(lambda: ("times", 2) not in layer.shown_text())


def to_fill(cpu: OnlineRig) -> None:
    cpu.session.set("Start", True)
    assert wait_until(lambda: 2 in active(cpu))


def colour_in(page: Page, client: object, rect: tuple[float, float, float, float]) -> tuple:
    """The most frequent colour on the page inside the scene rectangle (cx, cy, w, h): the
    colour behind its text."""
    from PIL import Image

    cx, cy, w, h = rect
    x0, y0 = page_point(client, cx - w / 2, cy + h / 2, page=page)
    x1, y1 = page_point(client, cx + w / 2, cy - h / 2, page=page)
    shot = Image.open(io.BytesIO(page.screenshot())).convert("RGB")
    crop = shot.crop((x0 + 1, y0 + 1, max(x1 - 1, x0 + 2), max(y1 - 1, y0 + 2)))
    pixels = np.asarray(crop).reshape(-1, 3)
    return Counter(map(tuple, pixels.tolist())).most_common(1)[0][0]


def dark_pixels(page: Page, client: object, x: float, y: float, w: float, h: float) -> int:
    """How many dark (text) pixels the page shows in the scene rectangle with top-left
    corner ``(x, y)``."""
    from PIL import Image

    x0, y0 = page_point(client, x, y, page=page)
    x1, y1 = page_point(client, x + w, y - h, page=page)
    shot = Image.open(io.BytesIO(page.screenshot())).convert("L")
    return int(np.count_nonzero(np.asarray(shot.crop((x0, y0, x1, y1))) < 170))


def near(seen: tuple, wanted: tuple[int, int, int], within: int = 25) -> bool:
    return all(abs(a - b) <= within for a, b in zip(seen, wanted, strict=True))


def test_the_action_table_of_the_active_step_shows_its_rows_and_live_operand_values(
    cpu: OnlineRig, page: Page
) -> None:
    view = view_of(cpu)
    step = view.layout.step(2)
    assert step is not None
    rows = [(a.event, a.qualifier, a.operand) for a in step.actions]
    assert rows == [("", "N", '"Pump"'), ("S1", "S", '"Valve"'), ("", "N", "count := count + 1")]
    assert [c.key for c in view.picture.cells[2]] == ["Pump", "Valve", "count"]
    layer = view.status
    assert layer is not None
    assert not any(k[0] == "value" for k in layer.shown_text())  # no step with a table active
    to_fill(cpu)
    assert wait_until(lambda: layer.shown_text().get(("value", 2, 0)) == ("TRUE",))
    assert wait_until(lambda: layer.shown_text().get(("value", 2, 1)) == ("TRUE",))
    assert wait_until(lambda: ("value", 2, 2) in layer.shown_text())  # each cell in its turn
    first = int(layer.shown_text()[("value", 2, 2)][0])
    assert wait_until(lambda: int(layer.shown_text()[("value", 2, 2)][0]) > first + 5)
    aim_at_chart(cpu)
    pump = view.picture.cells[2][0]
    client = client_of(cpu)
    box = (pump.cx, pump.cy, pump.w, pump.h)
    seen: list[tuple] = []

    def green() -> bool:
        seen.append(colour_in(page, client, box))
        return near(seen[-1], VALUE_TRUE)

    assert wait_until(green, 30, 0.5), seen
    back_to_idle(cpu)
    assert wait_until(lambda: not any(k[0] == "value" for k in layer.shown_text()))


def _seconds(text: str) -> float:
    found = re.fullmatch(r"[TU] (\d+\.\d) s", text)
    assert found is not None, text
    return float(found[1])


def test_t_and_u_are_shown_under_an_active_step_and_advance(cpu: OnlineRig, page: Page) -> None:
    view = view_of(cpu)
    layer = view.status
    assert layer is not None
    aim_at_chart(cpu)
    client = client_of(cpu)
    x, y = view.picture.times[2]
    # S2 idle: nothing under it (once the page has drawn what the server shows, at the aim)
    assert wait_until(lambda: dark_pixels(page, client, x, y, 0.8, 0.33) == 0, 30, 0.5)
    to_fill(cpu)
    assert wait_until(lambda: ("times", 2) in layer.shown_text())
    t0 = _seconds(layer.shown_text()[("times", 2)][0])
    assert wait_until(lambda: _seconds(layer.shown_text()[("times", 2)][0]) >= t0 + 2, 20)
    t_text, u_text = layer.shown_text()[("times", 2)]
    assert _seconds(u_text) <= _seconds(t_text)  # U: active and undisturbed
    assert wait_until(lambda: dark_pixels(page, client, x, y, 0.8, 0.33) > 10, 30, 0.5)
    back_to_idle(cpu)
    assert wait_until(lambda: ("times", 2) not in layer.shown_text())
    assert wait_until(lambda: dark_pixels(page, client, x, y, 0.8, 0.33) == 0, 30, 0.5)


def test_a_transitions_contacts_on_the_chart_change_colour_with_its_inputs(
    cpu: OnlineRig, page: Page
) -> None:
    """T2 := "Full" AND NOT "Start" leaves S2: with Start still set both contacts block
    (red); Start reset, its NOT contact lets the condition through (green)."""
    view = view_of(cpu)
    layer = view.status
    assert layer is not None
    rects = view.picture.contacts[("T", 2)]
    assert len(rects) == 2
    full, not_start = (("T", 2), 0, 0), (("T", 2), 1, 0)
    aim_at_chart(cpu)
    client = client_of(cpu)
    to_fill(cpu)  # Start stays set
    assert wait_until(lambda: layer.shown_contacts().get(not_start) == CONTACT_FAILS)
    assert layer.shown_contacts()[full] == CONTACT_FAILS
    seen: list[tuple] = []

    def shows(k: int, colour: tuple[int, int, int]) -> bool:
        seen.append(colour_in(page, client, rects[k][0]))
        return near(seen[-1], colour)

    assert wait_until(lambda: shows(1, CONTACT_FAILS) and shows(0, CONTACT_FAILS), 30, 0.5), seen
    cpu.session.set("Start", False)
    assert wait_until(lambda: layer.shown_contacts().get(not_start) == CONTACT_PASSES)
    assert layer.shown_contacts()[full] == CONTACT_FAILS and active(cpu)[0] == 2
    assert wait_until(lambda: shows(1, CONTACT_PASSES) and shows(0, CONTACT_FAILS), 30, 0.5), seen
    back_to_idle(cpu)  # T2 switches: S2's transition no longer evaluated, T1's is
    assert wait_until(lambda: full not in layer.shown_contacts())
    assert wait_until(lambda: layer.shown_contacts().get((("T", 1), 0, 0)) == CONTACT_FAILS)


def test_a_chart_of_two_sequences_offers_each_and_the_overview(cpu: OnlineRig, page: Page) -> None:
    view = view_of(cpu)
    (panel,) = view.panels.values()
    for name in ("Overview", "1 Fill", "2 Mix"):
        assert page.get_by_role("button", name=name, exact=True).count() == 1, name
    x0, x1, _, _ = view.picture.sequence_bounds[2]
    page.get_by_text("Sequence: Overview", exact=True).wait_for(timeout=30_000)
    page.get_by_role("button", name="2 Mix", exact=True).click()
    page.get_by_text("Sequence: 2 Mix", exact=True).wait_for(timeout=30_000)  # the one shown
    assert wait_until(lambda: x0 <= float(panel.client.camera.position[0]) <= x1)
    time.sleep(0.5)
    sx, sy = view.picture.steps[12]
    corner = (sx - BOX_W / 2 + 0.15, sy + BOX_H / 2 - 0.1, 0.1, 0.1)
    seen: list[tuple] = []

    def grey() -> bool:
        seen.append(colour_in(page, panel.client, corner))
        return near(seen[-1], INACTIVE)

    assert wait_until(grey, 30, 0.5), seen
    page.get_by_role("button", name="Overview", exact=True).click()
    where: list[tuple[int, int]] = []

    def whole() -> bool:  # the whole chart: both sequences on the canvas, once it moved there
        _, width, height = canvas_box(page)
        where[:] = [page_point(panel.client, *view.picture.steps[n], page=page) for n in (1, 12)]
        return all(0 <= px < width and 0 <= py < height for px, py in where)

    assert wait_until(whole, 30, 0.5), where


def test_the_permanent_instructions_are_listed_with_the_values_they_write(
    cpu: OnlineRig, page: Page
) -> None:
    """As S7-GRAPH's permanent post-instructions in TIA Portal's status view: the panel's
    *Permanent instructions* lists each under its heading, and the value it writes and its
    contacts (✓ fulfilled, ✗ not) follow the plant's inputs."""
    folder = page.get_by_text("Permanent instructions", exact=True)
    folder.wait_for(timeout=30_000)
    page.get_by_text("After the sequences", exact=True).wait_for(timeout=30_000)
    line = page.get_by_text('busy := "Start" AND "Door";')
    line.first.wait_for(timeout=30_000)
    row = page.locator("div", has=line.first).last  # the panel's HTML holding the list

    def says(value: str) -> bool:
        return value in row.inner_text()

    assert wait_until(lambda: says("FALSE")), row.inner_text()
    to_fill(cpu)  # Start and Door: busy, both contacts fulfilled
    assert wait_until(lambda: says("TRUE") and says('✓ "Start"') and says('✓ "Door"'))
    back_to_idle(cpu)
    assert wait_until(lambda: says("FALSE") and says('✗ "Start"')), row.inner_text()
