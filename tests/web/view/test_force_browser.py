"""The page's Force folder in a real headless Chromium, against a chart on the virtual clock
on a real bus: an engineer forces an input from the page, every page shows the yellow FORCE
mark and the engineer's the active job, Unforce gives it back; Modify writes a value once
without a force job, and *Details* offers *Modify to 1/0* on the contact that blocks; an
operator's page has neither."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING

import pytest

from s7graph.web.access.audit import read_audit
from tests.web.bus.test_bus_force import CHART
from tests.web.helpers import (
    PASSWORD,
    OnlineRig,
    chromium_page,
    field,
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
USERS = {"eng": "engineer", "olga": "operator"}


@pytest.fixture
def cpu(tmp_path_factory: pytest.TempPathFactory, bus_certs: BusCerts) -> Iterator[OnlineRig]:
    tmp = tmp_path_factory.mktemp("force")
    with online_cpu(tmp, CHART, serve=True, users=USERS, certs=bus_certs, name="lamp.s7g") as rig:
        yield rig


@contextmanager
def _open(url: str) -> Iterator[Page]:
    with chromium_page(url) as page:
        page.get_by_role("button", name="Log in", exact=True).wait_for(timeout=30_000)
        yield page


def _active(cpu: OnlineRig) -> list[int]:
    g = cpu.session.graph
    return [n for n, x in zip(g.cc.step_numbers, g.state.x, strict=True) if x]


def _engineers_force_folder(page: Page, address: str, value: str) -> None:
    """Log in as the engineer, open the Force folder, fill in ``address`` and ``value``."""
    log_in(page, "eng", PASSWORD)
    page.get_by_text("Force", exact=True).first.click()  # open the folder
    fill(page, "Address", address)
    fill(page, "Value", value)


def test_an_engineer_forces_from_the_page_and_every_page_shows_force(cpu: OnlineRig) -> None:
    with _open(cpu.edge.url) as page:
        _engineers_force_folder(page, "Start", "TRUE")
        page.get_by_role("button", name="Force", exact=True).click()
        page.get_by_text("force applied").first.wait_for(timeout=30_000)
        assert wait_until(lambda: _active(cpu) == [2], 20)  # OB1 read the forced input
        page.get_by_text("FORCE", exact=True).first.wait_for(timeout=30_000)  # the FRCE LED
        page.get_by_text('"Start" = TRUE').first.wait_for(timeout=30_000)  # the list
        rows = [(r.user, r.outcome) for r in read_audit(cpu.state) if r.op == "force"]
        assert rows == [("eng", "applied")]

        field(page, "Value").fill("")
        page.get_by_role("button", name="Unforce", exact=True).click()
        page.get_by_text("no force job active").first.wait_for(timeout=30_000)
        assert wait_until(lambda: _active(cpu) == [1], 20)
        assert page.get_by_text("FORCE", exact=True).count() == 0

        field(page, "Address").fill("DB1.DBX0.0")
        field(page, "Value").fill("TRUE")
        field(page, "Value").press("Tab")
        page.get_by_role("button", name="Force", exact=True).click()
        page.get_by_text("DB1.DBX0.0 cannot be forced").first.wait_for(timeout=30_000)


def test_an_engineer_modifies_from_the_page_once_without_a_force_job(cpu: OnlineRig) -> None:
    with _open(cpu.edge.url) as page:
        _engineers_force_folder(page, "Start", "TRUE")
        page.get_by_role("button", name="Modify", exact=True).click()
        page.get_by_text("modify applied").first.wait_for(timeout=30_000)
        assert wait_until(lambda: _active(cpu) == [2], 20)  # OB1 read the modified input
        assert len(cpu.session.cpu.forces) == 0
        page.get_by_text("no force job active").first.wait_for(timeout=30_000)
        assert page.get_by_text("FORCE", exact=True).count() == 0  # no FRCE LED
        rows = [(r.user, r.outcome) for r in read_audit(cpu.state) if r.op == "modify"]
        assert rows == [("eng", "applied")]


def test_an_engineer_modifies_the_contact_that_blocks_from_details(cpu: OnlineRig) -> None:
    with _open(cpu.edge.url) as page:
        log_in(page, "eng", PASSWORD)
        to_1 = page.get_by_role("button", name="Modify to 1", exact=True)
        to_1.wait_for(timeout=30_000)
        assert wait_until(lambda: to_1.is_enabled(), 30)  # S1 shown: T1 := "Start"
        to_1.click()
        page.get_by_text("modify applied").first.wait_for(timeout=30_000)
        assert wait_until(lambda: _active(cpu) == [2], 20)  # the modified input switched T1
        to_0 = page.get_by_role("button", name="Modify to 0", exact=True)
        to_0.click()  # S2 shown now: T2 := NOT "Start"
        assert wait_until(lambda: _active(cpu) == [1], 20)
        assert len(cpu.session.cpu.forces) == 0
        rows = [(r.user, r.outcome) for r in read_audit(cpu.state) if r.op == "modify"]
        assert rows == [("eng", "applied")] * 2


def test_an_operators_page_has_no_force_folder(cpu: OnlineRig) -> None:
    with _open(cpu.edge.url) as page:
        log_in(page, "olga", PASSWORD)
        page.get_by_role("button", name="Initialize", exact=True).wait_for(timeout=30_000)
        assert page.get_by_role("button", name="Unforce all", exact=True).count() == 0
        view = cpu.edge.edge.view if cpu.edge.edge is not None else None
        assert view is not None
        assert wait_until(lambda: all(p.role == "operator" for p in view.panels.values()))
        assert all(p.force_folder is None for p in view.panels.values())
        assert all(p.contact_modify is None for p in view.panels.values())
        assert page.get_by_role("button", name="Modify to 1", exact=True).count() == 0
