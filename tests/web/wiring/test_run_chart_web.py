"""``s7graph run CHART --web``: the live view of the real running sequence.

In process: :class:`LiveEdge` on a compiled chart and the virtual clock, commanded over the
real zenoh bus. End to end: the drill example as a real subprocess on the system clock,
its page in one headless Chromium, a supervision fault acknowledged by a click.
"""

from __future__ import annotations

import io
import re
import signal
import sqlite3
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from s7graph.engine.clock import VirtualClock
from s7graph.web.bus.client import BusClient
from s7graph.web.bus.live import LiveGraph
from s7graph.web.bus.protocol import Command, CommandReply
from s7graph.web.bus.session import open_session
from s7graph.web.harness.session import ChartSession, load_chart
from s7graph.web.wiring.live_edge import LiveEdge
from tests.paths import ROOT
from tests.web.helpers import (
    chromium_page,
    free_port,
    log_in,
    needs_chromium,
    scanning,
    view_line,
    wait_until,
)

DRILL = ROOT / "examples" / "drill"
FB = "Seq_drill"


@pytest.fixture
def running_edge() -> Iterator[tuple[LiveEdge, ChartSession]]:
    """The drill chart on the virtual clock, scanned in a thread, served on a free port."""
    cc, table = load_chart(DRILL / "drill.s7g", DRILL / "symbols.txt")
    session = ChartSession(cc, table, VirtualClock())
    live = LiveGraph(session.graph, read=session.get, watch=["Start_button"])
    with LiveEdge(live, port=0) as edge, scanning(session, edge):
        yield edge, session


@pytest.mark.timeout(60)
def test_live_edge_publishes_each_scan_and_applies_bus_commands_between_scans(
    running_edge: tuple[LiveEdge, ChartSession],
) -> None:
    edge, session = running_edge
    assert edge.edge is not None
    client = edge.edge.client
    follower = edge.edge.follower
    assert wait_until(lambda: follower.latest is not None and follower.latest.active == [1])
    latest = follower.latest
    assert latest is not None and "S_NO" in latest.values and "Start_button" in latest.values

    login = client.login("bob")
    assert login.ok, login.reason

    def as_bob(op: str, **args: object) -> Command:
        return Command(op=op, fb=FB, user="bob", token=login.token, args=args)  # type: ignore[arg-type]

    refused = client.send(as_bob("step_on", step=2))
    assert not refused.applied
    assert refused.reason == "step_on needs mode MAN (S7-GRAPH Control Sequencer)"
    assert client.send(as_bob("mode", mode="MAN")).applied
    assert client.send(as_bob("step_on", step=2)).applied
    assert wait_until(lambda: follower.latest is not None and follower.latest.active == [1, 2])
    unknown = client.send(as_bob("step_off", step=42))
    assert (unknown.applied, unknown.reason) == (False, f"no step S42 in {FB}")
    # S2's supervision (S2.U > 500 ms) trips: disturbed and latched until acknowledged
    assert wait_until(lambda: follower.latest is not None and follower.latest.latched == [2])
    # its cause (S2.U > 500 ms) persists: acknowledged in MAN it would latch again at once
    persists = client.send(as_bob("ack"))
    assert not persists.applied and "persists" in persists.reason
    for name in ("Cl_press_ok", "Dr_mot_running", "Coolant_sel"):  # T2 holds
        session.set(name, True)
    assert client.send(as_bob("mode", mode="AUTO")).applied
    assert wait_until(lambda: follower.latest is not None and follower.latest.mode == "AUTO")
    cycle = follower.latest.cycle
    assert wait_until(lambda: follower.latest is not None and follower.latest.cycle > cycle + 1)
    ack = client.send(as_bob("ack"))  # in AUTO the acknowledgement lets S2 switch on T2
    assert ack.applied and ack.cycle is not None

    status = client.status()
    assert status is not None and status.state == "RUN" and status.stats is not None
    assert status.stats.max_ms >= status.stats.min_ms > 0


def send(client: BusClient, command: Command) -> CommandReply:
    """Send, and again if the reply was lost or expired on a busy machine (not applied)."""
    for _ in range(3):
        reply = client.send(command)
        if not reply.reason.startswith(("no answer", "expired")):
            break
    return reply


def _green_pixels(png: bytes) -> int:
    """Pixels of the ACTIVE step colour family (green clearly above red and blue)."""
    import numpy as np
    from PIL import Image

    rgb = np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(np.int16)
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    return int(np.count_nonzero((g > r + 50) & (g > b + 50)))


@pytest.mark.timeout(280)
@needs_chromium
def test_run_drill_web_serves_the_live_sequence_and_takes_an_acknowledge_click(
    tmp_path: Path,
) -> None:
    pytest.importorskip("playwright.sync_api", reason="playwright is not installed")
    state = tmp_path / "drill.sqlite"
    stderr = (tmp_path / "stderr.txt").open("w")
    command = [sys.executable, "-m", "s7graph", "run", str(DRILL / "drill.s7g")]
    command += ["--plant", str(DRILL / "plant.py"), "--symbols", str(DRILL / "symbols.txt")]
    command += ["--web", "--port", str(free_port()), "--duration-s", "200", "--state", str(state)]
    command += ["--max-cycle-ms", "5000"]  # a loaded CI's slow scan is no time error here
    proc = subprocess.Popen(
        command,
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=stderr,
        text=True,
    )
    session = None
    try:
        # the view is a second python process importing viser: 36 s at load 20 on 2 cores
        found = view_line(proc, tmp_path / "stderr.txt", timeout=90)
        url, endpoint = found[1], found[2]
        assert url.startswith("http://127.0.0.1:")

        session = open_session(connect=[endpoint])
        client = BusClient(session, "cpu1", timeout=5.0)
        login = client.login("rob")
        assert login.ok, login.reason
        with chromium_page(url) as page:
            page.get_by_role("button", name="Acknowledge", exact=True).wait_for(timeout=30_000)
            log_in(page, "olga")
            # the initial step S1 is active: its box turns green in the WebGL scene
            assert wait_until(lambda: _green_pixels(page.screenshot()) > 200, 40)
            page.get_by_text(re.compile(r"active: S\d")).first.wait_for(timeout=40_000)

            # operator: MAN, activate S2 (the plant may have moved the sequence there
            # already); in MAN it stays, and its supervision (500 ms) trips and latches
            as_rob = {"fb": FB, "user": "rob", "token": login.token}
            reply = send(client, Command(op="mode", args={"mode": "MAN"}, **as_rob))
            assert reply.applied, reply.reason
            reply = send(client, Command(op="step_on", args={"step": 2}, **as_rob))
            assert reply.applied or reply.reason == "S2 is already active", reply.reason

            def latched() -> bool:
                st = client.state(FB)
                return st is not None and st.latched == [2]

            assert wait_until(latched, 30)
            page.get_by_text("error: S2").first.wait_for(timeout=40_000)
            # Step details follow the disturbed step: its supervision contact and the
            # contacts of the transitions leaving it
            page.get_by_text("Supervision (V): fault").first.wait_for(timeout=40_000)
            page.get_by_text("S2.U > T#500MS").first.wait_for(timeout=40_000)
            page.get_by_text("T2  Clamped, coolant").first.wait_for(timeout=40_000)
            # the supervision message in the Alarms panel, acknowledged by its own button
            page.get_by_text("S002 Work piece not clamped").first.wait_for(timeout=40_000)
            page.get_by_role("button", name="Acknowledge S2 supervision").click()
            page.get_by_text("acknowledge message applied").first.wait_for(timeout=40_000)
            # the cause persists (MAN holds S2): released as ACK_S would, S2 faults again
            # as a new message; the first went, acknowledged by olga (the alarm history)

            def acked_by_olga() -> bool:
                history = client.history()
                return history is not None and any(
                    e.state == "acknowledged" and e.user == "olga (unverified)"
                    for e in history.entries
                )

            assert wait_until(acked_by_olga, 40)
            page.get_by_role("button", name="Acknowledge", exact=True).click()
            page.get_by_text(re.compile(r"acknowledge (applied|refused)")).first.wait_for(
                timeout=40_000
            )
        client.close()
        session.close()
        session = None

        proc.send_signal(signal.SIGINT)
        assert proc.wait(timeout=30) == 0, (tmp_path / "stderr.txt").read_text()
    finally:
        if session is not None:
            session.close()
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        stderr.close()
    err = (tmp_path / "stderr.txt").read_text()
    assert "Traceback" not in err, err
    with sqlite3.connect(state) as db:
        audit = db.execute("SELECT user, action, detail FROM audit ORDER BY id").fetchall()
        alarms = db.execute("SELECT key, state, user FROM alarms ORDER BY id").fetchall()
        part = db.execute("SELECT state FROM parts WHERE name='messages'").fetchone()
    rows = [(u, a) for u, a, _ in audit]
    assert ("rob (unverified)", "mode") in rows
    assert ("olga (unverified)", "ack_msg") in rows
    # the page's Acknowledge after the message's: applied (the cause persists) or refused
    assert ("olga (unverified)", "ack") in rows
    who = {u for k, st, u in alarms if k == f"{FB}/DB1/S2/SV" and st == "acknowledged"}
    assert who == {"olga (unverified)"}  # the alarm log names the user, not "program"
    assert part is not None and f"{FB}/DB1/S2/SV" in part[0]  # the message list, persisted
