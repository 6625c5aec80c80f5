"""Warm, hot and cold restart: what each keeps and clears (docs/runtime.md, "Restarts: warm, hot,
cold"; Siemens' Program Design for S7-300/400, ch. 9)."""

from __future__ import annotations

from s7graph.engine import DB, CallContext, Cpu, CpuMode, EventId, InstanceDB, VirtualClock, fb, ob
from s7graph.engine.restart import RESTART, RestartType

ran: list[int] = []


@ob(100)
def ob100(ctx: CallContext) -> None:
    ran.append(100)


@ob(101)
def ob101(ctx: CallContext) -> None:
    ran.append(101)


@ob(102)
def ob102(ctx: CallContext) -> None:
    ran.append(102)


@fb(1, STAT={"n": ("INT", 5)})
def keeper(ctx: CallContext, db: InstanceDB) -> None:
    db.n = int(db.n) + 1  # type: ignore[call-overload]


def _cpu(clock: VirtualClock) -> Cpu:
    ran.clear()
    cpu = Cpu(clock)
    cpu.load(ob100, ob101, ob102, keeper, DB(5, 4, init=b"\x00\x2a"))
    cpu.create_instance_db(2, keeper)
    cpu.start("cold")
    ran.clear()
    mem = cpu.mem
    mem.set("MW0", 111)  # retentive (MB0..MB15)
    mem.set("MW100", 222)  # not retentive
    mem.set("DB5.DBW0", 333)
    mem.counters[0].set_value(7)  # C0 retentive
    mem.counters[20].set_value(9)  # C20 not retentive
    mem.set("Q0.1", True)
    cpu.instance_db(2).n = 77
    mem.create_db(9, 4, created=True)  # as SFC22 would
    clock.advance(10)
    cpu.scan()
    assert mem.periph_out[0] == 2
    cpu.stop()
    return cpu


def test_warm_restart_clears_non_retentive_and_keeps_retentive_and_dbs(
    clock: VirtualClock,
) -> None:
    """OB100; non-retentive M/C zeroed, retentive M/C and DBs kept, PIQ cleared."""
    cpu = _cpu(clock)
    cpu.start("warm")
    mem = cpu.mem
    assert ran == [100] and cpu.mode is CpuMode.RUN
    assert mem.get("MW0") == 111 and mem.get("MW100") == 0
    assert mem.counters[0].value == 7 and mem.counters[20].value == 0
    assert mem.get("DB5.DBW0") == 333 and 9 in mem.dbs
    assert cpu.instance_db(2).n == 77
    assert mem.get("Q0.1") is False


def test_cold_restart_resets_everything_to_initial_values(clock: VirtualClock) -> None:
    """OB102; all M/T/C zeroed, DBs reloaded, SFC22 DBs deleted."""
    cpu = _cpu(clock)
    cpu.start("cold")
    mem = cpu.mem
    assert ran == [102]
    assert mem.get("MW0") == 0 and mem.counters[0].value == 0
    assert mem.get("DB5.DBW0") == 42 and 9 not in mem.dbs
    assert cpu.instance_db(2).n == 5


def test_hot_restart_clears_nothing_but_the_outputs(clock: VirtualClock) -> None:
    """OB101; M/T/C and DBs kept; PIQ cleared unless parametrised to keep."""
    cpu = _cpu(clock)
    cpu.start("hot")
    mem = cpu.mem
    assert ran == [101] and cpu.last_restart is RestartType.HOT
    assert mem.get("MW100") == 222 and mem.counters[20].value == 9
    assert mem.get("Q0.1") is False
    cpu.stop()
    cpu.keep_outputs_on_hot_restart = True
    mem.set("Q0.1", True)
    cpu.start("hot")
    assert mem.get("Q0.1") is True


def test_hot_restart_is_refused_after_a_download(clock: VirtualClock) -> None:
    """After a block download in STOP only a warm restart is possible."""
    cpu = _cpu(clock)
    cpu.load(ob100)
    record = cpu.start("hot")
    assert ran == [100] and cpu.last_restart is RestartType.WARM
    assert any("hot restart refused" in e.message for e in record.diagnostics)
    assert cpu.mem.get("MW100") == 0


def test_hot_restart_is_refused_after_memory_reset(clock: VirtualClock) -> None:
    """After MRES only a warm restart is possible."""
    cpu = _cpu(clock)
    cpu.memory_reset()
    cpu.start("hot")
    assert cpu.last_restart is RestartType.WARM


def test_hot_restart_is_refused_after_a_stop_by_an_error(clock: VirtualClock) -> None:
    """A STOP by an error outside the program (the state file not written, a scan the
    supervisor ended) allows only a warm restart, as on S7 — also when read back from a
    saved diagnostic buffer."""
    from s7graph.engine.restart import stop_blocker

    cpu = _cpu(clock)
    cpu.stop_by_error(EventId.STOP_STATE_WRITE, "", "state file not written: disk full")
    cpu.start("hot")
    assert cpu.last_restart is RestartType.WARM
    killed = cpu.diagnostics.record(clock.now_ns(), EventId.STOP_KILLED, "plant p.py", "hung")
    assert stop_blocker([killed]) == "STOP by an error (hung)"


def test_hot_restart_is_refused_after_a_block_aborted_by_cycle_monitoring(
    clock: VirtualClock,
) -> None:
    """A STOP by cycle monitoring (a block still running at twice the maximum cycle time)
    allows only a warm restart in the running process too, not only once the state file
    is read back."""
    cpu = _cpu(clock)
    cpu.start()
    cpu.scan()
    cpu.abort("OB1")
    assert cpu.hot_blockers >= {"STOP by an error (block aborted by cycle monitoring)"}
    cpu.start("hot")
    assert cpu.last_restart is RestartType.WARM


def test_the_first_start_after_loading_is_never_hot(clock: VirtualClock) -> None:
    """A freshly downloaded program starts warm even if hot is asked for."""
    cpu = Cpu(clock)
    cpu.load(ob100, ob101)
    ran.clear()
    cpu.start("hot")
    assert ran == [100]


def test_missing_startup_ob_is_not_an_error(clock: VirtualClock) -> None:
    """Without OB100/101/102 the startup proceeds to RUN."""
    cpu = Cpu(clock)
    for kind in ("warm", "cold"):
        record = cpu.start(kind)
        assert record.mode is CpuMode.RUN
        assert EventId.STARTUP_TO_RUN in [e.event_id for e in record.diagnostics]
        cpu.stop()


def test_startup_has_no_monitoring_interrupts_or_outputs(clock: VirtualClock) -> None:
    """A long OB100 never times out, no OB35 runs, PIQ bits do not reach the
    modules, direct PQ writes do."""
    calls: list[int] = []

    @ob(100)
    def slow(ctx: CallContext) -> None:
        ctx.mem.set("Q0.0", True)
        ctx.mem.set("PQB10", 0x55)
        assert ctx.mem.periph_out[0] == 0
        clock.advance(10_000)  # an endless-looking startup program

    @ob(35)
    def cyclic(ctx: CallContext) -> None:
        calls.append(ctx.cycle)

    cpu = Cpu(clock)
    cpu.load(slow, cyclic)
    record = cpu.start()
    assert cpu.mode is CpuMode.RUN and calls == []
    assert cpu.mem.periph_out[10] == 0x55 and cpu.mem.periph_out[0] == 0
    assert record.outputs == {"PQB10": 0x55}
    clock.advance(20)
    record = cpu.scan()
    assert record.mode is CpuMode.RUN and record.ran == ()
    assert EventId.CYCLE_TIME_EXCEEDED not in [e.event_id for e in cpu.diagnostics]
    assert cpu.mem.periph_out[0] == 1


def test_restart_table_names_the_startup_obs() -> None:
    """docs/runtime.md, "Restarts: warm, hot, cold": warm OB100, hot OB101, cold OB102; only cold
    clears retentive data."""
    assert {t: r.ob for t, r in RESTART.items()} == {
        RestartType.WARM: 100,
        RestartType.HOT: 101,
        RestartType.COLD: 102,
    }
    assert [t for t, r in RESTART.items() if r.clear_retentive_mtc] == [RestartType.COLD]
