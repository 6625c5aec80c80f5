"""Edit mode in a real headless Chromium against a chart running on the virtual clock, with a users
file, a real zenoh bus and the CPU's online change (docs/online-change.md): an operator and a
viewer get no edit mode; an invalid edit shows its diagnostic with line and column while the CPU
keeps its chart; an engineer changes a transition condition, downloads, and the running sequence
follows the new condition; the source view is as tall as the page; a chart built from scratch
in the browser (three steps, an alternative branch, a jump) downloads and runs; a read of the
CPU's S7-SCL FB's variable by name (``DB12.n``) is no error in the editor and downloads, one of
a variable the FB lacks is E048; a call that does not fit that FB is E047 on the page and its
download refused there.
One browser, one page for the module (CI has 2 cores); the tests run in order on it."""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from s7graph.sequencer.text.elements import StepRef, TransitionRef, find
from s7graph.sequencer.text.format import format_chart, format_expr
from s7graph.sequencer.text.model import Transition
from s7graph.web.view.editor import Editor
from s7graph.web.view.uses_list import use_label
from tests.web.bus.test_online_change import CHART
from tests.web.helpers import (
    PASSWORD,
    PREVIEW_MS,
    OnlineRig,
    chromium_page,
    fill,
    log_in,
    needs_chromium,
    online_cpu,
    wait_until,
)

if TYPE_CHECKING:
    from playwright.sync_api import Page

    from tests.conftest import BusCerts

pytestmark = [pytest.mark.timeout(240), needs_chromium]
pytest.importorskip("playwright.sync_api", reason="playwright is not installed")
USERS = {"eng": "engineer", "olga": "operator", "vic": "viewer"}
BLOCKS = """// beside the chart: reads what step S2 writes
FUNCTION FC 5 : VOID
BEGIN
  M1.0 := Q0.0;
END_FUNCTION

// counts its calls: a chart reads n by name (DB12.n)
FUNCTION_BLOCK FB17
VAR_INPUT go : BOOL; END_VAR
VAR n : INT; END_VAR
  IF go THEN n := n + 1; END_IF;
END_FUNCTION_BLOCK
"""


@pytest.fixture(scope="module")
def cpu(tmp_path_factory: pytest.TempPathFactory, bus_certs: BusCerts) -> Iterator[OnlineRig]:
    tmp = tmp_path_factory.mktemp("edit")
    blocks = {"fill_blocks.scl": BLOCKS}
    with online_cpu(
        tmp, CHART, serve=True, users=USERS, certs=bus_certs, name="fill.s7g", blocks=blocks
    ) as rig:
        yield rig


@pytest.fixture(scope="module")
def page(cpu: OnlineRig) -> Iterator[Page]:
    with chromium_page(cpu.edge.url) as pg:
        pg.get_by_role("button", name="Log in", exact=True).wait_for(timeout=30_000)
        yield pg


def editor(cpu: OnlineRig) -> Editor:
    """The editor of the (only) page."""
    view = cpu.edge.edge.view if cpu.edge.edge is not None else None
    assert view is not None
    assert wait_until(lambda: any(p.editor is not None for p in view.panels.values()))
    found = next(p.editor for p in view.panels.values() if p.editor is not None)
    assert found is not None
    return found


def log_out(page: Page) -> None:
    page.get_by_role("button", name="Log out", exact=True).click()
    page.get_by_text("viewer: log in").first.wait_for(timeout=30_000)


def choose(page: Page, label: str, option: str) -> None:
    """Pick ``option`` in the viser dropdown ``label``."""
    row = "ancestor::div[contains(@class,'mantine-Flex-root')][1]"
    page.locator(f"xpath=//label[text()='{label}']/{row}//input").first.click()
    page.get_by_role("option", name=option, exact=True).click()


def select(page: Page, ed: Editor, option: str, ref: object) -> None:
    """Select an element in the Element dropdown and wait for its form on the page. The
    choice is made again when it did not reach the view: the dropdown's options are
    re-sent after every edit, and a popup open while they arrive may lose the click."""
    for _ in range(3):
        choose(page, "Element", option)
        if wait_until(lambda: ed.session is not None and ed.session.selection == ref, 5):
            break
        page.keyboard.press("Escape")
    assert ed.session is not None and ed.session.selection == ref
    kind = "step" if option.startswith("S") else "transition"
    page.get_by_text(f"{kind} {option}", exact=True).first.wait_for(timeout=30_000)


def type_into(page: Page, label: str, text: str) -> None:
    fill(page, label, text)  # it reaches the view before the next input (GUI_SETTLE_MS)


def condition(ed: Editor, n: int) -> str:
    assert ed.session is not None
    t = find(ed.session.chart, TransitionRef(n))
    assert isinstance(t, Transition)
    return "" if t.condition is None else format_expr(t.condition)


def steps(ed: Editor) -> int:
    return len(ed.session.chart.sequences[0].steps) if ed.session is not None else 0


def click(page: Page, name: str) -> None:
    page.get_by_role("button", name=name, exact=True).click()


def active(cpu: OnlineRig) -> list[int]:
    g = cpu.session.graph
    return [n for n, x in zip(g.cc.step_numbers, g.state.x, strict=True) if x]


def screenshot(page: Page, path: Path) -> None:
    """The page without its notifications, as a small palette PNG."""
    from PIL import Image

    buttons = page.locator(".mantine-Notification-closeButton").locator("visible=true")

    def closed() -> bool:
        for button in buttons.all():
            with contextlib.suppress(Exception):  # it may close by itself meanwhile
                button.click(timeout=1_000)
        return buttons.count() == 0

    assert wait_until(closed, timeout=30)
    raw = path.with_suffix(".raw.png")
    page.screenshot(path=str(raw))
    with Image.open(raw) as image:
        image.convert("RGB").quantize(colors=64).save(path, optimize=True)
    raw.unlink()


def source_typed(page: Page, ed: Editor, text: str) -> None:
    """``text`` typed into the source view, and the chart it makes in the session."""
    box = page.locator("textarea").first
    box.fill(text)
    box.blur()
    assert wait_until(lambda: ed.session is not None and format_chart(ed.session.chart) == text)


def error_codes(ed: Editor) -> list[str]:
    """The codes of the errors the editor lists."""
    return [d.code for d in ed.located.diagnostics if d.is_error]


def test_an_operator_and_a_viewer_get_no_edit_mode(page: Page, cpu: OnlineRig) -> None:
    for user in ("olga", "vic"):
        log_in(page, user, PASSWORD)
        assert page.get_by_role("button", name="Edit mode").count() == 0, user
        log_out(page)
    log_in(page, "eng", PASSWORD)
    page.get_by_role("button", name="Edit mode").wait_for(timeout=30_000)


def test_an_invalid_edit_shows_its_diagnostic_with_line_and_column_and_the_cpu_keeps_its_chart(
    page: Page, cpu: OnlineRig
) -> None:
    running = cpu.session.graph.cc
    click(page, "Edit mode")
    page.get_by_role("button", name="Leave edit mode").wait_for(timeout=30_000)
    ed = editor(cpu)
    select(page, ed, "T2 Full", TransitionRef(2))
    type_into(page, "Condition", "full AND nosuch")
    assert wait_until(lambda: condition(ed, 2) == "full AND nosuch")
    shown = page.get_by_text("error[E042] unknown name 'nosuch'").first
    shown.wait_for(timeout=30_000)
    assert "20:50" in shown.inner_text()  # line 20, column 50 of the source view
    select(page, ed, "S1 Idle", StepRef(1))
    page.get_by_role("button", name="1 · 20:50 E042 · transition T2").click()  # selects T2
    assert wait_until(lambda: ed.session is not None and ed.session.selection == TransitionRef(2))
    keep = os.environ.get("S7GRAPH_EDIT_SCREENSHOT")
    if keep:  # docs/edit-mode.png is made this way
        screenshot(page, Path(keep))
    click(page, "Download")
    page.get_by_text("download refused").first.wait_for(timeout=30_000)
    assert cpu.session.graph.cc is running  # the CPU keeps its chart
    click(page, "Undo")
    assert wait_until(lambda: condition(ed, 2) == "full")


def test_cross_references_list_an_operands_uses_and_a_click_selects_its_element(
    page: Page, cpu: OnlineRig
) -> None:
    ed = editor(cpu)
    select(page, ed, "T1 Go", TransitionRef(1))
    page.get_by_role("tab", name="Cross-references").click()
    choose(page, "Uses of", "pieces")
    page.get_by_text("pieces: 2 uses").first.wait_for(timeout=30_000)  # written and read
    assert ed._xref is not None
    uses = [u for u in ed._xref.uses if u.operand == "pieces"]
    assert [(u.element, u.access) for u in uses] == [
        ('S2 "Fill" row 1 (S1 N)', "write"),
        ('S2 "Fill" row 1 (S1 N)', "read"),
    ]
    page.get_by_role("button", name=use_label(uses[0]), exact=True).click()
    assert wait_until(lambda: ed.session is not None and ed.session.selection == StepRef(2))
    page.get_by_text("step S2 Fill", exact=True).first.wait_for(timeout=30_000)
    choose(page, "Uses of", "Q0.0")  # written by S2, read by FC 5 beside the chart
    page.get_by_text("Q0.0: 2 uses").first.wait_for(timeout=30_000)
    in_block = [u for u in ed._xref.uses if u.operand == "Q0.0"][-1]
    assert (in_block.element, in_block.access, in_block.loc.line) == ("FC 5", "read", 4)
    page.get_by_role("button", name=use_label(in_block), exact=True).click()
    page.get_by_text("M1.0 := Q0.0;").first.wait_for(timeout=30_000)  # FC 5's source
    page.get_by_role("button", name="Close", exact=True).click()
    page.get_by_role("tab", name="Element").click()


def test_an_engineer_changes_a_condition_downloads_and_the_sequence_follows(
    page: Page, cpu: OnlineRig
) -> None:
    ed = editor(cpu)
    assert active(cpu) == [1]
    select(page, ed, "T1 Go", TransitionRef(1))
    type_into(page, "Condition", "full")
    assert wait_until(lambda: condition(ed, 1) == "full")
    assert wait_until(lambda: "FROM S1 TO S2 := full;" in str(ed.source.value))  # the source
    page.get_by_role("tab", name="Source (.s7g)").click()  # view follows; and back:
    box = page.locator("textarea").first
    box.fill(box.input_value().replace("TO S1 := empty;", "TO S1 := empty OR go;"))
    box.blur()
    assert wait_until(lambda: condition(ed, 3) == "empty OR go")  # the text is the chart
    page.get_by_role("tab", name="Element").click()
    click(page, "Download")
    page.get_by_text("What changes").first.wait_for(timeout=PREVIEW_MS)
    assert page.get_by_text("T1").count() >= 1
    click(page, "Download to the CPU")
    page.get_by_text("download applied").first.wait_for(timeout=30_000)
    assert wait_until(lambda: cpu.online.current.number == 2)
    assert "FROM S1 TO S2 := full;" in cpu.path.read_text(encoding="utf-8")
    cpu.session.set("go", False)
    cpu.session.set("full", True)  # the new condition of T1
    assert wait_until(lambda: active(cpu) == [3])  # S1 -> S2 (full) -> S3 (full)
    cpu.session.set("full", False)
    cpu.session.set("empty", True)
    assert wait_until(lambda: active(cpu) == [1])
    cpu.session.set("empty", False)


def test_the_source_view_is_as_tall_as_the_page_not_six_rows(page: Page) -> None:
    page.get_by_role("tab", name="Source (.s7g)").click()
    box = page.locator("textarea").first
    assert wait_until(lambda: "FUNCTION_BLOCK" in box.input_value())
    shown, viewport = box.bounding_box(), page.viewport_size
    assert shown is not None and viewport is not None
    assert shown["height"] > 0.6 * viewport["height"], shown  # Mantine's autosize: 104 px
    page.get_by_role("tab", name="Element").click()


def test_save_to_this_computer_gives_the_browser_the_chart_being_edited(
    page: Page, cpu: OnlineRig
) -> None:
    ed = editor(cpu)
    select(page, ed, "T2 Full", TransitionRef(2))
    type_into(page, "Condition", "full AND NOT go")  # an edit not downloaded
    assert wait_until(lambda: condition(ed, 2) == "full AND NOT go")
    with page.expect_download(timeout=30_000) as started:
        click(page, "Save to this computer")
    got = started.value
    assert got.suggested_filename == "fill.s7g"
    text = Path(got.path()).read_text(encoding="utf-8")
    assert ed.session is not None and text == format_chart(ed.session.chart)
    assert "FROM S2 TO S3 := full AND NOT go;" in text
    assert "FROM S2 TO S3 := full AND NOT go;" not in cpu.path.read_text(encoding="utf-8")
    click(page, "Undo")
    assert wait_until(lambda: condition(ed, 2) == "full")


def test_a_chart_built_from_scratch_downloads_and_runs(page: Page, cpu: OnlineRig) -> None:
    ed = editor(cpu)
    click(page, "New")
    assert wait_until(
        lambda: ed.session is not None and len(ed.session.chart.sequences[0].steps) == 1
    )
    select(page, ed, "T1 Trans1", TransitionRef(1))
    click(page, "Step + Transition")  # S2, T2
    select(page, ed, "T2 Trans2", TransitionRef(2))
    click(page, "Step + Transition")  # S3, T3 (T3 jumps back to S1)
    assert wait_until(lambda: steps(ed) == 3)
    select(page, ed, "S2 Step2", StepRef(2))
    type_into(page, "to", "1")
    click(page, "Alternative branch")  # T4: S2 -> S1
    assert wait_until(lambda: len(ed.session.chart.sequences[0].transitions) == 4)  # type: ignore[union-attr]
    select(page, ed, "S2 Step2", StepRef(2))
    choose(page, "Qualifier", "N")
    type_into(page, "Operand", "Q0.0")
    click(page, "Add action row")
    for n, address in ((1, "I0.0"), (2, "I0.1"), (3, "I0.2"), (4, "I0.3")):
        select(page, ed, f"T{n} Trans{n}", TransitionRef(n))
        type_into(page, "Condition", address)
        assert wait_until(lambda n=n, a=address: condition(ed, n) == a)  # type: ignore[misc]
    assert ed.session is not None and not ed.session.has_errors
    click(page, "Download")
    page.get_by_text("What changes").first.wait_for(timeout=PREVIEW_MS)
    click(page, "Download to the CPU")
    page.get_by_text("download applied").first.wait_for(timeout=30_000)
    cc = cpu.session.graph.cc
    assert wait_until(lambda: cpu.online.current.number == 3)
    assert len(cc.transition_numbers) == 4 and cc.step_numbers == (1, 2, 3)
    cpu.session.set("I0.0", True)
    assert wait_until(lambda: active(cpu) == [2])
    assert wait_until(lambda: cpu.session.get("Q0.0") is True)  # the row made in the browser
    cpu.session.set("I0.0", False)
    cpu.session.set("I0.3", True)  # the alternative branch jumps back to S1
    assert wait_until(lambda: active(cpu) == [1])


def test_a_read_of_the_cpus_fb_variable_by_name_is_checked_in_its_blocks_and_downloads(
    page: Page, cpu: OnlineRig
) -> None:
    """The editor checks ``DB12.n`` in the S7-SCL blocks the CPU runs: no E048, and the
    download (chart alone) reads the FB's variable; ``DB12.nope`` is E048 on the page."""
    ed = editor(cpu)
    cpu.session.set("I0.3", False)
    assert ed.session is not None
    text = format_chart(ed.session.chart)
    calls = text.replace("    N Q0.0;\n", "    N Q0.0;\n    CALL FB 17, DB 12 (go := TRUE);\n")
    reads = calls.replace("FROM S2 TO S3 := I0.1;", "FROM S2 TO S3 := DB12.n > 3;")
    assert "CALL FB 17, DB 12" in reads and "DB12.n > 3" in reads, reads
    page.get_by_role("tab", name="Source (.s7g)").click()
    source_typed(page, ed, reads.replace("DB12.n", "DB12.nope"))
    assert wait_until(lambda: error_codes(ed) == ["E048"])
    page.get_by_role("tab", name="Element").click()  # the diagnostics
    page.get_by_text("nope is not a variable of FB17").first.wait_for(timeout=30_000)
    page.get_by_role("tab", name="Source (.s7g)").click()
    source_typed(page, ed, reads)
    assert wait_until(lambda: error_codes(ed) == [])
    page.get_by_role("tab", name="Element").click()
    assert ed.session is not None and not ed.session.has_errors
    click(page, "Download")
    page.get_by_text("What changes").first.wait_for(timeout=PREVIEW_MS)
    click(page, "Download to the CPU")
    page.get_by_text("download applied").first.wait_for(timeout=30_000)
    assert wait_until(lambda: cpu.online.current.number == 4)
    cpu.session.set("I0.0", True)
    assert wait_until(lambda: active(cpu) == [3])  # S2 called FB17 until its n was 4
    assert int(cpu.session.get("DB12.n")) >= 4


def test_a_call_that_does_not_fit_the_cpus_fb_is_e047_on_the_page_before_any_download(
    page: Page, cpu: OnlineRig
) -> None:
    """The editor checks the chart's calls in the S7-SCL blocks the CPU runs, as a download
    does: ``go := 2.5`` to FB17's BOOL input is E047 on the page, and *Download* is refused
    there, never asking the CPU, which runs its chart on."""
    ed = editor(cpu)
    assert ed.session is not None
    version = cpu.online.current.number
    text = format_chart(ed.session.chart)
    assert "(go := TRUE)" in text, text
    page.get_by_role("tab", name="Source (.s7g)").click()
    source_typed(page, ed, text.replace("(go := TRUE)", "(go := 2.5)"))
    assert wait_until(lambda: error_codes(ed) == ["E047"])
    page.get_by_role("tab", name="Element").click()  # the diagnostics
    page.get_by_text("FB17: go is BOOL, REAL does not fit it").first.wait_for(timeout=30_000)
    click(page, "Download")
    page.get_by_text("download refused: the chart has 1 error(s)").first.wait_for(timeout=30_000)
    assert cpu.online.current.number == version
