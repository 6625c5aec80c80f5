"""The page's alarm list in a real headless Chromium, against a chart of two sequences whose
interlocks are lost together, on the virtual clock and a real bus with a users file: the
list filtered by sequence and to the unacknowledged messages, and *Acknowledge all* sending
one audited ``ack_msg`` per message. (An interlock message acknowledged stays listed while
its interlock is lost, a supervision message acknowledged after its cause went does not.)"""

from __future__ import annotations

import json
from collections.abc import Iterator
from typing import TYPE_CHECKING

import pytest

from s7graph.web.access.audit import read_audit
from s7graph.web.view.alarms import ALL, UNACKNOWLEDGED
from s7graph.web.view.chart_view import ChartView
from tests.web.helpers import (
    PASSWORD,
    OnlineRig,
    chromium_page,
    log_in,
    needs_chromium,
    online_cpu,
    wait_until,
)
from tests.web.view.test_edit_browser import choose

if TYPE_CHECKING:
    from playwright.sync_api import Page

pytestmark = [pytest.mark.timeout(240), needs_chromium]
pytest.importorskip("playwright.sync_api", reason="playwright is not installed")

CHART = """\
FUNCTION_BLOCK "Ovens" FB 1 DB 1
  PARAMETERS := STANDARD;
  ACK_REQUIRED := TRUE; MESSAGES := TRUE;
SYMBOLS
  "Go" : I0.0 : BOOL;
  "Door" : I0.1 : BOOL;
END_SYMBOLS
SEQUENCE 1 "Left"
  INITIAL_STEP S1 "Idle":
  END_STEP
  STEP S2 "Heat" "left oven door open":
    INTERLOCK := "Door";
  END_STEP
  TRANSITION T1 FROM S1 TO S2 := "Go";
  TRANSITION T2 FROM S2 TO S1 := NOT "Go";
END_SEQUENCE
SEQUENCE 2 "Right"
  INITIAL_STEP S11 "Idle":
  END_STEP
  STEP S12 "Heat" "right oven door open":
    INTERLOCK := "Door";
  END_STEP
  TRANSITION T11 FROM S11 TO S12 := "Go";
  TRANSITION T12 FROM S12 TO S11 := NOT "Go";
END_SEQUENCE
END_FUNCTION_BLOCK
"""

if TYPE_CHECKING:
    from tests.conftest import BusCerts


@pytest.fixture(scope="module")
def cpu(tmp_path_factory: pytest.TempPathFactory, bus_certs: BusCerts) -> Iterator[OnlineRig]:
    tmp = tmp_path_factory.mktemp("alarms")
    users = {"olga": "operator"}
    with online_cpu(
        tmp, CHART, serve=True, users=users, name="ovens.s7g", messages=True, certs=bus_certs
    ) as rig:
        yield rig


@pytest.fixture(scope="module")
def page(cpu: OnlineRig) -> Iterator[Page]:
    with chromium_page(cpu.edge.url) as pg:
        pg.get_by_role("button", name="Log in", exact=True).wait_for(timeout=30_000)
        log_in(pg, "olga", PASSWORD)
        yield pg


def view_of(cpu: OnlineRig) -> ChartView:
    assert cpu.edge.edge is not None
    return cpu.edge.edge.view


def doors_open(cpu: OnlineRig) -> None:
    """S2 and S12 active with their interlocks lost: a message each to acknowledge."""
    cpu.session.set("Go", True)
    cpu.session.set("Door", False)
    graph = cpu.session.graph

    def lost() -> bool:
        st = graph.state
        return sum(bool(st.il_err[graph.cc.step_index[n]]) for n in (2, 12)) == 2

    assert wait_until(lost, 20)


def test_acknowledge_all_sends_one_audited_ack_msg_per_message(cpu: OnlineRig, page: Page) -> None:
    doors_open(cpu)
    (panel,) = view_of(cpu).panels.values()
    alarms = panel.alarms
    assert wait_until(lambda: len([e for e in alarms.shown() if not e.acked]) == 2, 20)
    pending = {str(e.msg_id) for e in alarms.shown() if not e.acked}
    # filtered by sequence: the right oven's message alone, and one to acknowledge
    choose(page, "Sequence", "2 Right")  # the list is filtered when the button says so
    page.get_by_role("button", name="Acknowledge all (1)", exact=True).wait_for(timeout=30_000)
    page.get_by_text("right oven door open").first.wait_for(timeout=30_000)
    assert wait_until(lambda: [e.step for e in alarms.shown()] == [12], 20)
    choose(page, "Sequence", "every sequence")
    button = page.get_by_role("button", name="Acknowledge all (2)", exact=True)
    button.wait_for(timeout=30_000)
    button.click()
    page.get_by_text("2 messages acknowledged").first.wait_for(timeout=30_000)
    rows = [r for r in read_audit(cpu.state) if r.op == "ack_msg"]
    assert [(r.user, r.outcome) for r in rows] == [("olga", "applied")] * 2
    assert {str(json.loads(r.args)["msg_id"]) for r in rows} == pending  # one per message
    assert wait_until(lambda: [e.acked for e in alarms.shown()] == [True, True], 20)
    page.get_by_text("acknowledged by olga").first.wait_for(timeout=30_000)
    page.get_by_role("button", name="Acknowledge all", exact=True).wait_for(timeout=30_000)
    assert page.get_by_role("button", name="Acknowledge all", exact=True).is_disabled()


def test_the_filter_hides_acknowledged_messages(cpu: OnlineRig, page: Page) -> None:
    (panel,) = view_of(cpu).panels.values()
    alarms = panel.alarms
    assert wait_until(lambda: any(e.acked for e in alarms.shown()), 20)  # the previous test's
    choose(page, "Show", UNACKNOWLEDGED)
    page.get_by_text("no unacknowledged messages").first.wait_for(timeout=30_000)
    assert alarms.shown() == [] and page.get_by_text("acknowledged by olga").count() == 0
    cpu.session.set("Door", True)  # the messages go, acknowledged: off the list
    assert wait_until(lambda: alarms.alarms is not None and not alarms.alarms.entries, 20)
    cpu.session.set("Door", False)  # lost again: new, unacknowledged messages
    assert wait_until(lambda: len(alarms.shown()) == 2, 20)
    page.get_by_role("button", name="Acknowledge all (2)", exact=True).wait_for(timeout=30_000)
    assert all(not e.acked for e in alarms.shown())
    assert page.get_by_text("acknowledged by olga").count() == 0
    page.get_by_role("button", name="Acknowledge all (2)", exact=True).click()
    page.get_by_text("no unacknowledged messages").first.wait_for(timeout=30_000)
    choose(page, "Show", ALL)
    page.get_by_text("acknowledged by olga").first.wait_for(timeout=30_000)
    assert [e.acked for e in alarms.shown()] == [True, True]
