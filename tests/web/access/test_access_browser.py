"""Logins in a real headless Chromium against the drill chart running on the virtual clock,
with a users file: two pages as two users are audited apart, the alarm list's Acknowledge
releases a latched step and the alarm log names the user, a websocket from a foreign
Origin is refused, and a CPU that goes shows "disconnected". One browser for the module."""

from __future__ import annotations

import re
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import pytest
import viser

from s7graph.engine.clock import VirtualClock
from s7graph.engine.persistence import StateStore
from s7graph.engine.record import ScanRecord
from s7graph.sfb.alarms import message_list
from s7graph.web.access.audit import AuditStore, read_audit
from s7graph.web.access.login import Authenticator
from s7graph.web.access.users import UsersFile
from s7graph.web.bus.gate import Gate
from s7graph.web.bus.live import LiveGraph
from s7graph.web.bus.protocol import Command
from s7graph.web.harness.session import ChartSession, load_chart
from s7graph.web.view.chart_view import DISCONNECTED
from s7graph.web.wiring.live_edge import LiveEdge
from tests.paths import ROOT
from tests.web.helpers import (
    ARGS,
    CHROMIUM,
    log_in,
    needs_chromium,
    scanning,
    wait_until,
)

if TYPE_CHECKING:
    from playwright.sync_api import Browser, Page

pytestmark = [pytest.mark.timeout(240), needs_chromium]
pytest.importorskip("playwright.sync_api", reason="playwright is not installed")
DRILL = ROOT / "examples" / "drill"
FB = "Seq_drill"
SV = f"{FB}/DB1/S2/SV"
PASSWORD = "correct horse"
VISER_SUBPROTOCOL = f"viser-v{viser.__version__}"


@dataclass
class Plant:
    edge: LiveEdge
    session: ChartSession
    state: Path
    stop: threading.Event


@pytest.fixture(scope="module")
def plant(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Plant]:
    tmp = tmp_path_factory.mktemp("plant")
    users = UsersFile(tmp / "users.json")
    for name in ("olga", "otto"):
        users.add(name, "operator", PASSWORD)
    users.add("vic", "viewer", PASSWORD)
    state = tmp / "state.sqlite"
    store = StateStore(state)
    audit = AuditStore(state)
    cc, table = load_chart(DRILL / "drill.s7g", DRILL / "symbols.txt")
    session = ChartSession(cc, table, VirtualClock())
    live = LiveGraph(session.graph, read=session.get, messages=message_list(session.cpu))
    gate = Gate(Authenticator(users), audit)

    def alarm_log(record: ScanRecord) -> None:  # as the runner keeps it
        if record.alarms:
            store.log_alarms(record.alarms, time.time_ns())

    try:
        with LiveEdge(live, port=0, gate=gate) as edge, scanning(session, edge, alarm_log) as stop:
            yield Plant(edge, session, state, stop)
    finally:
        store.close()
        audit.close()


@pytest.fixture(scope="module")
def browser() -> Iterator[Browser]:
    sync_api = pytest.importorskip("playwright.sync_api")
    with sync_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, headless=True, args=ARGS)
        try:
            yield b
        finally:
            b.close()


def open_page(browser: Browser, url: str) -> Page:
    page = browser.new_context(viewport={"width": 1280, "height": 800}).new_page()
    page.goto(url)
    page.get_by_role("button", name="Log in", exact=True).wait_for(timeout=60_000)
    return page


def test_two_pages_as_two_users_are_audited_apart_and_the_alarm_ack_names_its_user(
    plant: Plant, browser: Browser
) -> None:
    edge = plant.edge
    assert edge.edge is not None
    url = edge.url
    first, second = open_page(browser, url), open_page(browser, url)
    init = second.get_by_role("button", name="Initialize", exact=True)
    assert init.is_disabled()  # a viewer until it logs in
    log_in(first, "olga", PASSWORD)
    log_in(second, "otto", PASSWORD)
    assert wait_until(init.is_enabled, 20)

    first.get_by_role("button", name="MAN", exact=True).click()
    first.get_by_text("mode MAN applied").first.wait_for(timeout=30_000)
    second.get_by_role("button", name="Activate", exact=True).click()  # S_ON on step 1
    second.get_by_text(re.compile(r"activate step 1 (applied|refused)")).first.wait_for(
        timeout=30_000
    )

    rows = [r for r in read_audit(plant.state) if r.op in ("mode", "step_on")]
    assert [(r.user, r.op) for r in rows] == [("olga", "mode"), ("otto", "step_on")]
    # one view process, one link: the transport's origin is the same; the pages it vouches
    # for are told apart by the origins it claims, kept as notes
    assert rows[0].origin == rows[1].origin and rows[0].origin.startswith("unixsock-stream/")
    pages = [re.search(r"claimed origin: (page \d+) \(", r.detail) for r in rows]
    assert pages[0] and pages[1] and pages[0][1] != pages[1][1]

    # a supervision fault: S2 active in MAN, its supervision (S2.U > 500 ms) latches
    client = edge.edge.client
    login = client.login("olga", PASSWORD)
    reply = client.send(
        Command(op="step_on", fb=FB, user="olga", token=login.token, args={"step": 2})
    )
    assert reply.applied or reply.reason == "S2 is already active", reply.reason
    follower = edge.edge.follower
    assert wait_until(lambda: follower.latest is not None and 2 in follower.latest.latched, 30)
    released: list[int] = []
    client.follow(FB, lambda u: released.extend(s for e, s in u.events if e == "A1"))
    first.get_by_role("button", name="Acknowledge S2 supervision").click()
    first.get_by_text("acknowledge message applied").first.wait_for(timeout=30_000)
    assert wait_until(lambda: 2 in released, 30)  # released as ACK_S would

    assert wait_until(lambda: (SV, "acknowledged", "olga") in _alarm_rows(plant.state), 20)
    acks = {u for k, st, u in _alarm_rows(plant.state) if k == SV and st == "acknowledged"}
    assert acks == {"olga"}  # not "program"
    audit = [(r.user, r.op, r.outcome) for r in read_audit(plant.state)]
    assert ("olga", "ack_msg", "applied") in audit
    first.close()
    second.close()


def _logins(state: Path) -> list[tuple[str, str]]:
    return [(r.user, r.outcome) for r in read_audit(state) if r.op == "login"]


def _alarm_rows(state: Path) -> list[tuple[str, str, str]]:
    import sqlite3

    with sqlite3.connect(f"file:{state}?mode=ro", uri=True) as db:
        return [tuple(r) for r in db.execute("SELECT key, state, user FROM alarms ORDER BY id")]


def test_a_websocket_with_a_foreign_origin_is_refused(plant: Plant) -> None:
    from websockets.exceptions import ConnectionClosed
    from websockets.sync.client import connect

    assert plant.edge.edge is not None
    url = plant.edge.url.replace("http://", "ws://")
    host = url.removeprefix("ws://").rstrip("/")
    with connect(url, origin="http://evil.example", subprotocols=[VISER_SUBPROTOCOL]) as ws:
        with pytest.raises(ConnectionClosed) as closed:
            while True:
                ws.recv(timeout=10)
        assert closed.value.rcvd is not None and closed.value.rcvd.code == 1008
    with connect(url, origin=f"http://{host}", subprotocols=[VISER_SUBPROTOCOL]) as ws:
        assert ws.recv(timeout=10)  # the page's own origin gets the scene


def test_a_cpu_that_goes_greys_the_chart_under_a_disconnected_banner(
    plant: Plant, browser: Browser
) -> None:
    assert plant.edge.edge is not None
    page = open_page(browser, plant.edge.url)
    plant.stop.set()
    plant.edge.edge.cpu_side.publisher.close()  # the CPU's bus goes: its alive token too
    page.get_by_text("disconnected: CPU cpu1").first.wait_for(timeout=30_000)
    view = plant.edge.edge.view
    assert wait_until(lambda: all(box.color == DISCONNECTED for box in view.boxes.values()))
    page.close()
