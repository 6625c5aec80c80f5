"""The CPU's diagnostic buffer over OPC UA (docs/opcua.md, "The address space"):
``DiagnosticBuffer`` shows the newest entries, newest first, as the CPU's ``diag`` lists
them, and an entry the CPU writes (a force job an engineer starts by a write) reaches a
client's subscription through ``diag/new``. The merging of ``diag/new`` into what the
face shows, and asking ``diag`` again when an entry was missed, on its own. (A STOP's
reason and entry: test_process.py, with a real CPU's RUN/STOP switch.)"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import pytest
from asyncua import ua

from s7graph.web.bus.client import BusClient
from s7graph.web.bus.protocol import DiagBuffer, DiagEvent
from s7graph.web.bus.session import open_session
from s7graph.web.opcua.diag import DIAG_ENTRIES, DiagShown, entry_line
from tests.web.opcua.helpers import FACE_CN, connected, eventually, face_rig, node, run

if TYPE_CHECKING:
    from tests.conftest import BusCerts

pytestmark = pytest.mark.timeout(180)

BUFFER = "cpu1/DiagnosticBuffer"
COLUMNS = ("Number", "Time", "EventId", "OB", "PriorityClass", "Text", "Info", "Entries")


async def _buffer(client: Any) -> dict[str, Any]:
    """Every variable of the face's DiagnosticBuffer: name → value."""
    names = (*COLUMNS, "Total", "Capacity")
    values = [await node(client, f"{BUFFER}/{name}").read_value() for name in names]
    return dict(zip(names, values, strict=True))


def test_the_buffer_is_the_cpus_and_a_new_entry_reaches_a_subscription(
    tmp_path: Path, bus_certs: BusCerts
) -> None:
    with (
        face_rig(tmp_path, bus_certs) as face,
        open_session(connect=[face.rig.endpoint], tls=bus_certs.tls(FACE_CN)) as session,
        BusClient(session, "cpu1") as bus,
    ):

        async def check() -> None:
            async with connected(face.url, "eng") as c:
                held = bus.diag(DIAG_ENTRIES)
                assert held is not None and held.entries  # the CPU's start is in it

                async def same() -> bool:
                    shown = await _buffer(c)
                    return (
                        shown["Total"] >= held.total
                        and shown["Number"][-1] <= held.entries[-1].number
                    )

                assert await eventually(same, 20)
                shown = await _buffer(c)
                assert all(len(shown[k]) == len(shown["Number"]) for k in COLUMNS)
                assert shown["Number"] == sorted(shown["Number"], reverse=True)
                assert shown["Number"][0] == shown["Total"] and shown["Capacity"] == held.capacity
                first = next(e for e in held.entries if e.number == shown["Number"][-1])
                k = len(shown["Number"]) - 1
                assert shown["EventId"][k] == f"16#{first.event_id:04X}"
                assert (shown["Text"][k], shown["Entries"][k]) == (first.text, entry_line(first))

                seen: list[int] = []

                class Seen:
                    def datachange_notification(self, _n: Any, value: Any, _d: Any) -> None:
                        seen.append(int(value))

                sub = await c.create_subscription(20, Seen())
                await sub.subscribe_data_change([node(c, f"{BUFFER}/Total")])
                before = shown["Total"]
                await node(c, "cpu1/Symbols/Level").write_value(ua.Variant(7, ua.VariantType.Int16))
                assert await eventually(lambda: _has(seen, before + 1), 20)  # a subscription
                now = await _buffer(c)
                assert now["EventId"][0] == "16#5F03" and now["Number"][0] == now["Total"]
                newest = bus.diag(1)
                assert newest is not None and newest.entries[0].number == now["Total"]
                assert now["Entries"][0] == entry_line(newest.entries[0])
                assert "MW20" in now["Info"][0] and now["Entries"][0].startswith(f"{now['Total']} ")
                known = now["Time"][0].year > 1601  # the time when the CPU knows it
                assert known == bool(newest.entries[0].wall_ms)
                assert now["Number"][1:] == shown["Number"][: len(now["Number"]) - 1]

                await sub.delete()

        run(check())


async def _has(seen: list[int], total: int) -> bool:
    return any(t >= total for t in seen)


async def _reads(client: Any, path: str, value: object, index: int | None = None) -> bool:
    got = await node(client, path).read_value()
    if index is not None:
        return bool(got) and got[index] == value
    return bool(got == value)


def _event(number: int) -> DiagEvent:
    return DiagEvent(number=number, event_id=0x5F03, text="Force job started")


def _published(total: int, *numbers: int) -> DiagBuffer:
    return DiagBuffer(total=total, capacity=100, entries=[_event(n) for n in numbers])


def test_new_entries_go_in_front_and_a_gap_asks_for_the_buffer_again() -> None:
    diag = DiagShown()
    assert not diag.merge(_published(5, 5))  # nothing held yet: ask diag
    diag.replace(_published(4, 4, 3, 2, 1))
    assert diag.merge(_published(6, 6, 5))
    assert [e.number for e in diag.entries] == [6, 5, 4, 3, 2, 1] and diag.total == 6
    assert diag.merge(_published(6, 6, 5))  # one already shown changes nothing
    assert [e.number for e in diag.entries] == [6, 5, 4, 3, 2, 1]
    assert not diag.merge(_published(9, 9))  # 7 and 8 missed
    assert [e.number for e in diag.entries] == [6, 5, 4, 3, 2, 1]
    diag.replace(_published(DIAG_ENTRIES, *range(DIAG_ENTRIES, 0, -1)))
    assert diag.merge(_published(DIAG_ENTRIES + 1, DIAG_ENTRIES + 1))
    assert len(diag.entries) == DIAG_ENTRIES and diag.entries[-1].number == 2  # the oldest go


def test_an_entry_is_one_line_with_its_number_time_id_ob_and_text() -> None:
    event = DiagEvent(
        number=17,
        event_id=0x4562,
        text="STOP caused by a programming error",
        info="ZeroDivisionError",
        block="FB12",
        ob=121,
        priority=1,
        wall_ms=1_796_447_274_715,
    )
    assert entry_line(event) == (
        "17 2026-12-05T05:07:54.715Z 16#4562 OB121/PC1 "
        "STOP caused by a programming error: FB12: ZeroDivisionError"
    )
    clock = DiagEvent(number=1, event_id=0x1381, text="Manual warm restart", t_ms=1500)
    assert entry_line(clock) == "1 CPU-clock 1.500s 16#1381 - Manual warm restart"
