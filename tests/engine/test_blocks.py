"""Blocks, interfaces, instance DBs and calls (docs/runtime.md, "Programs of blocks in Python";
Siemens' Program Design for S7-300/400, ch. 2)."""

from __future__ import annotations

from typing import Any

import pytest

from s7graph.engine import BlockError, CallContext, Cpu, InstanceDB, Var, VirtualClock, fb, fc, ob
from s7graph.engine.blocks import Decl
from s7graph.sfb import s5_timers


class Tally:
    """An OBJECT value with to_state/from_state (like a GraphFB state)."""

    def __init__(self) -> None:
        self.hits = 0

    def to_state(self) -> dict[str, Any]:
        return {"hits": self.hits}

    @classmethod
    def from_state(cls, data: dict[str, Any]) -> Tally:
        t = cls()
        t.hits = int(data["hits"])
        return t


@fb(
    1,
    "Motor",
    IN={"start": "BOOL", "speed": ("INT", 10)},
    OUT={"running": "BOOL", "calls": "INT"},
    STAT={"n": ("INT", 0), "tally": ("OBJECT", Tally)},
    TEMP={"scratch": "INT"},
)
def motor(ctx: CallContext, db: InstanceDB) -> None:
    db.n = int(db.n) + 1  # type: ignore[call-overload]
    db.running = db.start
    db.calls = db.n
    tally = db.tally
    assert isinstance(tally, Tally)
    tally.hits += 1


def _cpu(clock: VirtualClock, body: Any) -> Cpu:
    cpu = Cpu(clock)
    cpu.load(ob(1)(body), motor)
    cpu.create_instance_db(1, motor)
    cpu.start()
    return cpu


def test_fb_stat_and_out_persist_between_calls(clock: VirtualClock) -> None:
    """STAT and OUT values stay in the instance DB; TEMP is never stored."""
    outs: list[dict[str, object]] = []
    cpu = _cpu(clock, lambda ctx: outs.append(ctx.call(motor, 1, start=True)))
    for _ in range(3):
        cpu.scan()
    assert outs[-1] == {"running": True, "calls": 3}
    idb = cpu.instance_db(1)
    assert "scratch" not in idb and "scratch" not in idb.snapshot()
    with pytest.raises(AttributeError):
        _ = idb.scratch


def test_omitted_fb_input_keeps_its_last_value(clock: VirtualClock) -> None:
    """An IN omitted at the call keeps the value stored in the instance DB."""
    calls = iter([{"start": True, "speed": 50}, {}])
    cpu = _cpu(clock, lambda ctx: ctx.call(motor, 1, **next(calls)))
    cpu.scan()
    cpu.scan()
    idb = cpu.instance_db(1)
    assert idb.start is True and idb.speed == 50


def test_fb_actuals_may_be_operands(clock: VirtualClock) -> None:
    """An address string is an operand: IN read from it, OUT written to it."""
    cpu = _cpu(clock, lambda ctx: ctx.call(motor, 1, start="I0.3", running="Q0.2", calls="MW4"))
    cpu.mem.periph_in[0] = 0b1000
    cpu.scan()
    assert cpu.mem.get("Q0.2") is True and cpu.mem.get("MW4") == 1


def test_calling_an_fb_without_instance_db_is_an_error(clock: VirtualClock) -> None:
    """docs/runtime.md, "Programs of blocks in Python": calling an FB without an instance DB raises
    BlockError."""
    ctx = Cpu(clock)._ctx
    with pytest.raises(BlockError, match="without an instance DB"):
        ctx.call(motor)


def test_fc_must_get_every_parameter_and_writes_to_the_actual_operand(clock: VirtualClock) -> None:
    """An FC needs all parameters; its OUT goes straight to the actual operand."""

    @fc(2, IN={"a": "INT", "b": "INT"}, OUT={"sum": "INT"}, RET="BOOL")
    def add(ctx: CallContext, p: dict[str, object]) -> object:
        p["sum"] = int(p["a"]) + int(p["b"])  # type: ignore[call-overload]
        return True

    results: list[dict[str, object]] = []
    cpu = _cpu(clock, lambda ctx: results.append(ctx.call(add, a=-5, b="MW10", sum="MW12")))
    cpu.mem.set("MW10", 7)
    cpu.scan()
    assert cpu.mem.get("MW12") == 2 and results == [{"sum": 2, "RET_VAL": True}]
    with pytest.raises(BlockError, match="missing"):
        cpu._ctx.call(add, a=1, sum="MW12")
    with pytest.raises(BlockError, match="needs an operand"):
        cpu._ctx.call(add, a=1, b=2, sum=3)


def test_two_multi_instances_are_independent(clock: VirtualClock) -> None:
    """FBs declared as STAT store their data in the caller's instance DB."""

    @fb(3, STAT={"m1": motor, "m2": motor})
    def line(ctx: CallContext, db: InstanceDB) -> None:
        ctx.call(db.m1, start=True)  # type: ignore[arg-type]
        ctx.call(db.m1, start=True)  # type: ignore[arg-type]
        ctx.call(db.m2)  # type: ignore[arg-type]

    cpu = Cpu(clock)
    cpu.load(ob(1)(lambda ctx: ctx.call(line, 3)), motor, line)
    idb = cpu.create_instance_db(3, line)
    cpu.start()
    cpu.scan()
    m1, m2 = idb.m1, idb.m2
    assert isinstance(m1, InstanceDB) and isinstance(m2, InstanceDB)
    assert (m1.n, m2.n, m1.running, m2.running) == (2, 1, True, False)
    assert idb.snapshot()["m1"]["n"] == 2  # type: ignore[index]


def test_object_stat_round_trips_through_snapshot(clock: VirtualClock) -> None:
    """docs/runtime.md, "Programs of blocks in Python": a STAT of type OBJECT persists through
    to_state()/from_state()."""
    a = InstanceDB(1, motor)
    b = InstanceDB(2, motor)
    assert a.tally is not b.tally  # each instance gets its own object
    tally = a.tally
    assert isinstance(tally, Tally)
    tally.hits = 9
    a.n = 4
    b.restore(a.snapshot())
    restored = b.tally
    assert isinstance(restored, Tally) and restored.hits == 9 and b.n == 4


def test_interface_declaration_rules() -> None:
    """Table 2-2: STAT only in FBs, no TEMP/FC initial values, known types, unique names."""
    with pytest.raises(BlockError, match="STAT"):
        fc(1, STAT={"x": "INT"})(lambda ctx, p: None)
    with pytest.raises(BlockError, match="initial"):
        fb(1, TEMP={"x": ("INT", 1)})(lambda ctx, db: None)
    with pytest.raises(BlockError, match="initial"):
        fc(1, IN={"x": ("INT", 1)})(lambda ctx, p: None)
    with pytest.raises(BlockError, match="unknown data type"):
        fb(1, IN={"x": "FLOAT"})(lambda ctx, db: None)
    with pytest.raises(BlockError, match="twice"):
        fb(1, IN={"x": "INT"}, OUT={"x": "INT"})(lambda ctx, db: None)
    with pytest.raises(BlockError, match="initial value"):
        fb(1, STAT={"x": ("INT", 40000)})(lambda ctx, db: None)
    assert motor.interface[0] == Var("start", "BOOL", Decl.IN)


def test_unknown_variable_and_parameter_are_errors(clock: VirtualClock) -> None:
    """docs/runtime.md, "The block runtime" spirit: no silent zeroes — unknown names raise
    BlockError."""
    idb = InstanceDB(1, motor)
    with pytest.raises(BlockError):
        idb.nope = 1
    cpu = Cpu(clock)
    cpu.load(motor)
    cpu.create_instance_db(1, motor)
    with pytest.raises(BlockError, match="no parameter"):
        cpu._ctx.call(motor, 1, nope=True)
    with pytest.raises(BlockError, match="already exists"):
        cpu.create_instance_db(1, motor)


def test_fc_out_operand_is_written_not_read_and_left_alone_when_unassigned() -> None:
    """An FC OUT refers to the actual operand and is only written — a zeroed
    DB (no valid DATE_AND_TIME bytes) is a fine OUT; an OUT the FC does not assign keeps
    the operand's value."""
    from datetime import datetime

    from s7graph.engine import DB, parse_address

    clock = VirtualClock()
    stamp = datetime(2026, 1, 2, 3, 4, 5)

    @fc(5, OUT={"CDT": "DATE_AND_TIME", "N": "INT"})
    def read_clock(ctx: CallContext, params: dict[str, Any]) -> None:
        assert "CDT" not in params
        params["CDT"] = stamp

    @ob(1)
    def main(ctx: CallContext) -> None:
        assert ctx.call("FC5", CDT="DB1.DBB0", N="MW10") == {"CDT": stamp}

    cpu = Cpu(clock)
    cpu.load(read_clock, main, DB(1, 8))
    cpu.mem.set("MW10", 77)
    cpu.start()
    record = cpu.scan()
    assert record.mode == "RUN", record.diagnostics
    assert cpu.mem.read_as(parse_address("DB1.DBB0"), "DATE_AND_TIME") == stamp
    assert cpu.mem.get("MW10") == 77


# The motor block of the mixing process (Siemens' Program Design for S7-300/400, appendix A, FB1
# "Motor"): one FB for pump A (DB1, timer T12) and the agitator (DB3, timer T16).
@fb(
    31,
    "Motor",
    IN={
        "Start": "BOOL",
        "Stop": "BOOL",
        "Ruec": "BOOL",
        "Zeit_Nr": "TIMER",
        "Ruec_Zeit": ("S5TIME", 0),
    },
    OUT={"Fehler": "BOOL", "Start_Anz": "BOOL", "Stop_Anz": "BOOL", "Wartung": "BOOL"},
    IN_OUT={"Motor": "BOOL"},
    STAT={"Starts": ("INT", 0), "Start_Flanke": ("BOOL", False)},
)
def seed_motor(ctx: CallContext, db: InstanceDB) -> None:
    db.Motor = bool((db.Start or db.Motor) and not db.Stop)  # network 1
    cell = s5_timers.cell_of(ctx.mem.timers, int(db.Zeit_Nr))  # type: ignore[call-overload]
    s5_timers.run(cell, "SD", bool(db.Motor), int(db.Ruec_Zeit), ctx.now_ns)  # type: ignore[call-overload]
    if cell.q and not db.Ruec:  # network 2: no feedback in time
        db.Fehler, db.Motor = True, False
    db.Start_Anz = db.Ruec  # network 3
    if db.Ruec:
        db.Fehler = False
    db.Stop_Anz = not db.Ruec  # network 4


def test_a_timer_parameter_carries_the_timer_number_so_each_instance_runs_its_own_timer(
    clock: VirtualClock,
) -> None:
    """A TIMER parameter passes the timer's number (``T12`` arrives as 12, not as its value):
    the mixing process's FB1 supervises pump A on T12 (7 s) and the agitator on T16 (10 s),
    each motor switched off by its own timer (Siemens' Program Design for S7-300/400,
    appendix A)."""
    seen: list[tuple[object, object]] = []

    def main(ctx: CallContext) -> None:
        t = ctx.now_ns // 1_000_000
        pump = ctx.call(seed_motor, 1, Start=t == 0, Zeit_Nr="T12", Ruec_Zeit=7000, Motor="Q8.4")
        mix = ctx.call(
            seed_motor, 3, Start=t == 3000, Zeit_Nr="T16", Ruec_Zeit=10000, Motor="Q10.0"
        )
        seen.append((pump["Fehler"], mix["Fehler"]))

    cpu = Cpu(clock)
    cpu.load(ob(1)(main), seed_motor)
    cpu.create_instance_db(1, seed_motor)
    cpu.create_instance_db(3, seed_motor)
    cpu.start()
    states: dict[int, tuple[object, ...]] = {}
    for t in range(0, 15000, 100):
        cpu.scan()
        states[t] = (cpu.mem.get("Q8.4"), cpu.mem.get("Q10.0"), *seen[-1])
        clock.advance(100)
    assert cpu.instance_db(1).values["Zeit_Nr"] == 12 and cpu.instance_db(3).values["Zeit_Nr"] == 16
    assert states[6900] == (True, True, False, False)
    assert states[7000] == (False, True, True, False)  # T12 ran out: pump A off, fault
    assert states[12900] == (False, True, True, False)
    assert states[13000] == (False, False, True, True)  # T16 ran out 10 s after its start


def test_a_timer_parameter_refuses_an_operand_that_is_not_a_timer(clock: VirtualClock) -> None:
    """A TIMER parameter takes a timer (``T n``), a COUNTER parameter a counter (``C n``)."""
    errors: list[str] = []

    def main(ctx: CallContext) -> None:
        for actual in ("MW10", "C12", True):
            try:
                ctx.call(seed_motor, 1, Zeit_Nr=actual)
            except BlockError as exc:
                errors.append(str(exc))

    cpu = Cpu(clock)
    cpu.load(ob(1)(main), seed_motor)
    cpu.create_instance_db(1, seed_motor)
    cpu.start()
    cpu.scan()
    assert len(errors) == 3 and all("takes a timer like T12" in e for e in errors), errors


def test_a_db_is_loaded_with_its_layout_and_keeps_it_through_a_cold_restart(
    clock: VirtualClock,
) -> None:
    """A downloaded DB's layout (its variables by name) is the CPU's DB's layout."""
    from s7graph.engine import DB, parse_address
    from s7graph.engine.datatypes import layout

    recipe = layout([("warm", "BOOL"), ("avg", "REAL")])
    cpu = Cpu(clock)
    cpu.load(DB(20, recipe.size, layout=recipe), DB(21, 4))
    assert cpu.mem.dbs[20].layout == recipe and cpu.mem.dbs[21].layout is None
    assert cpu.mem.dbs[20].field_address("avg") == parse_address("DB20.DBD2")
    cpu.start("cold")
    assert cpu.mem.dbs[20].layout == recipe


def test_a_db_is_found_by_its_symbol_first_then_by_its_own_name_in_any_case(
    clock: VirtualClock,
) -> None:
    """``Cpu.db_named``: a DB symbol wins; then an instance DB's or a global DB's own name,
    case-insensitive; nothing → None; a symbol of another block or an operand → the reason."""
    from s7graph.engine import DB
    from s7graph.engine.errors import S7Error
    from s7graph.engine.symbols import SymbolTable

    cpu = Cpu(clock)
    cpu.load(ob(1)(lambda ctx: None), motor, DB(20, 4, name="Recipe"), DB(21, 4, name="Motor_1"))
    cpu.create_instance_db(1, motor, name="Motor_1")
    cpu.mem.symbols = SymbolTable.from_text('"Oven"; DB21\n"Start"; I0.0; BOOL\n"Drive"; FB1\n')
    assert cpu.db_named('"Oven"') == 21
    assert cpu.db_named("recipe") == 20
    assert cpu.db_named("MOTOR_1") == 1  # an instance DB's name before a global DB's
    assert cpu.db_named("Nope") is None
    for name, reason in (("Start", "is the operand I0.0"), ("Drive", "is FB 1")):
        with pytest.raises(S7Error, match=reason):
            cpu.db_named(name)
