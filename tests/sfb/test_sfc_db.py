"""SFC22 CREAT_DB, SFC23 DEL_DB, SFC24 TEST_DB (STEP7 comprehensive guide vol. 2, ch. 12)."""

from __future__ import annotations

from s7graph.engine.blocks import DB, OB
from s7graph.engine.clock import VirtualClock
from s7graph.engine.cpu import CallContext, Cpu
from s7graph.sfb import install
from s7graph.sfb.catalogue import as_int


def make_cpu(clock: VirtualClock, main: object) -> Cpu:
    cpu = Cpu(clock)
    install(cpu)
    cpu.load(OB(1, "OB1", main), DB(12, 4))  # type: ignore[arg-type]
    return cpu


def test_unguarded_creat_db_creates_the_lowest_free_numbers_until_the_range_is_used_up(
    clock: VirtualClock,
) -> None:
    """CREAT_DB(LOW_LIMIT:=10, UP_LIMIT:=14, COUNT:=200) called every scan creates DB10, DB11, DB13,
    DB14 (DB12 exists) with 200 bytes, then W#16#80B1."""
    rets: list[dict[str, object]] = []

    def main(ctx: CallContext) -> None:
        rets.append(ctx.call("CREAT_DB", LOW_LIMIT=10, UP_LIMIT=14, COUNT=200, DB_NUMBER="MW0"))

    cpu = make_cpu(clock, main)
    cpu.start()
    for _ in range(5):
        cpu.scan()
    assert [r.get("DB_NUMBER") for r in rets] == [10, 11, 13, 14, None]
    assert rets[-1]["RET_VAL"] == as_int(0x80B1) and cpu.mem.get("MW0") == 14
    assert len(cpu.mem.dbs[13]) == 200 and cpu.mem.dbs[13].created


def test_creat_db_needs_an_even_non_zero_count_and_a_valid_range(clock: VirtualClock) -> None:
    """COUNT must be even (W#16#80A2); LOW_LIMIT > UP_LIMIT is W#16#80A1."""
    rets: list[object] = []

    def main(ctx: CallContext) -> None:
        for low, up, count in ((20, 20, 7), (20, 20, 0), (21, 20, 8)):
            rets.append(
                ctx.call("CREAT_DB", LOW_LIMIT=low, UP_LIMIT=up, COUNT=count, DB_NUMBER="MW0")[
                    "RET_VAL"
                ]
            )

    cpu = make_cpu(clock, main)
    cpu.start()
    cpu.scan()
    assert rets == [as_int(0x80A2), as_int(0x80A2), as_int(0x80A1)] and 20 not in cpu.mem.dbs


def test_test_db_on_a_missing_db_returns_80b1_and_del_db_deletes(clock: VirtualClock) -> None:
    """TEST_DB on a missing DB gives RET_VAL W#16#80B1; on an existing one DB_LENGTH; DEL_DB removes
    a DB, a second DEL_DB is W#16#80B1."""
    got: list[dict[str, object]] = []

    def main(ctx: CallContext) -> None:
        got.append(ctx.call("TEST_DB", DB_NUMBER=12, DB_LENGTH="MW0", WRITE_PROT="M2.0"))
        got.append(ctx.call("DEL_DB", DB_NUMBER=12))
        got.append(ctx.call("DEL_DB", DB_NUMBER=12))
        got.append(ctx.call("TEST_DB", DB_NUMBER=12, DB_LENGTH="MW0", WRITE_PROT="M2.0"))

    cpu = make_cpu(clock, main)
    cpu.start()
    cpu.scan()
    assert got[0] == {"RET_VAL": 0, "DB_LENGTH": 4, "WRITE_PROT": False}
    assert got[1]["RET_VAL"] == 0 and got[2]["RET_VAL"] == as_int(0x80B1)
    assert got[3] == {"RET_VAL": as_int(0x80B1)} and 12 not in cpu.mem.dbs


def test_dbs_created_by_creat_db_survive_a_warm_restart_but_not_a_cold_one(
    clock: VirtualClock,
) -> None:
    """A cold restart deletes SFC22-created DBs; a warm restart keeps them."""

    def main(ctx: CallContext) -> None:
        if ctx.cycle == 1 and 30 not in ctx.mem.dbs:
            ctx.call("CREAT_DB", LOW_LIMIT=30, UP_LIMIT=30, COUNT=2, DB_NUMBER="MW0")

    cpu = make_cpu(clock, main)
    cpu.start()
    cpu.scan()
    cpu.stop()
    cpu.start("warm")
    assert 30 in cpu.mem.dbs
    cpu.stop()
    cpu.start("cold")
    assert 30 not in cpu.mem.dbs and 12 in cpu.mem.dbs
