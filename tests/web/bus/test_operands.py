"""The CPU's operands on a real zenoh bus (``web.bus.operands``): the catalog names every
symbol with its type and address and each FB's variables and pins; the values follow the
CPU at most ``PERIOD_MS`` apart and only on change; an online change that brings another
variable gives the catalog a new version and the values the variable."""

from __future__ import annotations

import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from s7graph.web.bus.client import BusClient
from s7graph.web.bus.operands import PERIOD_MS
from s7graph.web.bus.protocol import Command, OperandValues
from tests.web.helpers import PASSWORD, OnlineRig, online_client, wait_until

if TYPE_CHECKING:
    from tests.conftest import BusCerts

pytestmark = pytest.mark.timeout(90)

CHART = """FUNCTION_BLOCK "Seq_lamp" FB 1 DB 1
VAR
  count : INT := 0;
END_VAR
SYMBOLS
  "Start" : I0.0 : BOOL;
  "Lamp"  : Q1.0 : BOOL;
  "Speed" : MW20 : INT;
  "Setpoint" : DB1.DBD4 : REAL;
END_SYMBOLS
SEQUENCE 1 "Lamp"
  INITIAL_STEP S1 "Idle":
  END_STEP
  STEP S2 "Lit":
    N "Lamp";
    S1 N count := count + 1;
  END_STEP
  TRANSITION T1 "Go" FROM S1 TO S2 := "Start";
  TRANSITION T2 "Done" FROM S2 TO S1 := NOT "Start";
END_SEQUENCE
END_FUNCTION_BLOCK
"""


@dataclass
class Bus:
    rig: OnlineRig
    client: BusClient
    seen: list[OperandValues]

    def latest(self) -> OperandValues:
        return self.seen[-1]


@pytest.fixture
def bus(tmp_path: Path, bus_certs: BusCerts) -> Iterator[Bus]:
    with online_client(
        tmp_path, CHART, certs=bus_certs, user=None, name="lamp.s7g", operands=True
    ) as on:
        seen: list[OperandValues] = []
        on.client.on_operands(seen.append)
        assert wait_until(lambda: bool(seen))
        yield Bus(on.rig, on.client, seen)


def test_the_catalog_names_every_operand_with_its_type(bus: Bus) -> None:
    catalog = bus.client.operand_catalog()
    assert catalog is not None
    symbols = {s.name: (s.type, s.address) for s in catalog.symbols}
    assert symbols == {
        "Start": ("BOOL", "I0.0"),
        "Lamp": ("BOOL", "Q1.0"),
        "Speed": ("INT", "MW20"),
        "Setpoint": ("REAL", "DB1.DBD4"),
    }
    fb = catalog.fbs["Seq_lamp"]
    assert [(v.name, v.type) for v in fb.variables] == [("count", "INT")]
    pins = {p.name: p.direction for p in fb.pins}
    assert pins["S_NO"] == "OUT" and pins["INIT_SQ"] == "IN"
    assert bus.latest().catalog == catalog.version


def test_the_values_follow_the_cpu(bus: Bus) -> None:
    latest = bus.latest()
    assert latest.symbols["Start"] is False and latest.symbols["Speed"] == 0
    assert latest.fbs["Seq_lamp"]["S_NO"] == 1
    bus.rig.session.set("Start", True)
    bus.rig.session.set("Speed", 1234)

    def lit() -> bool:
        v = bus.latest()
        return v.symbols["Lamp"] is True and v.fbs["Seq_lamp"]["count"] == 1

    assert wait_until(lit)
    assert bus.latest().symbols["Speed"] == 1234
    assert bus.latest().fbs["Seq_lamp"]["S_NO"] == 2
    current = bus.client.operands()  # the queryable: the newest
    assert current is not None and current.seq == bus.latest().seq


def test_values_go_out_only_on_change_and_at_most_every_period(bus: Bus) -> None:
    time.sleep(1.0)
    quiet = len(bus.seen)
    time.sleep(1.0)
    assert len(bus.seen) == quiet  # nothing changed: nothing published
    start = len(bus.seen)
    began = time.monotonic()
    while time.monotonic() - began < 1.0:  # a value changing at every scan
        bus.rig.session.set("Speed", int((time.monotonic() - began) * 10_000) % 30_000)
        time.sleep(0.005)
    went = len(bus.seen) - start
    assert 3 <= went <= 1000 / PERIOD_MS + 2, went


def test_an_online_change_brings_a_new_catalog(bus: Bus) -> None:
    client = bus.client
    login = client.login("eng", PASSWORD)
    assert login.ok
    before = client.operand_catalog()
    assert before is not None
    edited = CHART.replace("  count : INT := 0;\n", "  count : INT := 0;\n  total : DINT := 7;\n")
    command = Command(
        op="download",
        fb="Seq_lamp",
        user="eng",
        token=login.token,
        args={"source": edited, "base": 1},  # type: ignore[arg-type]
    )
    reply = client.send(command, timeout=20)
    assert reply.applied, reply.reason
    assert wait_until(lambda: "total" in bus.latest().fbs["Seq_lamp"])
    assert bus.latest().fbs["Seq_lamp"]["total"] == 7
    after = client.operand_catalog()
    assert after is not None and after.version > before.version
    assert [v.name for v in after.fbs["Seq_lamp"].variables] == ["count", "total"]
