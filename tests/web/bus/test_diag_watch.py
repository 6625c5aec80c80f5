"""The diagnostic buffer, the watch table and the memory reset over a real zenoh bus (TCP on
127.0.0.1) against a program of blocks in this process (``web.wiring.program_edge``):
``diag`` answers newest first and ``?n=`` bounds it, ``diag/new`` publishes each entry at
the next scan boundary, ``status`` names the STOP's entry and the error that caused it,
``watch`` reads operands between two scans, ``mres`` resets the memory in STOP only and
is on disk before it is answered."""

from __future__ import annotations

import base64
import json
import sqlite3
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
import zenoh

from s7graph.engine import DB, CallContext, Cpu, EventId, InstanceDB, VirtualClock, fb, ob
from s7graph.engine.clock import SystemClock
from s7graph.engine.datatypes import layout
from s7graph.engine.persistence import StateStore
from s7graph.engine.runner import Runner
from s7graph.engine.symbols import SymbolTable
from s7graph.web.access.audit import read_audit
from s7graph.web.bus.client import BusClient
from s7graph.web.bus.protocol import (
    Command,
    DiagBuffer,
    WatchRequest,
    WatchValues,
    decode,
    encode,
)
from s7graph.web.bus.session import BusEnds, open_session
from s7graph.web.bus.watch import parse_item, split_operands
from s7graph.web.wiring.program_edge import ProgramEdge
from tests.web.helpers import free_port, program_client, wait_until

pytestmark = pytest.mark.timeout(120)


@fb(10, "Average", IN={"x": "REAL"}, STAT={"avg": "REAL", "n": "INT", "last": "ARRAY[1..3] OF INT"})
def average(ctx: CallContext, db: InstanceDB) -> None:
    n = int(db.n) + 1  # type: ignore[call-overload]
    db.n = min(n, 32767)
    db.avg = float(db.avg) + (float(db.x) - float(db.avg)) / n  # type: ignore[arg-type]
    db.last = [n, n + 1, n + 2]


@ob(1)
def main(ctx: CallContext) -> None:
    ctx.mem.set("MW0", (int(ctx.mem.get("MW0")) + 1) & 0x7FFF)
    ctx.mem.set("Q4.0", not ctx.mem.get("Q4.0"))
    ctx.call(average, 11, x=2.0)


def program_cpu(clock: object) -> Cpu:
    """The program in a CPU on ``clock``; its maximum cycle time long enough that a busy
    test machine does not stop it by a time error."""
    cpu = Cpu(clock, max_cycle_ms=5000)  # type: ignore[arg-type]
    cpu.load(main, average)
    cpu.create_instance_db(11, average)
    recipe = layout([("speed", "INT"), ("on", "BOOL"), ("temps", "ARRAY[1..4] OF REAL")])
    cpu.mem.create_db(20, recipe.size, layout=recipe)
    cpu.mem.write_as(cpu.mem.dbs[20].field_address("speed"), "INT", -5)
    cpu.mem.symbols = SymbolTable()
    cpu.mem.symbols.add("Counter", "MW0", "INT")
    return cpu


@dataclass
class Rig:
    cpu: Cpu
    edge: ProgramEdge
    client: BusClient
    session: zenoh.Session
    clock: VirtualClock

    def scan(self, n: int = 1) -> None:
        """``n`` scans, each handed to the edge as the runner would (this thread)."""
        for _ in range(n):
            self.clock.advance(10)
            self.edge.on_record(self.cpu.scan(), stats=self.cpu.stats)

    def watch(self, addresses: list[str]) -> WatchValues:
        """Ask ``watch`` from another thread and scan until it is answered."""
        answers: list[WatchValues] = []
        asking = threading.Thread(target=lambda: answers.append(self.client.watch(addresses)))
        asking.start()
        while asking.is_alive():
            self.scan()
            asking.join(0.01)
        return answers[0]


@contextmanager
def program_rig(cpu: Cpu, clock: VirtualClock) -> Iterator[Rig]:
    """``cpu`` (on ``clock``) started behind a ``ProgramEdge`` on TCP on loopback, a
    client's session on it, one scan made and the status seen."""
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    with (
        ProgramEdge(cpu, ends=BusEnds(listen=[endpoint])) as edge,
        open_session(connect=[endpoint]) as session,
        BusClient(session, "cpu1") as client,
    ):
        cpu.start()
        rig = Rig(cpu, edge, client, session, clock)
        rig.scan()
        assert wait_until(lambda: client.status() is not None)
        yield rig


@pytest.fixture
def rig() -> Iterator[Rig]:
    clock = VirtualClock()
    with program_rig(program_cpu(clock), clock) as made:
        yield made


def test_diag_answers_the_newest_entries_first_and_n_bounds_them(rig: Rig) -> None:
    for i in range(150):
        rig.cpu.diagnostics.record(rig.clock.now_ns(), 0x5F03, "", f"entry {i}")
    rig.scan()
    buffer = rig.client.diag()
    assert buffer is not None and buffer.capacity == 100 and len(buffer.entries) == 100
    assert buffer.entries[0].info == "entry 149" and buffer.entries[0].number == buffer.total
    numbers = [e.number for e in buffer.entries]
    assert numbers == sorted(numbers, reverse=True) and numbers[-1] == buffer.total - 99
    five = rig.client.diag(5)
    assert five is not None and [e.info for e in five.entries] == [
        f"entry {i}" for i in range(149, 144, -1)
    ]
    assert five.entries[0].text == "Force job started" and five.entries[0].event_id == 0x5F03


@pytest.mark.parametrize("n", ["0", "abc", "1001", "-3"])
def test_a_number_of_entries_that_is_none_is_refused_with_the_reason(rig: Rig, n: str) -> None:
    replies = list(rig.session.get(f"s7graph/cpu1/diag?n={n}", timeout=5))
    assert len(replies) == 1 and replies[0].ok is None
    assert "give a number of entries, 1 to 1000" in replies[0].err.payload.to_string()


def test_each_entry_written_goes_out_on_diag_new_at_the_next_scan_boundary(rig: Rig) -> None:
    got: list[DiagBuffer] = []
    rig.client.on_diag(got.append)
    before = rig.cpu.diagnostics.total

    def fresh() -> list[DiagBuffer]:  # a startup's message may still be on its way
        return [g for g in got if g.total > before]

    rig.cpu.diagnostics.record(rig.clock.now_ns(), 0x5F03, "", "one")
    rig.cpu.diagnostics.record(rig.clock.now_ns(), 0x5F04, "", "two")
    assert not wait_until(fresh, 0.5)  # not before the boundary
    rig.scan()
    assert wait_until(fresh)
    new = fresh()[0]
    assert new.total == before + 2 and [e.info for e in new.entries] == ["two", "one"]


def test_entries_read_back_from_the_state_file_keep_their_numbers_on_the_bus(
    tmp_path: Path,
) -> None:
    first = program_cpu(VirtualClock())
    store = StateStore(tmp_path / "state.sqlite")
    for i in range(150):  # more than the buffer holds: the state file has them all
        first.diagnostics.record(0, 0x5F03, "", f"entry {i + 1}")
    store.save(first)
    store.close()
    clock = VirtualClock()
    cpu = program_cpu(clock)
    store = StateStore(tmp_path / "state.sqlite")
    assert store.load(cpu)
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    with (
        ProgramEdge(cpu, ends=BusEnds(listen=[endpoint])) as edge,
        open_session(connect=[endpoint]) as session,
        BusClient(session, "cpu1") as client,
    ):
        rig = Rig(cpu, edge, client, session, clock)
        cpu.start("warm")
        rig.scan()
        assert wait_until(lambda: (b := client.diag(1)) is not None and b.total == 152)
        buffer = client.diag(5)
        assert buffer is not None
        assert [(e.number, e.info) for e in buffer.entries[2:]] == [
            (150, "entry 150"),
            (149, "entry 149"),
            (148, "entry 148"),
        ]
        assert [e.number for e in buffer.entries[:2]] == [152, 151]  # the warm restart's
        got: list[DiagBuffer] = []
        client.on_diag(got.append)
        written = [0]

        def published() -> bool:  # one entry a scan until the subscription sees one
            written[0] += 1
            cpu.diagnostics.record(clock.now_ns(), 0x5F04, "", f"new {written[0]}")
            rig.scan()
            return any(e.number > 152 for b in got for e in b.entries)

        assert wait_until(published)
        new = [e for b in got for e in b.entries if e.number > 152]  # a late 151, 152 aside
        assert new and all(e.info == f"new {e.number - 152}" for e in new)
    store.close()


def test_status_names_the_stop_entry_and_the_programming_error_that_caused_it(
    rig: Rig,
) -> None:
    """An OB1 whose FB raises, no OB121: STOP. ``status`` says why in words and gives the
    STOP's entry (16#4562, requesting OB121) and the error entry before it (16#25FF, OB121
    in OB1's priority class 1), as ``diag`` lists them."""

    @fb(12, "Broken", STAT={"n": "INT"})
    def broken(ctx: CallContext, db: InstanceDB) -> None:
        db.n = 1 // int(db.n)  # type: ignore[call-overload]

    @ob(1)
    def failing(ctx: CallContext) -> None:
        ctx.call(broken, 13)

    rig.cpu.load(failing, broken)
    rig.cpu.create_instance_db(13, broken)
    rig.scan(2)
    assert wait_until(lambda: (s := rig.client.status()) is not None and s.state == "STOP")
    status = rig.client.status()
    assert status is not None and status.stop is not None and status.cause is not None
    assert status.reason == (
        "FB12: ZeroDivisionError: integer division or modulo by zero "
        "(programming error, OB121 not loaded)"
    )
    assert (status.stop.event_id, status.stop.ob, status.stop.priority) == (0x4562, 121, 1)
    assert (status.cause.event_id, status.cause.ob, status.cause.priority) == (0x25FF, 121, 1)
    assert status.cause.block == "FB12" and "ZeroDivisionError" in status.cause.info
    listed = rig.client.diag(2)
    assert listed is not None and listed.entries == [status.stop, status.cause]


def test_watch_reads_addresses_symbols_and_db_variables_of_one_scan(rig: Rig) -> None:
    rig.scan(3)
    asked = [
        "MW0",
        "MW0:INT",
        "Counter",
        "Q4.0",
        "DB11.n",
        "DB11.avg",
        "DB11.last[2]",
        "DB20.speed",
        "db20.TEMPS[4]:real",
        "DB20.DBW0:INT",
        "T5",
        "C3",
        "DB11.nope",
        "DB99.x",
        "DB20.speed[1]",
        "MW0:FOO",
        "DB11.last[7]",
    ]
    answer = rig.watch(asked)
    assert answer.error == "" and answer.state == "RUN"
    got = {v.address: (v.text, v.type, v.error) for v in answer.values}
    n = answer.cycle
    assert got["MW0"] == (f"W#16#{n:04X}", "WORD", "")
    assert got["MW0:INT"] == got["Counter"] == (str(n), "INT", "")
    assert got["Q4.0"][1] == "BOOL" and got["Q4.0"][0] in ("TRUE", "FALSE")
    assert got["DB11.n"] == (str(n), "INT", "") and got["DB11.avg"] == ("2.0", "REAL", "")
    assert got["DB11.last[2]"] == (str(n + 1), "INT", "")
    assert got["DB20.speed"] == ("-5", "INT", "") and got["DB20.DBW0:INT"] == ("-5", "INT", "")
    assert got["db20.TEMPS[4]:real"] == ("0.0", "REAL", "")
    assert got["T5"] == ("S5T#0MS", "S5TIME", "") and got["C3"] == ("C#0", "COUNTER", "")
    assert got["DB11.nope"][2] == "DB11 (FB10) has no variable 'nope'; it has x, avg, n, last"
    assert got["DB99.x"][2] == "DB99 is not loaded"
    assert got["DB20.speed[1]"][2] == "DB20.speed is no ARRAY: it takes no index"
    assert got["MW0:FOO"][2] == "MW0:FOO: unknown type 'FOO' after ':'"
    assert got["DB11.last[7]"][2] == "DB11.last: index 7 outside 1..3"


def test_a_watch_request_is_answered_at_the_next_scan_boundary(rig: Rig) -> None:
    answers: list[WatchValues] = []
    asking = threading.Thread(target=lambda: answers.append(rig.client.watch(["MW0:INT"])))
    asking.start()
    assert not wait_until(lambda: answers, 0.5)  # no scan boundary: no answer
    rig.scan()
    asking.join(5)
    assert answers and answers[0].values[0].text == str(rig.cpu.cycle)


@pytest.mark.parametrize(
    ("payload", "reason"),
    [
        (b"", "a watch request names the addresses to watch"),
        (b'{"addresses": [', "malformed JSON"),
        (b'{"addresses": []}', "Expected `array` of length >= 1"),
        (encode(WatchRequest(addresses=["MW0"] * 65)), "length <= 64"),
        (b'{"addresses": ["MW0"], "evil": 1}', "unknown field `evil`"),
    ],
)
def test_a_hostile_watch_request_is_refused_with_the_reason(
    rig: Rig, payload: bytes, reason: str
) -> None:
    replies = list(rig.session.get("s7graph/cpu1/watch", payload=payload or None, timeout=5))
    answer = decode(replies[0].ok.payload.to_bytes(), WatchValues)
    assert reason in answer.error and answer.values == []


def test_a_wildcard_query_gets_no_watch_and_the_diag(rig: Rig) -> None:
    keys = {
        str(r.ok.key_expr)
        for r in rig.session.get(
            "s7graph/**",
            timeout=3,
            target=zenoh.QueryTarget.ALL,
            consolidation=zenoh.ConsolidationMode.NONE,
        )
        if r.ok is not None
    }
    assert "s7graph/cpu1/diag" in keys and "s7graph/cpu1/watch" not in keys


def test_a_program_cpu_takes_the_cpus_ops_and_refuses_an_fbs(rig: Rig) -> None:
    token = rig.client.login("eng").token
    ack = Command(op="ack", fb="cpu1", user="eng", token=token)
    reply = rig.client.send(ack, timeout=5.0)
    assert not reply.applied
    assert reply.reason == "unknown FB 'cpu1'; this CPU runs no GRAPH FB"
    force = Command(
        op="force", fb="cpu1", user="eng", token=token, args={"address": "M10.0", "value": True}
    )
    answers = []
    sending = threading.Thread(target=lambda: answers.append(rig.client.send(force, timeout=5.0)))
    sending.start()
    assert wait_until(lambda: rig.edge.publisher is not None and rig.edge.publisher.queued, 5)
    rig.scan()
    sending.join(5)
    assert answers and answers[0].applied, answers
    assert rig.cpu.mem.get("M10.0") is False  # forced from the next cycle's start
    rig.scan()
    assert rig.cpu.mem.get("M10.0") is True


def test_split_and_parse_operands() -> None:
    assert split_operands(" MW0, Q4.0,,DB20.m[1, 2] ,") == ["MW0", "Q4.0", "DB20.m[1, 2]"]
    assert parse_item("DB20.m[1, 2]").path == ("m", (1, 2))
    assert parse_item('"a:b"').target == '"a:b"' and parse_item('"a:b"').type is None
    item = parse_item("DB20.DBW2:int")
    assert (item.target, item.type, item.db) == ("DB20.DBW2", "INT", None)
    assert parse_item("DB10.ctu.CV").path == ("ctu", "CV")
    assert parse_item(":INT").error == ":INT: no operand before ':'"


# ---------------------------------------------------------------- MRES with a runner


@dataclass
class Running:
    cpu: Cpu
    runner: Runner
    client: BusClient
    store: StateStore


@pytest.fixture
def running(tmp_path: Path) -> Iterator[Running]:
    """The program scanned every 10 ms by a runner on the system clock, with its state file,
    on the bus with the demo's logins and the audit in the state file."""
    cpu = program_cpu(SystemClock())
    cpu.load(DB(30, 4, init=b"\x00\x07"))
    with program_client(cpu, tmp_path) as (run, client):
        yield Running(cpu, run.runner, client, run.store)


def _send(client: BusClient, op: str) -> tuple[bool, str]:
    token = client.login("eng").token
    reply = client.send(Command(op=op, fb="cpu1", user="eng", token=token), timeout=8.0)
    return reply.applied, reply.reason


def _on_disk(store: StateStore) -> tuple[list[int], dict[str, Any]]:
    """The diagnostic entries and the retentive memory image the state file holds."""
    with sqlite3.connect(f"file:{store.path}?mode=ro", uri=True) as con:
        events = [r[0] for r in con.execute("SELECT event_id FROM diagnostics ORDER BY seq")]
        memory = con.execute("SELECT value FROM meta WHERE key='memory'").fetchone()[0]
    con.close()
    return events, json.loads(memory)


def test_mres_is_refused_in_run_and_resets_the_memory_in_stop_on_disk_before_the_reply(
    running: Running,
) -> None:
    cpu = running.cpu
    assert wait_until(lambda: cpu.mem.get("MW0") > 5)
    assert _send(running.client, "mres") == (
        False,
        "the CPU is in RUN: a memory reset needs STOP (stop it first)",
    )
    cpu.mem.set("DB30.DBW0", 99)  # between scans is fine for this test: nothing writes it
    assert _send(running.client, "stop")[0]
    applied, _ = _send(running.client, "mres")
    assert applied
    events, memory = _on_disk(running.store)  # the reply waited for the commit
    assert events[-1] == EventId.MEMORY_RESET and EventId.STOP_BY_REQUEST in events
    assert base64.b64decode(memory["dbs"]["30"]["data"]) == b"\x00\x07\x00\x00"
    assert base64.b64decode(memory["markers"]["data"])[:2] == b"\x00\x00"  # MW0, retentive
    assert cpu.mem.get("MW0") == 0 and cpu.mem.get("DB30.DBW0") == 7
    assert cpu.instance_dbs[11].n == 0 and cpu.mode.value == "STOP"
    audited = [(r.op, r.outcome) for r in read_audit(running.store.path)]
    assert ("mres", "refused") in audited and ("mres", "applied") in audited
    assert "memory reset" in cpu.hot_blockers
    assert _send(running.client, "start")[0]
    assert wait_until(lambda: cpu.mode.value == "RUN" and cpu.mem.get("MW0") > 0)
    assert cpu.last_restart == "warm"


def test_a_watch_request_that_breaks_the_cpu_is_refused_in_words(
    rig: Rig, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A defect of ours reached by the watch's last-resort guard: an internal error,
    where, and what it said — never an exception's class name."""

    def broken(text: str) -> object:
        raise KeyError("x")

    monkeypatch.setattr("s7graph.web.bus.watch.parse_item", broken)
    payload = encode(WatchRequest(addresses=["MW0"]))
    replies = list(rig.session.get("s7graph/cpu1/watch", payload=payload, timeout=5))
    answer = decode(replies[0].ok.payload.to_bytes(), WatchValues)
    assert answer.error == (
        "watch refused: an internal error in the CPU while reading a watch request: "
        "'x' (please report it)"
    )
