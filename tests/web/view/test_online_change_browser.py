"""A download that inserts a step, and an undo of it, through a real zenoh bus, a real
headless Chromium page and ``s7graph watch``: an engineer inserts S8 between
S6 and S7 of the running chain S1 … S7 in the browser and downloads it; the sequence then
runs S6 → S8 → S7, and the events, ``watch``, the page (its step colours, its event list,
a click on the new step) and the audit name S8 and those switches. After *Undo download*
the editor's page still draws the chart it edits: its edits, its diagnostics, and a click
on a step selects it. One CPU, one browser and one page for the module (CI has 2 cores);
the tests run in order on them."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import threading
from collections.abc import Callable, Iterator
from io import BytesIO
from typing import TYPE_CHECKING

import pytest

from s7graph.sequencer.text.elements import StepRef, TransitionRef, find
from s7graph.web.access.audit import read_audit
from s7graph.web.bus.client import BusClient
from s7graph.web.bus.protocol import Command
from s7graph.web.bus.session import open_session
from s7graph.web.view.chart_view import ChartView
from s7graph.web.view.drawing import ACTIVE, BOX_H, BOX_W, INACTIVE, SELECTED, Drawing
from s7graph.web.view.editor import Editor
from tests.sequencer.exchange.helpers import synthetic
from tests.web.helpers import (
    PASSWORD,
    PREVIEW_MS,
    OnlineRig,
    chromium_page,
    log_in,
    needs_chromium,
    online_cpu,
    page_point,
    wait_until,
)
from tests.web.view.test_edit_browser import choose, click, condition, select, type_into

if TYPE_CHECKING:
    from playwright.sync_api import Page

    from tests.conftest import BusCerts

pytestmark = [pytest.mark.timeout(300), needs_chromium]
pytest.importorskip("playwright.sync_api", reason="playwright is not installed")

INSET = 0.15  # scene units inside a box's top-left corner: its fill, not its frame or text
CHAIN = "\n".join(
    [
        'FUNCTION_BLOCK "Seq_chain" FB 1 DB 1',
        "VAR",
        *(f"  g{n} : BOOL;" for n in range(1, 9)),
        "END_VAR",
        'SEQUENCE 1 "Chain"',
        *(
            f'  {"INITIAL_STEP" if n == 1 else "STEP"} S{n} "Step {n}":\n  END_STEP'
            for n in range(1, 8)
        ),
        *(f'  TRANSITION T{n} "Go{n}" FROM S{n} TO S{n % 7 + 1} := g{n};' for n in range(1, 8)),
        "END_SEQUENCE",
        "END_FUNCTION_BLOCK",
        "",
    ]
)


class Watch:
    """``s7graph watch`` on the CPU's bus, its lines collected as they come."""

    def __init__(self, bus: list[str]) -> None:
        self.lines: list[str] = []
        self.proc = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "s7graph",
                "watch",
                "--cpu",
                "cpu1",
                *bus,
                "--duration-s",
                "280",
            ],
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            stdin=subprocess.DEVNULL,
            text=True,
            env=dict(os.environ),
        )
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            self.lines.append(line.rstrip("\n"))

    def saw(self, *parts: str) -> bool:
        """Whether one line holds every one of ``parts``."""
        return any(all(p in line for p in parts) for line in list(self.lines))

    def close(self) -> None:
        self.proc.terminate()
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait(timeout=10)


@pytest.fixture(scope="module")
def cpu(tmp_path_factory: pytest.TempPathFactory, bus_certs: BusCerts) -> Iterator[OnlineRig]:
    tmp = tmp_path_factory.mktemp("insert")
    users = {"eng": "engineer"}
    with online_cpu(tmp, CHAIN, serve=True, users=users, certs=bus_certs, name="chain.s7g") as rig:
        yield rig


@pytest.fixture(scope="module")
def watch(cpu: OnlineRig) -> Iterator[Watch]:
    w = Watch(cpu.bus)
    try:
        assert wait_until(lambda: w.saw("Seq_chain", "active S1"), timeout=60), w.lines
        yield w
    finally:
        w.close()


@pytest.fixture(scope="module")
def page(cpu: OnlineRig) -> Iterator[Page]:
    with chromium_page(cpu.edge.url) as pg:
        pg.get_by_role("button", name="Log in", exact=True).wait_for(timeout=30_000)
        log_in(pg, "eng", PASSWORD)
        yield pg


def view_of(cpu: OnlineRig) -> ChartView:
    view = cpu.edge.edge.view if cpu.edge.edge is not None else None
    assert view is not None
    return view


def editor(cpu: OnlineRig) -> Editor:
    view = view_of(cpu)
    assert wait_until(lambda: any(p.editor is not None for p in view.panels.values()))
    found = next(p.editor for p in view.panels.values() if p.editor is not None)
    assert found is not None
    return found


def active(cpu: OnlineRig) -> list[int]:
    g = cpu.session.graph
    return [n for n, x in zip(g.cc.step_numbers, g.state.x, strict=True) if x]


def run_to(cpu: OnlineRig, gate: str, step: int) -> None:
    """Let the transition conditioned on ``gate`` switch, up to ``step`` being active."""
    cpu.session.set(gate, True)
    assert wait_until(lambda: active(cpu) == [step]), active(cpu)
    cpu.session.set(gate, False)


def live_point(page: Page, view: ChartView, n: int) -> tuple[int, int]:
    """Where the top-left inside corner of live step box ``n`` shows on the (one) page, as
    its camera is now."""
    x, y = view.picture.steps[n]
    (panel,) = view.panels.values()
    return page_point(panel.client, x - BOX_W / 2 + INSET, y + BOX_H / 2 - INSET, page=page)


def edit_point(page: Page, ed: Editor, drawing: Drawing, n: int) -> tuple[int, int]:
    """Where the top-left inside corner of step box ``n`` of the editor's drawing shows on
    its page (its canvas measured on the page: right of the docked editor), as its camera
    is now."""
    x, y = drawing.picture.steps[n]
    x, y = x + drawing.offset[0] - BOX_W / 2 + INSET, y + drawing.offset[1] + BOX_H / 2 - INSET
    return page_point(ed.client, x, y, page=page)


def shows(
    page: Page,
    where: Callable[[], dict[int, tuple[int, int]]],
    colours: dict[int, object],
    within: int = 20,
) -> bool:
    """Whether each point shows its colour on the page (each channel ``within``). The points
    are taken anew at each look: the camera the page reports may still be moving (an aim
    after an edit, back to the live chart) when the look is first asked for."""
    from PIL import Image

    points = where()
    shot = Image.open(BytesIO(page.screenshot())).convert("RGB")
    if not all(0 <= x < shot.width and 0 <= y < shot.height for x, y in points.values()):
        return False  # the camera looks elsewhere
    return all(
        all(abs(a - b) <= within for a, b in zip(shot.getpixel(points[n]), rgb, strict=True))  # type: ignore[arg-type]
        for n, rgb in colours.items()
    )


def test_an_inserted_step_is_named_by_events_watch_the_page_and_the_audit(
    page: Page, cpu: OnlineRig, watch: Watch
) -> None:
    for n in range(1, 6):
        run_to(cpu, f"g{n}", n + 1)  # S6 active: the steps before and after the insertion
    click(page, "Edit mode")
    page.get_by_role("button", name="Leave edit mode").wait_for(timeout=30_000)
    ed = editor(cpu)
    select(page, ed, "T6 Go6", TransitionRef(6))
    click(page, "Step + Transition")  # S8 after T6, and T8 from S8 to S7
    assert wait_until(lambda: ed.session is not None and ed.session.selection == StepRef(8))
    page.get_by_text("step S8 Step8", exact=True).first.wait_for(timeout=30_000)  # its form
    type_into(page, "Name", "Eight")
    select(page, ed, "T8 Trans8", TransitionRef(8))  # at once: what was typed is not lost
    assert wait_until(lambda: ed.session is not None and "Eight" in str(ed.source.value))
    assert ed.session is not None and find(ed.session.chart, StepRef(8)).name == "Eight"
    type_into(page, "Condition", "g8")
    assert wait_until(lambda: condition(ed, 8) == "g8")
    click(page, "Download")
    page.get_by_text("What changes").first.wait_for(timeout=PREVIEW_MS)
    click(page, "Download to the CPU")
    page.get_by_text("download applied").first.wait_for(timeout=30_000)
    assert cpu.session.graph.cc.step_numbers == (1, 2, 3, 4, 5, 6, 8, 7)
    assert active(cpu) == [6]
    click(page, "Leave edit mode")
    view = view_of(cpu)
    assert wait_until(lambda: sorted(view.boxes) == [1, 2, 3, 4, 5, 6, 7, 8])

    run_to(cpu, "g6", 8)  # S6 -> S8
    assert wait_until(lambda: watch.saw("active S8", "S0:S6", "S1:S8")), watch.lines
    page.get_by_text("S1 S8 Eight").first.wait_for(timeout=30_000)  # the page's event list
    page.get_by_text("S0 S6 Step 6").first.wait_for(timeout=30_000)

    def corners() -> dict[int, tuple[int, int]]:
        return {n: live_point(page, view, n) for n in (6, 7, 8)}

    colours = {8: ACTIVE, 6: INACTIVE, 7: INACTIVE}
    assert wait_until(lambda: shows(page, corners, colours), 30, poll=0.5)
    run_to(cpu, "g8", 7)  # S8 -> S7
    assert wait_until(lambda: watch.saw("active S7", "S0:S8", "S1:S7")), watch.lines
    page.get_by_text("S0 S8 Eight").first.wait_for(timeout=30_000)
    page.get_by_text("S1 S7 Step 7").first.wait_for(timeout=30_000)
    colours = {8: INACTIVE, 6: INACTIVE, 7: ACTIVE}
    assert wait_until(lambda: shows(page, corners, colours), 30, poll=0.5)
    assert not any("S1:S7" in line and "active S8" in line for line in watch.lines)

    click(page, "MAN")  # a click on S8 of the live chart names S8 in a command
    assert wait_until(lambda: cpu.session.graph.state.mode == "MAN")
    page.mouse.click(*corners()[8])  # where the page showed it active
    panel = next(p for p in view.panels.values() if p.editor is not None)
    assert wait_until(lambda: int(panel.step_number.value) == 8)
    click(page, "Activate")
    assert wait_until(lambda: active(cpu) == [7, 8] or active(cpu) == [8, 7])
    click(page, "Deactivate")
    assert wait_until(lambda: active(cpu) == [7])
    assert wait_until(lambda: watch.saw("S0:S8") and watch.saw("active S7 S8"))

    rows = read_audit(cpu.state)
    download = [r for r in rows if r.op == "download" and r.outcome == "applied"][-1]
    assert "S8" in download.detail and download.user == "eng"
    moves = [r for r in rows if r.op in ("step_on", "step_off")]
    steps = [(r.op, r.detail.split(": ", 1)[-1].split("; ")[0]) for r in moves]
    assert steps == [("step_on", "FB Seq_chain: S8"), ("step_off", "FB Seq_chain: S8")]
    assert all(r.detail.endswith(")") and "; claimed origin: page " in r.detail for r in moves)
    audit = panel.audit_html  # the page's Audit panel
    assert wait_until(lambda: "step_off" in audit.content and "8" in audit.content)


def test_after_undo_download_the_page_draws_the_chart_being_edited(
    page: Page, cpu: OnlineRig
) -> None:
    click(page, "Edit mode")
    page.get_by_role("button", name="Leave edit mode").wait_for(timeout=30_000)
    ed = editor(cpu)
    click(page, "Undo download")
    page.get_by_text("What changes").first.wait_for(timeout=PREVIEW_MS)
    click(page, "Undo the download")
    page.get_by_text("undo download applied").first.wait_for(timeout=30_000)
    assert cpu.session.graph.cc.step_numbers == tuple(range(1, 8))
    view = view_of(cpu)
    assert wait_until(lambda: sorted(view.boxes) == list(range(1, 8)))  # the live chart
    s = ed.session
    assert s is not None and [x.number for x in s.chart.sequences[0].steps] == list(range(1, 8))

    # the page looks at the chart it edits, not at the live one
    assert wait_until(lambda: float(ed.client.camera.look_at[1]) < -1000)
    select(page, ed, "T6 Go6", TransitionRef(6))
    click(page, "Step + Transition")  # an edit: S8 again, drawn and selected
    assert wait_until(lambda: ed._drawing is not None and 8 in ed._drawing.boxes)
    drawing = ed._drawing
    assert drawing is not None  # (the selection's blue shows a little paler: within 35)

    def corner() -> dict[int, tuple[int, int]]:
        return {n: edit_point(page, ed, drawing, n) for n in (6, 8)}

    assert wait_until(lambda: shows(page, corner, {8: SELECTED}, 35), 30, poll=0.5)
    select(page, ed, "T8 Trans8", TransitionRef(8))
    type_into(page, "Condition", "g8 AND nosuch")  # its diagnostic on the page
    page.get_by_text("error[E042] unknown name 'nosuch'").first.wait_for(timeout=30_000)
    page.mouse.click(*corner()[6])  # a click on a step of the drawing selects it
    assert wait_until(lambda: ed.session is not None and ed.session.selection == StepRef(6))
    page.get_by_text("step S6 Step 6", exact=True).first.wait_for(timeout=30_000)
    assert wait_until(lambda: shows(page, corner, {6: SELECTED}, 35), 30, poll=0.5)


def test_open_offers_each_chart_of_a_file_that_holds_several(page: Page, cpu: OnlineRig) -> None:
    """A file with two charts cannot open as one: the CPU's refusal names them and *Open
    file* offers each (``two.st » Blink``); opening one proposes ``two_Blink.s7g``."""
    shutil.copy(synthetic("il_beside_chart.st"), cpu.path.parent / "two.st")
    leave = page.get_by_role("button", name="Leave edit mode")
    leave.click()  # the last test's edits were not downloaded: the page asks first
    click(page, "Stay in edit mode")
    assert editor(cpu).editing
    leave.click()
    click(page, "Leave and drop the edits")
    click(page, "Edit mode")  # the Open file list is read on entering
    leave.wait_for(timeout=30_000)
    ed = editor(cpu)
    assert wait_until(lambda: "two.st" in ed.open_choice.options)
    choose(page, "Open file", "two.st")
    assert wait_until(lambda: ed.open_choice.value == "two.st")
    click(page, "Open")
    assert wait_until(lambda: ed.open_choice.value == "two.st » Blink")
    assert {"two.st » Blink", "two.st » Count"} <= set(ed.open_choice.options)
    page.get_by_text("two.st: choose a chart").first.wait_for(timeout=30_000)
    choose(page, "Open file", "two.st » Count")
    assert wait_until(lambda: ed.open_choice.value == "two.st » Count")
    click(page, "Open")
    assert wait_until(lambda: ed.session is not None and ed.session.chart.name == "Count")
    assert wait_until(lambda: ed.file.value == "two_Count.s7g")  # set just after the session


def test_a_page_download_of_an_edit_made_before_another_download_is_refused(
    page: Page, cpu: OnlineRig
) -> None:
    """The page's download names the version its edit was made from: after someone else's
    download, the CPU refuses it with the reason, instead of the edit silently undoing the
    other one (docs/online-change.md)."""
    leave = page.get_by_role("button", name="Leave edit mode")
    leave.click()  # the last test opened a chart of a file, unedited: no question
    click(page, "Edit mode")
    leave.wait_for(timeout=30_000)
    ed = editor(cpu)
    assert wait_until(lambda: ed.session is not None and ed.session.chart.name == "Seq_chain")
    assert wait_until(lambda: ed.base is not None)
    other = cpu.path.read_text(encoding="utf-8").replace('S3 "Step 3"', 'S3 "Heating"')
    with (
        open_session(connect=[cpu.endpoint], tls=cpu.tls) as bus,
        BusClient(bus, "cpu1") as client,
    ):
        login = client.login("eng", PASSWORD)
        assert login.ok, login.reason
        sent = Command(
            op="download", fb="Seq_chain", user="eng", token=login.token, args={"source": other}
        )
        done = client.send(sent, timeout=60)
        assert done.applied, done.reason
    select(page, ed, "S2 Step 2", StepRef(2))
    type_into(page, "Name", "Two")
    assert wait_until(lambda: ed.session is not None and "Two" in str(ed.source.value))
    click(page, "Download")
    page.get_by_text("someone downloaded meanwhile", exact=False).first.wait_for(timeout=60_000)
    names = {s.number: s.name for s in cpu.session.graph.cc.chart.sequences[0].steps}
    assert names[3] == "Heating" and names[2] == "Step 2"  # theirs kept, nothing of ours
