"""A program's page lists the messages of its ALARM_SQ / ALARM_S calls and acknowledges one,
in a real headless Chromium over a real bus: a viewer's button is disabled, an operator's
click acknowledges the message — audited — and the list empties (docs/view.md, "A
program's page")."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from s7graph.engine import Cpu
from s7graph.engine.clock import SystemClock
from s7graph.sfb import install
from s7graph.web.access.audit import read_audit
from tests.web.bus.test_alarm_feed import main
from tests.web.helpers import (
    ProgramPage,
    chromium_page,
    log_in,
    needs_chromium,
    program_page,
    wait_until,
)

pytestmark = [pytest.mark.timeout(240), needs_chromium]
pytest.importorskip("playwright.sync_api", reason="playwright is not installed")


@pytest.fixture
def program(tmp_path: Path) -> Iterator[ProgramPage]:
    """A program raising an ALARM_SQ message, scanned by a runner, on the bus, its page."""
    cpu = Cpu(SystemClock(), max_cycle_ms=5000)
    install(cpu)
    cpu.load(main)
    with program_page(cpu, tmp_path) as running:
        yield running


def test_a_programs_page_lists_its_messages_and_an_operator_acknowledges_one(
    program: ProgramPage,
) -> None:
    with chromium_page(program.view.url) as page:
        page.get_by_text("s7graph CPU cpu1 (a program)").first.wait_for(timeout=30_000)
        button = page.get_by_role("button", name="Acknowledge message 7", exact=True)
        button.wait_for(timeout=30_000)
        page.get_by_text("unacknowledged").first.wait_for(timeout=30_000)
        assert button.is_disabled()  # a viewer's page
        log_in(page, "olga")
        assert wait_until(button.is_enabled, 30)
        button.click()
        page.get_by_text("acknowledge message applied").first.wait_for(timeout=30_000)
        button.wait_for(state="detached", timeout=30_000)
    audited = [(r.op, r.outcome) for r in read_audit(program.state)]
    assert ("ack_msg", "applied") in audited
