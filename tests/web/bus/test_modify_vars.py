"""``modify`` of a DB variable by name (``web/bus/modify_vars.py`` through
``web.bus.forcing.Forcing``) on the virtual clock: a global DB's variable by its layout and
an instance DB's variable — into an ARRAY by its declared bounds — are written once in their
declared types, as TIA Portal's watch table modifies ``"Data".temps[2]``, and so is a
chart's own variable by its instance DB's name (``"Seq_mix".count``); the audit's
detail names the variable (and its address); a name that does not resolve, a value that
does not fit, a multi-instance or an ARRAY whole are refused with the reason and nothing
written."""

from __future__ import annotations

import pytest

from s7graph.engine import Cpu, VirtualClock
from s7graph.engine.address import parse_address
from s7graph.web.bus.forcing import Forcing
from s7graph.web.bus.watch import parse_item, watch_value
from s7graph.web.commands import Modify, ModifyArgs
from s7graph.web.harness.session import ChartSession, compile_text
from tests.web.bus.test_diag_watch import program_cpu
from tests.web.opcua.helpers import CHART


@pytest.fixture
def cpu() -> Cpu:
    made = program_cpu(VirtualClock())
    made.start()
    made.scan()
    return made


def _modify(cpu: Cpu, address: str, value: bool | int | float | str) -> tuple[bool, str, str]:
    command = Modify(fb="", args=ModifyArgs(address=address, value=value), user="eng")
    return Forcing(cpu).apply(command)


def test_a_global_db_variable_is_modified_by_name_in_its_declared_type(cpu: Cpu) -> None:
    assert _modify(cpu, "DB20.speed", "-300") == (
        True,
        "",
        "modify DB20.speed (DB20.DBW0) = -300",
    )
    assert _modify(cpu, "DB20.temps[3]", 1.5) == (
        True,
        "",
        "modify DB20.temps[3] (DB20.DBD12) = 1.5",
    )
    assert _modify(cpu, "DB20.on", "TRUE")[0]
    cpu.scan()  # not held, nothing forced: the values stay until written again
    db = cpu.mem.dbs[20]
    assert cpu.mem.read_as(db.field_address("speed"), "INT") == -300
    assert cpu.mem.read_as(db.field_address("on"), "BOOL") is True
    assert cpu.mem.read_as(parse_address("DB20.DBD12"), "REAL") == 1.5
    assert len(cpu.forces) == 0


def test_an_instance_db_variable_is_modified_by_name_the_fb_reads_it(cpu: Cpu) -> None:
    assert _modify(cpu, "DB11.n", 99) == (True, "", "modify DB11.n = 99")
    assert _modify(cpu, "DB11.avg", "2.5") == (True, "", "modify DB11.avg = 2.5")
    cpu.scan()  # the FB counts on from the value written
    assert cpu.instance_dbs[11].values["n"] == 100
    assert _modify(cpu, "DB11.last[2]", "-4") == (True, "", "modify DB11.last[2] = -4")
    assert cpu.instance_dbs[11].values["last"][1] == -4


@pytest.mark.parametrize(
    ("name", "value", "says"),
    [
        ("DB11.n", 70000, "out of range for INT"),
        ("DB11.n", True, "takes a number"),
        ("DB11.last", 1, "ARRAY"),
        ("DB11.last[4]", 1, "index 4 outside 1..3"),
        ("DB11.last[1, 2]", 1, "DB11.last is no ARRAY of that shape: it takes no index [1,2]"),
        ("DB11.n[1]", 1, "DB11.n is no ARRAY of that shape"),
        ("DB11.nope", 1, "has no variable 'nope'"),
        ("DB20.speed", "T#5S", "a TIME"),
        ("DB20.temps", 1.0, "is an ARRAY: modify one of its elements"),
        ("DB20.gone", 1, "has no variable 'gone'"),
        ("DB20.speed:REAL", 1.0, "no ':TYPE'"),
        ('"Nope".x', 1, "no DB has this name"),
        ("DB99.x", 1, "DB99 is not loaded"),
    ],
)
def test_a_variable_that_does_not_resolve_or_fit_is_refused_and_nothing_written(
    cpu: Cpu, name: str, value: bool | int | str, says: str
) -> None:
    before = (bytes(cpu.mem.dbs[20].data), repr(cpu.instance_dbs[11].values))
    applied, reason, detail = _modify(cpu, name, value)
    assert not applied and says in reason and detail == "", reason
    assert (bytes(cpu.mem.dbs[20].data), repr(cpu.instance_dbs[11].values)) == before


def test_a_charts_own_variable_is_watched_and_modified_by_its_instance_dbs_name() -> None:
    """As S7-GRAPH keeps an FB's static variables in its instance DB: ``"Seq_mix".count``
    reads the chart's ``VAR count``, and a modify of it is what the chart counts on from."""
    cc, table = compile_text(CHART, "mix.s7g")
    session = ChartSession(cc, table, VirtualClock())
    session.start()
    session.scan()
    cpu = session.cpu
    seen = watch_value(cpu, parse_item('"Seq_mix".count'))
    assert (seen.value, seen.type, seen.error) == (0, "INT", "")
    assert _modify(cpu, "DB1.count", "41") == (True, "", "modify DB1.count = 41")
    assert _modify(cpu, '"Seq_mix".DWELL', "T#3S") == (True, "", 'modify "Seq_mix".DWELL = T#3S')
    session.set("Start", True)  # S1 -> S2, whose S1 action counts: count := count + 1
    for _ in range(3):
        session.scan()
    assert session.graph.state.vars == {"count": 42, "dwell": 3000}
    applied, reason, _ = _modify(cpu, "DB1.count", "T#1S")
    assert not applied and "DB1.count" in reason
    applied, reason, _ = _modify(cpu, "DB1.counts", 1)
    assert not applied and "it has count, dwell, OFF_SQ" in reason


def test_an_instance_dbs_bytes_are_refused_naming_its_fb_and_a_variable(cpu: Cpu) -> None:
    """An FB's instance DB is kept by variable name here, not as bytes: ``DB11.DBW0`` says
    so — whose instance DB it is, and a variable to use — where a DB that is not there
    says it does not exist; a watch says it without the operand twice."""
    reason = (
        "DB11 is the instance DB of FB10 'Average': it has no byte addresses here; read and "
        "write its variables by name (DB11.x)"
    )
    assert _modify(cpu, "DB11.DBW0", 5) == (False, f"DB11.DBW0: {reason}", "")
    assert watch_value(cpu, parse_item("DB11.DBX0.1")).error == reason
    assert watch_value(cpu, parse_item("DB77.DBW0")).error == "DB77 does not exist"


def test_a_force_or_modify_that_breaks_in_the_cpu_is_refused_in_words(
    cpu: Cpu, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A defect of ours behind the force table's last guard: an internal error, which op,
    what it said — never the exception's class name."""

    def broken(self: Forcing, command: object) -> None:
        raise KeyError("x")

    monkeypatch.setattr(Forcing, "_apply", broken)
    assert _modify(cpu, "MW0", 1) == (
        False,
        "modify refused: an internal error in the CPU while applying modify: 'x' "
        "(please report it)",
        "",
    )
