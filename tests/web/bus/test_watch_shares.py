"""Each source has its own share of the ``watch`` queue (web/bus/watch.py, docs/bus.md, "The
watch table: watch"): a source that floods watch requests is answered ``busy`` beyond its
share, while another source's request is still served at the next scan boundary. Two real
clients on a mutual TLS bus on loopback — two certificates, two sources — against a
program of blocks in this process."""

from __future__ import annotations

import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import pytest
import zenoh

from s7graph.engine import VirtualClock
from s7graph.web.bus.client import BusClient
from s7graph.web.bus.origin import stamp
from s7graph.web.bus.protocol import WatchRequest, WatchValues, decode, encode
from s7graph.web.bus.session import BusEnds, open_session
from s7graph.web.bus.watch import PER_SOURCE, QUEUE
from s7graph.web.wiring.program_edge import ProgramEdge
from tests.web.bus.test_diag_watch import Rig, program_cpu
from tests.web.helpers import free_port, wait_until

if TYPE_CHECKING:
    from tests.conftest import BusCerts

pytestmark = pytest.mark.timeout(120)
WATCH = "s7graph/cpu1/watch"
ASK = encode(WatchRequest(addresses=["MW0:INT"]))


@dataclass
class TwoSources:
    rig: Rig  # olga's client, and the scans
    flooder: zenoh.Session  # client.rogue's session: another source


@contextmanager
def two_sources(bus_certs: BusCerts) -> Iterator[TwoSources]:
    clock = VirtualClock()
    cpu = program_cpu(clock)
    endpoint = f"tls/localhost:{free_port()}"
    ends = BusEnds(listen=[endpoint], tls=bus_certs.tls("cpu.cpu1"))
    with (
        ProgramEdge(cpu, ends=ends) as edge,
        open_session(connect=[endpoint], tls=bus_certs.tls("client.olga")) as olga,
        open_session(connect=[endpoint], tls=bus_certs.tls("client.rogue")) as rogue,
        BusClient(olga, "cpu1") as client,
    ):
        cpu.start()
        rig = Rig(cpu, edge, client, olga, clock)
        rig.scan()
        assert wait_until(lambda: client.status() is not None)
        yield TwoSources(rig, rogue)


def _flood(session: zenoh.Session, n: int) -> list[Any]:
    """``n`` watch requests sent at once, none waited for: their reply handlers."""
    return [
        session.get(WATCH, payload=ASK, timeout=20, source_info=stamp(session)) for _ in range(n)
    ]


def _answer(handler: Any) -> WatchValues:
    for reply in handler:
        if reply.ok is not None:
            return decode(reply.ok.payload.to_bytes(), WatchValues)
    raise AssertionError("no answer")


def test_a_flooding_source_is_busy_beyond_its_share_and_another_source_is_served(
    bus_certs: BusCerts,
) -> None:
    with two_sources(bus_certs) as bus:
        answers: list[WatchValues] = []
        waiting = [
            threading.Thread(target=lambda h=h: answers.append(_answer(h)), daemon=True)
            for h in _flood(bus.flooder, QUEUE)  # no scan boundary meanwhile
        ]
        for t in waiting:
            t.start()
        assert wait_until(lambda: len(answers) == QUEUE - PER_SOURCE)  # busy, at once
        assert {a.error for a in answers} == {
            f"busy: {PER_SOURCE} watch requests from here are waiting; ask again once they "
            "are answered"
        }
        honest = bus.rig.watch(["MW0:INT"])  # the queue is not full for another source
        assert honest.error == "" and honest.values[0].error == ""
        for t in waiting:  # the flooder's share was served in turn
            t.join(10)
        served = [a for a in answers if not a.error]
        assert len(served) == PER_SOURCE and all(a.values for a in served)


def test_a_flood_of_2000_requests_a_second_leaves_another_sources_watch_served(
    bus_certs: BusCerts,
) -> None:
    """The flood of the report (about 1,300 requests a second made honest clients busy),
    while the CPU scans every 10 ms: every request of the other source is answered."""
    with two_sources(bus_certs) as bus:
        stop = threading.Event()
        sent = [0]

        def flood() -> None:
            while not stop.is_set():
                start = time.monotonic()
                _flood(bus.flooder, 20)  # replies dropped: the flooder does not wait
                sent[0] += 20
                stop.wait(max(0.0, 0.01 - (time.monotonic() - start)))

        def scans() -> None:
            while not stop.is_set():
                bus.rig.scan()
                stop.wait(0.01)

        threads = [threading.Thread(target=f, daemon=True) for f in (flood, scans)]
        for t in threads:
            t.start()
        try:
            time.sleep(0.5)  # the flood is on
            start, answers = time.monotonic(), []
            for _ in range(20):
                answers.append(bus.rig.client.watch(["MW0:INT"], timeout=5))
                time.sleep(0.05)
            rate = sent[0] / (time.monotonic() - start + 0.5)
        finally:
            stop.set()
            for t in threads:
                t.join(10)
        assert rate > 1300, rate
        assert [a.error for a in answers] == [""] * 20
