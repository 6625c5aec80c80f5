"""The page's Diagnostics folder and a program's page in a real headless Chromium, over a
real bus: a program of blocks (no chart) gets its state, a watch table typed on the page
and its diagnostic buffer; an engineer stops it from the page and the page says why it is
in STOP, resets its memory and starts it again; a chart's page has the Diagnostics folder
too (docs/view.md, "Diagnostics", "A program's page")."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from s7graph.engine.clock import SystemClock
from s7graph.web.access.audit import read_audit
from tests.web.bus.test_bus_force import CHART
from tests.web.bus.test_diag_watch import program_cpu
from tests.web.helpers import (
    ProgramPage,
    chromium_page,
    field,
    fill,
    log_in,
    needs_chromium,
    online_cpu,
    program_page,
    wait_until,
)

pytestmark = [pytest.mark.timeout(240), needs_chromium]
pytest.importorskip("playwright.sync_api", reason="playwright is not installed")

if TYPE_CHECKING:
    from tests.conftest import BusCerts


_SWITCH = ("stop", "mres", "start")


@pytest.fixture
def program(tmp_path: Path) -> Iterator[ProgramPage]:
    """The watch test's program scanned by a runner, on the bus, and its page."""
    cpu = program_cpu(SystemClock())
    with program_page(cpu, tmp_path) as running:
        yield running


def test_a_programs_page_shows_its_state_a_watch_table_and_why_it_stopped(
    program: ProgramPage,
) -> None:
    assert program.view.program is not None and program.view.fb == ""
    with chromium_page(program.view.url) as page:
        page.get_by_text("s7graph CPU cpu1 (a program)").first.wait_for(timeout=30_000)
        page.get_by_text("Mode transition from STARTUP to RUN").first.wait_for(timeout=30_000)
        box = field(page, "Operands")
        box.fill("MW0:INT, DB11.n, DB20.speed, DB99.x")
        box.press("Tab")
        page.get_by_text("DB99 is not loaded").first.wait_for(timeout=30_000)
        page.get_by_text("-5").first.wait_for(timeout=30_000)  # DB20.speed, by its name
        stop = page.get_by_role("button", name="CPU to STOP", exact=True)
        assert stop.is_disabled()  # a viewer's page
        log_in(page, "eng")
        stop.click()  # as TIA Portal, the page asks first; Cancel sends nothing
        page.get_by_text("every output goes to 0").first.wait_for(timeout=30_000)
        page.get_by_role("button", name="Cancel", exact=True).click()
        assert program.runner.cpu.mode.value == "RUN"
        stop.click()
        page.get_by_role("button", name="Stop the CPU", exact=True).click()
        page.get_by_text("STOP by the switch (eng (unverified))").first.wait_for(timeout=30_000)
        page.get_by_text("STOP entry").first.wait_for(timeout=30_000)
        page.get_by_role("button", name="Memory reset (MRES)", exact=True).click()
        page.get_by_role("button", name="Reset the memory", exact=True).click()
        page.get_by_text("Memory reset started by a PG operation").first.wait_for(timeout=30_000)
        page.get_by_role("button", name="CPU to RUN", exact=True).click()
        assert wait_until(lambda: program.runner.cpu.mode.value == "RUN", 30)
        fill(page, "Modify value", "16#7FFF")  # MW0: the only operand it may modify
        page.get_by_role("button", name="Modify now", exact=True).click()
        page.get_by_text("modify applied").first.wait_for(timeout=30_000)
    audit = read_audit(program.state)
    switched = [(r.op, r.outcome) for r in audit if r.op in _SWITCH]
    assert switched == [("stop", "applied"), ("mres", "applied"), ("start", "applied")]
    modified = [(r.outcome, r.detail) for r in audit if r.op == "modify"]
    assert (
        len(modified) == 1
        and modified[0][0] == "applied"
        and "modify MW0 = W#16#7FFF" in modified[0][1]
    )


def test_a_charts_page_has_the_diagnostics_folder(tmp_path: Path, bus_certs: BusCerts) -> None:
    with (
        online_cpu(tmp_path, CHART, serve=True, users={"eng": "engineer"}, certs=bus_certs) as rig,
        chromium_page(rig.edge.url) as page,
    ):
        page.get_by_text("Diagnostics", exact=True).first.click()  # open the folder
        page.get_by_text("Mode transition from STOP to STARTUP").first.wait_for(timeout=30_000)
        page.get_by_text("OB100 · priority class 27").first.wait_for(timeout=30_000)
        page.get_by_role("button", name="Memory reset (MRES)", exact=True).wait_for()
