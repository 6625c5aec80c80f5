"""Editing where the element is drawn, in a real headless Chromium against a chart running on the
virtual clock with a users file and a real zenoh bus (docs/online-change.md, "Editing in the
browser"): a wrong password says so on the page; a click on a step or transition in edit mode
floats its form beside it with its values, leaving its text free; renaming there and completing
a condition change the chart and the source view; the step's action rows are a table; an insert
at the clicked transition lands after it, the chart staying where it is looked at; Undo and Redo
of the form and the keys Ctrl+Z, Ctrl+Y and Delete work; a click on an empty place offers the
inserts there; the window follows its step when the chart is zoomed; a step of 21 rows pages its
table. One browser, one page for the module (CI has 2 cores); the tests run in order on it."""

from __future__ import annotations

import time
from collections.abc import Iterator
from typing import TYPE_CHECKING

import pytest

from s7graph.sequencer.change.edit import make_edit
from s7graph.sequencer.text.elements import StepRef, TransitionRef, find
from s7graph.sequencer.text.model import Step, Transition
from s7graph.web.view.drawing import BOX_H, BOX_W, INACTIVE
from s7graph.web.view.editor import EDIT_OFFSET, Editor
from tests.web.bus.test_online_change import CHART
from tests.web.helpers import (
    PASSWORD,
    OnlineRig,
    canvas_box,
    chromium_page,
    field,
    log_in,
    needs_chromium,
    online_cpu,
    page_point,
    wait_until,
)
from tests.web.view.test_edit_browser import (
    choose,
    click,
    condition,
    editor,
    select,
    type_into,
)
from tests.web.view.test_online_change_browser import edit_point, shows

if TYPE_CHECKING:
    from playwright.sync_api import Page

    from tests.conftest import BusCerts

pytestmark = [pytest.mark.timeout(240), needs_chromium]
pytest.importorskip("playwright.sync_api", reason="playwright is not installed")


@pytest.fixture(scope="module")
def cpu(tmp_path_factory: pytest.TempPathFactory, bus_certs: BusCerts) -> Iterator[OnlineRig]:
    tmp = tmp_path_factory.mktemp("place")
    users = {"eng": "engineer"}
    with online_cpu(tmp, CHART, serve=True, users=users, certs=bus_certs, name="fill.s7g") as rig:
        yield rig


@pytest.fixture(scope="module")
def page(cpu: OnlineRig) -> Iterator[Page]:
    with chromium_page(cpu.edge.url) as pg:
        pg.get_by_role("button", name="Log in", exact=True).wait_for(timeout=30_000)
        yield pg


def click_on_chart(page: Page, ed: Editor, kind: str, n: int) -> tuple[int, int]:
    """Click step or transition ``n`` where the editor draws it; the page point clicked.
    Only once the page shows the drawing where the test reckons it (a step box's colour
    inside its corner: the scene has reached the browser and the camera it reports is the
    one it draws with) — a click before that hits nothing."""
    drawn = ed.session.chart if ed.session is not None else None
    assert wait_until(lambda: ed._drawing is not None and ed._drawn is drawn, timeout=30)
    drawing = ed._drawing
    assert drawing is not None
    if kind == "step":
        x, y = drawing.picture.steps[n]
    else:
        x, y = drawing.picture.transitions[n]  # its bar
    ox, oy = drawing.offset
    assert wait_until(lambda: settled(ed), timeout=30)
    seen = n if kind == "step" else min(drawing.picture.steps)
    colour = drawing._colour.get(("S", seen), INACTIVE)

    def corner() -> dict[int, tuple[int, int]]:
        return {seen: edit_point(page, ed, drawing, seen)}

    assert wait_until(lambda: shows(page, corner, {seen: colour}, 35), 30, poll=0.5)
    px, py = page_point(ed.client, x + ox, y + oy, page=page)
    on = f"() => document.elementFromPoint({px}, {py}).tagName"
    assert wait_until(lambda: page.evaluate(on) == "CANVAS", 10), f"{kind} {n} is covered"
    page.mouse.click(px, py)
    return px, py


def settled(ed: Editor) -> bool:
    """Whether the page's camera looks at the chart edited and stays put for a while."""
    before = tuple(float(v) for v in ed.client.camera.position)
    time.sleep(0.5)
    after = tuple(float(v) for v in ed.client.camera.position)
    return before == after and abs(after[1] - EDIT_OFFSET[1]) < 100


def step(ed: Editor, n: int) -> Step:
    assert ed.session is not None
    found = find(ed.session.chart, StepRef(n))
    assert isinstance(found, Step)
    return found


def targets(ed: Editor, n: int) -> tuple[int, ...]:
    assert ed.session is not None
    found = find(ed.session.chart, TransitionRef(n))
    assert isinstance(found, Transition)
    return found.targets


def blank(page: Page) -> None:
    """Take the focus out of the form's fields (a click on an empty place would insert)."""
    page.evaluate("() => document.activeElement && document.activeElement.blur()")


def click_at(page: Page, ed: Editor, x: float, y: float) -> None:
    """Click the picture point ``(x, y)`` of the chart edited, which must be on the canvas."""
    assert wait_until(lambda: settled(ed), timeout=30)
    ox, oy = EDIT_OFFSET
    px, py = page_point(ed.client, x + ox, y + oy, page=page)
    left, width, height = canvas_box(page)
    assert left < px < left + width and 0 < py < height, (px, py, left, width, height)
    page.mouse.click(px, py)


def tab_box(page: Page) -> tuple[float, float]:
    box = page.get_by_role("tab", name="Edit here").bounding_box()
    assert box is not None
    return box["x"], box["y"]


def test_a_wrong_password_says_so_on_the_page(page: Page, cpu: OnlineRig) -> None:
    field(page, "User").fill("eng")
    field(page, "Password").fill("not the password")
    field(page, "Password").press("Tab")
    click(page, "Log in")
    page.get_by_text("login refused: wrong user name or password").first.wait_for(timeout=30_000)
    assert page.get_by_role("button", name="Edit mode").count() == 0
    log_in(page, "eng", PASSWORD)  # the message goes with the next login
    said = page.get_by_text("login refused: wrong user name or password")
    assert wait_until(lambda: said.count() == 0)


def test_a_click_on_a_step_opens_its_form_beside_it_and_a_rename_there_changes_the_chart(
    page: Page, cpu: OnlineRig
) -> None:
    click(page, "Edit mode")
    page.get_by_role("button", name="Leave edit mode").wait_for(timeout=30_000)
    ed = editor(cpu)
    assert wait_until(lambda: ed._drawing is not None, timeout=30)
    px, py = click_on_chart(page, ed, "step", 2)
    assert wait_until(lambda: ed.session is not None and ed.session.selection == StepRef(2), 30), (
        ed.session and ed.session.selection
    )
    page.get_by_text("step S2 Fill", exact=True).first.wait_for(timeout=30_000)
    assert field(page, "Name").input_value() == "Fill"
    assert field(page, "Number").input_value() == "2"
    tab = page.get_by_role("tab", name="Edit here").bounding_box()
    assert tab is not None
    assert px < tab["x"] < px + 200 and tab["y"] < py, (px, py, tab)  # beside the step
    assert field(page, "Operand 1").input_value() == "pieces := pieces + 1"  # the row table
    assert field(page, "Operand 2").input_value() == "Q0.0"
    type_into(page, "Name", "Filling")
    assert wait_until(lambda: step(ed, 2).name == "Filling", 30)
    assert wait_until(lambda: 'STEP S2 "Filling":' in str(ed.source.value), 30)  # the source
    type_into(page, "Operand 2", "Q0.5")
    assert wait_until(lambda: "    N Q0.5;" in str(ed.source.value), 30)
    assert page.get_by_role("tab", name="Source (.s7g)").count() == 1


def test_a_condition_completes_a_name_and_the_source_view_follows(
    page: Page, cpu: OnlineRig
) -> None:
    ed = editor(cpu)
    click_on_chart(page, ed, "transition", 2)
    assert wait_until(lambda: ed.session is not None and ed.session.selection == TransitionRef(2))
    page.get_by_text("transition T2 Full", exact=True).first.wait_for(timeout=30_000)
    assert field(page, "Condition").input_value() == "full"
    assert ed._drawing is not None
    _, _, x1, y1 = ed._drawing.picture.shown[2]  # its bar and text, which the form leaves free
    right, _ = page_point(ed.client, x1 + EDIT_OFFSET[0], y1 + EDIT_OFFSET[1], page=page)
    assert wait_until(lambda: tab_box(page)[0] > right, 30), (tab_box(page), right)
    field(page, "Condition").fill("full AND em")  # typing: the list offers what completes it
    choose(page, "Complete", "empty")
    assert wait_until(lambda: condition(ed, 2) == "full AND empty", 30)
    box = field(page, "Condition")
    assert wait_until(lambda: box.input_value() == "full AND empty", 30), box.input_value()
    assert wait_until(lambda: "FROM S2 TO S3 := full AND empty;" in str(ed.source.value), 30)


def test_an_insert_lands_at_the_clicked_transition_and_undo_redo_and_keys_work(
    page: Page, cpu: OnlineRig
) -> None:
    ed = editor(cpu)
    click_on_chart(page, ed, "transition", 1)
    assert wait_until(lambda: ed.session is not None and ed.session.selection == TransitionRef(1))
    page.get_by_text("transition T1 Go", exact=True).first.wait_for(timeout=30_000)
    assert wait_until(lambda: settled(ed), timeout=30)
    looked = [float(v) for v in ed.client.camera.position]
    click(page, "Step + Transition")  # after T1: S4, then T4 to where T1 led
    assert wait_until(lambda: targets(ed, 1) == (4,), 30)
    assert targets(ed, 4) == (2,)
    assert wait_until(lambda: "FROM S1 TO S4 := go;" in str(ed.source.value), 30)
    assert wait_until(lambda: settled(ed), timeout=30)  # the chart grew; the page looks on
    assert [float(v) for v in ed.client.camera.position] == pytest.approx(looked, abs=1e-3)
    click(page, "Undo")
    assert wait_until(lambda: targets(ed, 1) == (2,), 30)
    click(page, "Redo")
    assert wait_until(lambda: targets(ed, 1) == (4,), 30)
    blank(page)
    page.keyboard.press("Control+z")
    assert wait_until(lambda: targets(ed, 1) == (2,), 30)
    page.keyboard.press("Control+y")
    assert wait_until(lambda: targets(ed, 1) == (4,), 30)
    click_on_chart(page, ed, "step", 4)
    assert wait_until(lambda: ed.session is not None and ed.session.selection == StepRef(4))
    blank(page)
    page.keyboard.press("Delete")  # S4 and T4 go; T1 leads to S2 again
    assert wait_until(lambda: targets(ed, 1) == (2,), 30)
    assert ed.session is not None and len(ed.session.chart.sequences[0].steps) == 3


def test_a_click_on_an_empty_place_offers_the_inserts_there(page: Page, cpu: OnlineRig) -> None:
    ed = editor(cpu)
    assert ed._drawing is not None
    pic = ed._drawing.picture
    x1, y1 = pic.steps[1]
    x3, y3 = pic.transitions[3]  # the column's last transition (the jump back to S1)
    click_at(page, ed, x3, y3 - 0.5)  # below it, in its column: the inserts after it
    assert wait_until(lambda: ed.session is not None and ed.session.selection == TransitionRef(3))
    page.get_by_text("transition T3 Empty", exact=True).first.wait_for(timeout=30_000)
    click(page, "Step + Transition")
    assert wait_until(lambda: targets(ed, 3) == (4,), 30)
    assert targets(ed, 4) == (1,)  # appended: the new transition jumps back as T3 did
    click(page, "Undo")
    assert wait_until(lambda: targets(ed, 3) == (1,), 30)
    click_at(page, ed, x1, y1 + 1.5 * BOX_H)  # above the column: the chart's inserts
    assert wait_until(lambda: ed._form is not None and ed._form.ref is None, 30)
    click(page, "Sequencer")
    assert wait_until(lambda: ed.session is not None and len(ed.session.chart.sequences) == 2)
    click(page, "Undo")
    assert wait_until(lambda: ed.session is not None and len(ed.session.chart.sequences) == 1)


def test_the_window_follows_the_chart_when_it_is_zoomed(page: Page, cpu: OnlineRig) -> None:
    ed = editor(cpu)
    select(page, ed, "S2 Filling", StepRef(2))  # the window beside it (over the chart: narrow)
    assert wait_until(lambda: ed._placed is not None, 30)
    before, placed = tab_box(page), ed._placed
    left, width, height = canvas_box(page)
    page.mouse.move(left + width / 4, height / 4)
    page.mouse.wheel(0, 800)  # zoom out
    assert wait_until(lambda: settled_anywhere(ed), timeout=30)
    assert wait_until(lambda: ed._placed != placed, 30), placed
    assert ed._placed is not None
    moved = left + ed._placed[0]
    assert wait_until(lambda: abs(tab_box(page)[0] - moved) <= 2, 30), (before, moved)
    drawing = ed._drawing
    assert drawing is not None
    x, y = drawing.picture.steps[2]
    px, py = page_point(ed.client, x + EDIT_OFFSET[0] + BOX_W / 2, y + EDIT_OFFSET[1], page=page)
    tx, ty = tab_box(page)
    assert px <= tx < px + 60 and ty < py, (px, py, tx, ty)  # beside the step where it is now


def settled_anywhere(ed: Editor) -> bool:
    before = tuple(float(v) for v in ed.client.camera.position)
    time.sleep(0.6)
    return before == tuple(float(v) for v in ed.client.camera.position)


def test_a_step_with_more_rows_than_the_table_shows_pages_through_them(
    page: Page, cpu: OnlineRig
) -> None:
    ed = editor(cpu)
    more = "".join(f"    N Q{i // 8}.{i % 8};\n" for i in range(1, 21))  # S3: 21 rows
    text = str(ed.source.value).replace("    N Q0.1;\n", "    N Q0.1;\n" + more)
    ed._guarded(lambda: ed.apply(make_edit("set_source", {"text": text})))
    assert wait_until(lambda: len(step(ed, 3).actions) == 21, 30)
    select(page, ed, "S3 Drain", StepRef(3))
    page.get_by_text("rows 1–16 of 21, run top to bottom").first.wait_for(timeout=30_000)
    assert field(page, "Operand 16").input_value() == "Q1.7"
    choose(page, "Rows shown", "17–21")
    page.get_by_text("rows 17–21 of 21, run top to bottom").first.wait_for(timeout=30_000)
    assert wait_until(lambda: field(page, "Operand 17").input_value() == "Q2.0", 30)
    assert field(page, "Operand 21").input_value() == "Q2.4"
    type_into(page, "Operand 18", "Q7.7")
    assert wait_until(lambda: "Q7.7" in str(step(ed, 3).actions[17]), 30)
    assert page.get_by_text("rows 17–21 of 21, run top to bottom").count() > 0  # stays
