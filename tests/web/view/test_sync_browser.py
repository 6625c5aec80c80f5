"""The page's *Synchronization* in a real headless Chromium, against a chart on the virtual
clock on a real bus: a viewer's page finds where the process stands (the steps whose
interlock holds and whose next transition does not, the likely one first, framed on its
chart until cleared) and cannot set it; an operator's page switches to MAN and sets the
step found in one call — the step active there leaves."""

from __future__ import annotations

from typing import TYPE_CHECKING

import pytest

from tests.web.helpers import PASSWORD, OnlineRig, log_in, needs_chromium, wait_until
from tests.web.view.test_force_browser import _open, cpu  # noqa: F401  (the fixture)

if TYPE_CHECKING:
    from playwright.sync_api import Page

pytestmark = [pytest.mark.timeout(240), needs_chromium]
pytest.importorskip("playwright.sync_api", reason="playwright is not installed")


def _found(page: Page) -> str:
    return page.locator("table", has_text="seq 1").first.inner_text()


def _find(page: Page, likely: str) -> None:
    """Click *Find steps* until the table names ``likely`` as the likely step."""
    page.get_by_role("button", name="Find steps", exact=True).click()
    assert wait_until(lambda: f"{likely}\tseq 1\tlikely" in _found(page), 30), _found(page)


def test_a_page_finds_where_the_process_stands_and_an_operator_resumes_there(
    cpu: OnlineRig,  # noqa: F811
) -> None:
    with _open(cpu.edge.url) as page:
        page.get_by_text("Synchronization", exact=True).first.click()  # open the folder
        _find(page, "S1 Idle")  # "Start" off: T2 into S1 holds, T1 out of it does not
        assert wait_until(lambda: _framed(cpu) == ["/sync/likely"], 10)  # on that page
        page.get_by_role("button", name="Clear marks", exact=True).click()
        assert wait_until(lambda: _framed(cpu) == [], 10)
        assert "1 of 2 steps fit" in page.locator("div", has_text="steps fit").last.inner_text()
        activate = page.get_by_role("button", name="Set in MAN", exact=True)
        assert activate.count() == 0 or not activate.is_visible()  # a viewer's page
        log_in(page, "olga", PASSWORD)
        page.get_by_role("button", name="MAN", exact=True).click()
        assert wait_until(lambda: cpu.session.graph.state.mode == "MAN", 30)
        cpu.session.cpu.mem.periph_in[0] |= 1  # "Start" on: the lamp's step is where it is
        assert wait_until(lambda: "S2 Lit\tseq 1\tlikely" in _refound(page), 30)
        activate.wait_for(timeout=30_000)
        assert wait_until(activate.is_enabled, 30)
        activate.click()
        page.get_by_text("set step 2 applied").first.wait_for(timeout=30_000)
        state = cpu.session.graph.state
        assert wait_until(lambda: state.x[1] and not state.x[0], 30)  # S2 in, S1 out


def _refound(page: Page) -> str:
    page.get_by_role("button", name="Find steps", exact=True).click()
    page.wait_for_timeout(300)
    return _found(page)


def _framed(rig: OnlineRig) -> list[str]:
    """The frames the page's *Synchronization* drew around steps (one page open)."""
    assert rig.edge.edge is not None and rig.edge.edge.view is not None
    (panel,) = rig.edge.edge.view.panels.values()
    assert panel.sync_view is not None
    return list(panel.sync_view.framed)
