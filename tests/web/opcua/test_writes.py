"""``s7graph opcua --writes modify``: a client's write of a symbol is a modify — written
once at the scan boundary, as an S7-1500's OPC UA server writes a PLC tag — instead of a
force job: an input written is read by the program's next scan, an output written is
written over by the program again (not held), a data block's symbol becomes writable,
no force job is left; still an engineer's op through the CPU's gate, audited
(docs/opcua.md, "Writes")."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING

import pytest
from asyncua import ua
from asyncua.ua.uaerrors import UaStatusCodeError

from s7graph.web.access.audit import read_audit
from s7graph.web.cli.opcua import OpcuaProcess
from s7graph.web.opcua.space import WRITES, symbol_writable
from tests.web.opcua.helpers import (
    CHART,
    FaceRig,
    connected,
    eventually,
    face_rig,
    node,
    run,
)

if TYPE_CHECKING:
    from tests.conftest import BusCerts

pytestmark = pytest.mark.timeout(120)

# the face's chart with "Total" in a global data block (an S7-SCL source beside it)
TOTAL = """  "Total" : DB1.DBW30 : INT;"""
WRITES_CHART = CHART.replace(TOTAL, """  "Total" : DB10.DBW0 : INT;""")
DATA = "DATA_BLOCK DB10\nSTRUCT total : INT; END_STRUCT\nBEGIN\nEND_DATA_BLOCK\n"


@pytest.fixture(scope="module")
def face(tmp_path_factory: pytest.TempPathFactory, bus_certs: BusCerts) -> Iterator[FaceRig]:
    where = tmp_path_factory.mktemp("writes")
    assert TOTAL in CHART
    options = {"writes": "modify"}
    with face_rig(
        where, bus_certs, chart=WRITES_CHART, options=options, blocks={"data.scl": DATA}
    ) as rig:
        rig.set("Guard", True)
        yield rig


async def _reads(client: object, path: str, expected: object) -> bool:
    try:
        return bool(await node(client, path).read_value() == expected)
    except UaStatusCodeError:
        return False


async def _writable(client: object, path: str) -> bool:
    level = await node(client, path).read_attribute(ua.AttributeIds.UserAccessLevel)
    return bool(level.Value.Value & ua.AccessLevel.CurrentWrite.mask)


def test_the_areas_a_write_takes_are_forces_or_modifys() -> None:
    assert [symbol_writable(a, "force") for a in ("I0.0", "QB1", "MW20", "DB1.DBW30")] == [
        True,
        True,
        True,
        False,
    ]
    assert all(symbol_writable(a, "modify") for a in ("I0.0", "QB1", "MW20", "DB1.DBW30"))
    assert not any(symbol_writable(a, op) for a in ("T1", "C2", "PIW256") for op in WRITES)


def test_the_docs_table_of_writes_is_the_faces() -> None:
    text = (Path(__file__).resolve().parents[3] / "docs" / "opcua.md").read_text()
    rows = [line.split("|")[1:5] for line in text.splitlines() if line.startswith("| `")]
    found = {
        op.split("`")[1]: (areas.strip().removeprefix("on "), variables.strip())
        for op, _, areas, variables in rows
        if "`" in op
    }
    assert {op: found.get(op) for op in WRITES} == {
        op: (", ".join(w.areas), "writable" if w.variables else "read only")
        for op, w in WRITES.items()
    }


def test_run_hands_what_a_write_sends_to_its_opcua_child() -> None:
    child = OpcuaProcess(
        connect=["tcp/127.0.0.1:1"], cpu="cpu1", url="opc.tcp://127.0.0.1:4840", writes="modify"
    )
    cmd = child.command()
    assert cmd[cmd.index("--writes") + 1] == "modify"


def test_a_written_symbol_is_modified_once_and_not_held(face: FaceRig) -> None:
    cpu = face.rig.session.cpu

    async def check() -> None:
        true = ua.Variant(True, ua.VariantType.Boolean)
        async with connected(face.url, "olga") as c:  # modify: an engineer's
            with pytest.raises(UaStatusCodeError) as refused:
                await node(c, "cpu1/Symbols/Start").write_value(true)
            assert int(refused.value.code) == ua.StatusCodes.BadUserAccessDenied
        async with connected(face.url, "eng") as c:
            assert await _writable(c, "cpu1/Symbols/Total")  # a data block's: modify only
            await node(c, "cpu1/Symbols/Start").write_value(true)  # the program reads it
            assert await eventually(lambda: _reads(c, "cpu1/Seq_mix/S2/Active", True))
            assert await eventually(lambda: _reads(c, "cpu1/Symbols/Valve", True))  # N "Valve"
            await node(c, "cpu1/Symbols/Valve").write_value(ua.Variant(False))
            assert await eventually(lambda: _reads(c, "cpu1/Symbols/Valve", True))  # not held
            total = ua.Variant(9, ua.VariantType.Int16)
            await node(c, "cpu1/Symbols/Total").write_value(total)
            assert await eventually(lambda: _reads(c, "cpu1/Symbols/Total", 9))
            assert await _reads(c, "cpu1/ForceJobs", 0)
            count = "cpu1/Seq_mix/Variables/count"  # a chart's own variable, by name
            await node(c, count).write_value(ua.Variant(41, ua.VariantType.Int16))
            assert await eventually(lambda: _reads(c, count, 41))
            assert face.rig.session.graph.state.vars["count"] == 41
            with pytest.raises(UaStatusCodeError) as refused:
                await node(c, "cpu1/Symbols/Total").write_value(ua.Variant(1.5))
            assert int(refused.value.code) == ua.StatusCodes.BadTypeMismatch

    run(check())
    assert len(cpu.forces) == 0
    rows = [(r.user, r.outcome) for r in read_audit(face.rig.state) if r.op == "modify"]
    assert rows == [("olga", "refused")] + [("eng", "applied")] * 4
    details = [r.detail for r in read_audit(face.rig.state) if r.op == "modify"]
    assert 'modify "Seq_mix".count = 41' in details[-1]
    assert not [r for r in read_audit(face.rig.state) if r.op == "force"]
