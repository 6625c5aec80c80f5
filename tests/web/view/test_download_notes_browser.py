"""The page's *Undo download* question names what the instance DBs would keep, in real
Chromium over a real bus: after a download that brought a changed S7-SCL FB with a new
variable, the undo's preview on an engineer's page says the variable would be dropped —
the note the undo's reply gives too (docs/online-change.md, "S7-SCL blocks")."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from s7graph.web.bus.client import BusClient
from s7graph.web.bus.protocol import Command
from s7graph.web.bus.session import open_session
from tests.web.bus.test_online_change_blocks import BLOCKS, CHART
from tests.web.helpers import PASSWORD, chromium_page, log_in, needs_chromium, online_cpu

if TYPE_CHECKING:
    from tests.conftest import BusCerts

pytestmark = [pytest.mark.timeout(300), needs_chromium]
pytest.importorskip("playwright.sync_api", reason="playwright is not installed")

EXTRA = BLOCKS.replace("old : INT;", "old : INT; extra : INT;")
DROPPED = "DB10 FB17 'FB17': dropped (no longer declared): extra"


def test_the_pages_undo_question_names_the_variables_the_undo_drops(
    tmp_path: Path, bus_certs: BusCerts
) -> None:
    users = {"eng": "engineer"}
    blocks = {"fb17.scl": BLOCKS}
    with (
        online_cpu(tmp_path, CHART, serve=True, users=users, certs=bus_certs, blocks=blocks) as rig,
        open_session(connect=[rig.endpoint], tls=rig.tls) as bus,
        BusClient(bus, "cpu1") as client,
    ):
        login = client.login("eng", PASSWORD)
        assert login.ok, login.reason
        args = {"source": CHART, "blocks": {"fb17.scl": EXTRA}}
        sent = Command(op="download", fb="Seq", user="eng", token=login.token, args=args)
        done = client.send(sent, timeout=60)
        assert done.applied, done.reason
        with chromium_page(rig.edge.url) as page:
            page.get_by_role("button", name="Log in", exact=True).wait_for(timeout=60_000)
            log_in(page, "eng", PASSWORD)
            page.get_by_role("button", name="Edit mode", exact=True).click()
            undo = page.get_by_role("button", name="Undo download", exact=True)
            undo.wait_for(timeout=30_000)
            undo.click()
            page.get_by_text("What changes").first.wait_for(timeout=60_000)
            assert "S7-SCL blocks changed: fb17.scl" in page.inner_text("body")
            page.get_by_text(DROPPED).first.wait_for(timeout=30_000)
            page.get_by_role("button", name="Undo the download", exact=True).click()
            page.get_by_text("undo download applied").first.wait_for(timeout=60_000)
        assert rig.session.cpu.block("FB17").interface[-1].name == "old"  # extra gone
