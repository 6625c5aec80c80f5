"""The chart page's watch table in a real headless Chromium, against a chart on the virtual
clock on a real bus: a page not logged in (reading is a viewer's) types operands into
*Watch*; the values follow the CPU and an operand that cannot be read says why — the same
table a program's page has (tests/web/view/test_diagnostics_browser.py); an engineer's
page modifies a watched operand with *Modify now*."""

from __future__ import annotations

from typing import TYPE_CHECKING

import pytest

from tests.web.helpers import PASSWORD, OnlineRig, fill, log_in, needs_chromium, wait_until
from tests.web.view.test_force_browser import _open, cpu  # noqa: F401  (the fixture)

if TYPE_CHECKING:
    from playwright.sync_api import Page

pytestmark = [pytest.mark.timeout(240), needs_chromium]
pytest.importorskip("playwright.sync_api", reason="playwright is not installed")


def _table(page: Page) -> str:
    return page.locator("table", has_text="MW20").first.inner_text()


def test_a_viewers_chart_page_watches_operands_as_the_cpu_reads_them(cpu: OnlineRig) -> None:  # noqa: F811
    with _open(cpu.edge.url) as page:
        page.get_by_text("Watch", exact=True).first.click()  # open the folder
        fill(page, "Operands", '"Start", MW20:INT, MW99999')
        assert wait_until(lambda: "FALSE" in _table(page), 30)
        assert "outside" in _table(page).split("MW99999", 1)[1]  # why it cannot be read
        cpu.session.cpu.mem.set("MW20", -5)
        cpu.session.cpu.mem.periph_in[0] |= 1  # "Start" on the module
        assert wait_until(lambda: "TRUE" in _table(page) and "-5" in _table(page), 20)
        fill(page, "Operands", "")
        page.get_by_text("type operands above").first.wait_for(timeout=30_000)


def test_an_engineer_modifies_a_watched_operand_now(cpu: OnlineRig) -> None:  # noqa: F811
    with _open(cpu.edge.url) as page:
        page.get_by_text("Watch", exact=True).first.click()  # open the folder
        assert page.get_by_role("button", name="Modify now", exact=True).count() == 0
        log_in(page, "eng", PASSWORD)
        now = page.get_by_role("button", name="Modify now", exact=True)
        now.wait_for(timeout=30_000)
        fill(page, "Modify value", "-7")
        fill(page, "Operands", "MW20:INT, DB1.count")  # DB1.count: watched, not modified
        assert wait_until(lambda: now.is_enabled(), 30)
        now.click()
        page.get_by_text("modify applied").first.wait_for(timeout=30_000)
        assert wait_until(lambda: "-7" in _table(page), 20)
        assert cpu.session.cpu.mem.get("MW20") == 0xFFF9 and len(cpu.session.cpu.forces) == 0
