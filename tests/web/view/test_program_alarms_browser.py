"""A program's page lists the messages of its ALARM_SQ / ALARM_S calls and acknowledges one,
in a real headless Chromium over a real bus: a viewer's button is disabled, an operator's
click acknowledges the message — audited — and the list empties (docs/view.md, "A
program's page")."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

from s7graph.engine import Cpu
from s7graph.engine.clock import SystemClock
from s7graph.engine.persistence import StateStore
from s7graph.engine.record import ScanRecord
from s7graph.engine.runner import Runner
from s7graph.sfb import install
from s7graph.web.access.audit import read_audit
from s7graph.web.bus.gate import cpu_gate
from s7graph.web.bus.session import BusEnds
from s7graph.web.view.edge import ViewSide
from s7graph.web.wiring.program_edge import ProgramEdge
from tests.web.bus.test_alarm_feed import main
from tests.web.bus.test_diag_watch import free_port
from tests.web.helpers import chromium_page, log_in, needs_chromium, wait_until

pytestmark = [pytest.mark.timeout(240), needs_chromium]
pytest.importorskip("playwright.sync_api", reason="playwright is not installed")


@dataclass
class Program:
    runner: Runner
    view: ViewSide
    state: Path


@pytest.fixture
def program(tmp_path: Path) -> Iterator[Program]:
    """A program raising an ALARM_SQ message, scanned by a runner, on the bus, its page."""
    cpu = Cpu(SystemClock(), max_cycle_ms=5000)
    install(cpu)
    cpu.load(main)
    store = StateStore(tmp_path / "state.sqlite")
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    edge = ProgramEdge(cpu, ends=BusEnds(listen=[endpoint]), gate=cpu_gate(None, store))
    runner: Runner

    def on_record(record: ScanRecord) -> None:
        edge.on_record(record, stats=cpu.stats, runner=runner)

    runner = Runner(cpu, store=store, on_record=on_record, rt_priority=None, idle_gc=False)
    runner.startup()
    runner.start_thread(duration_s=200)
    view = None
    try:
        view = ViewSide(cpu="cpu1", fb=None, ends=BusEnds(connect=[endpoint]), port=0)
        yield Program(runner, view, store.path)
    finally:
        if view is not None:
            view.close()
        runner.shutdown("test ended")
        edge.close()
        store.close()


def test_a_programs_page_lists_its_messages_and_an_operator_acknowledges_one(
    program: Program,
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
        page.get_by_text("ack_msg applied").first.wait_for(timeout=30_000)
        button.wait_for(state="detached", timeout=30_000)
    audited = [(r.op, r.outcome) for r in read_audit(program.state)]
    assert ("ack_msg", "applied") in audited
