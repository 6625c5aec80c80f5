"""The editor checks a chart's calls against the user blocks a CPU holds that come as no
S7-SCL source — a Python program's FBs and FCs loaded beside the chart — over a real zenoh
bus (docs/online-change.md, "Editing in the browser and downloading"): the CPU sends their
interfaces with the running chart's source (``ChartSource.interfaces``), the editor reads
them (``web.view.editor_cpu.cpu_blocks``), and a call that does not fit is E047 at its line
and column, the very diagnostics the CPU's download refuses it with. A ChartSource from a
CPU from before (no ``interfaces``) still reads; a hostile one is refused naming the field,
and the editor says so and goes on.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from types import SimpleNamespace
from typing import TYPE_CHECKING, Any

import msgspec
import pytest

from s7graph.engine import CallContext, InstanceDB, fb, fc
from s7graph.sequencer.change.edit import Session
from s7graph.sequencer.change.typed import parse_source
from s7graph.sequencer.checks.diagnostics import format_diagnostic
from s7graph.sequencer.checks.interfaces import program_blocks
from s7graph.sequencer.text.format import format_chart
from s7graph.web.bus.client import BusClient
from s7graph.web.bus.protocol import BlockInterfaces, ChartSource, ProtocolError, decode, encode
from s7graph.web.bus.session import open_session
from s7graph.web.view.editor import _located
from s7graph.web.view.editor_cpu import CpuCommands, cpu_blocks
from tests.web.helpers import CALLS_FB17, OnlineClient, free_port, online_client, wait_until

if TYPE_CHECKING:
    from tests.conftest import BusCerts

pytestmark = pytest.mark.timeout(180)


@fb(17, "Motor", IN={"go": "BOOL", "k": "INT"}, OUT={"q": "BOOL"}, STAT={"n": ("INT", 0)})
def motor(ctx: CallContext, db: InstanceDB) -> None:
    if db.go:
        db.n += 1
    db.q = db.go


@fc(5, "Plus", IN={"a": "INT"}, OUT={"r": "INT"})
def plus(ctx: CallContext, params: dict[str, Any]) -> None:
    params["r"] = params["a"] + 1


class PythonProgram:
    """A program of blocks written in Python (docs/runtime.md, "Programs of blocks in
    Python"), loaded beside the chart: FB17 "Motor" and FC5 "Plus", no source text."""

    blocks = (motor, plus)

    def load(self, cpu: Any) -> None:
        cpu.load(*self.blocks)


UNFIT = CALLS_FB17.replace(
    "CALL FB 17, DB 10 (go := TRUE);",
    "CALL FB 17, DB 10 (go := 2.5, nope := 1); CALL FC 5, DB 12 (a := 1, r => MW20);",
)


PIN = {"name": "a", "direction": "IN", "type": "INT"}
SCL_FB17 = """FUNCTION_BLOCK FB17
VAR_INPUT go : BOOL; k : INT; END_VAR
VAR_OUTPUT q : BOOL; END_VAR
  q := go;
END_FUNCTION_BLOCK
FUNCTION FC5 : VOID
VAR_INPUT a : INT; END_VAR
VAR_OUTPUT r : INT; END_VAR
  r := a + 1;
END_FUNCTION
"""


@pytest.fixture
def cpu(tmp_path: Path, bus_certs: BusCerts) -> Iterator[OnlineClient]:
    program = PythonProgram()
    with online_client(
        tmp_path, CALLS_FB17, certs=bus_certs, name="seq.s7g", program=program
    ) as cpu:
        yield cpu


def test_the_editor_marks_a_call_that_does_not_fit_a_python_programs_block_as_the_download(
    cpu: OnlineClient,
) -> None:
    source = cpu.client.source("Seq")
    assert source is not None and source.blocks == {} and source.interfaces is not None
    chart = parse_source(UNFIT, "seq.s7g")
    blocks, note = cpu_blocks(source, chart)
    assert note == "" and blocks is not None
    found = [d for d in _located(chart, None, blocks).diagnostics if d.is_error]
    assert [(d.code, d.message[:26]) for d in found] == [
        ("E047", "FB17 has no parameter nope"),
        ("E047", "FB17: go is BOOL, REAL doe"),
        ("E047", "FC5 is an FC and takes no "),
    ]
    shown = format_chart(chart).splitlines()  # as the source view writes it
    assert shown[found[1].loc.line - 1][found[1].loc.col - 1 :].startswith("2.5")
    assert Session.open(chart, None, blocks).has_errors  # the page's Download refuses
    reply = cpu.send("download", source=format_chart(chart), preview=True)
    assert not reply.applied
    assert reply.reason.startswith("the chart's calls do not fit the CPU's blocks: ")
    marked = [format_diagnostic(d).removeprefix("seq.s7g:") for d in found]  # 5:30: error…
    assert [line.removeprefix("the edited chart:") for line in reply.lines] == marked


def test_calls_that_fit_the_python_programs_blocks_show_no_error_and_download(
    cpu: OnlineClient,
) -> None:
    source = cpu.client.source("Seq")
    assert source is not None
    fits = "(go := TRUE, k := 3); CALL FC 5 (a := 41, r => MW20);"
    text = format_chart(parse_source(CALLS_FB17.replace("(go := TRUE);", fits), "seq.s7g"))
    chart = parse_source(text, "seq.s7g")
    blocks, _ = cpu_blocks(source, chart)
    assert [d.code for d in _located(chart, None, blocks).diagnostics if d.is_error] == []
    reply = cpu.send("download", source=text)
    assert reply.applied, reply.reason
    assert wait_until(lambda: int(cpu.session.get("MW20")) == 42)


def test_the_interfaces_come_back_as_the_cpu_holds_them() -> None:
    held = program_blocks(PythonProgram.blocks, {10: "FB17"})
    sent = decode(encode(BlockInterfaces.of(held)), BlockInterfaces)
    assert sent.program() == held
    assert held.find("", "MOTOR") is held.find("FB", 17)


def test_a_chart_source_from_a_cpu_from_before_reads_without_interfaces() -> None:
    before = b'{"fb":"Seq","version":3,"file":"seq.s7g","text":"x","blocks":{},"left_out":[]}'
    source = decode(before, ChartSource)
    assert source.interfaces is None and source.version == 3
    chart = parse_source(CALLS_FB17, "seq.s7g")
    assert cpu_blocks(source, chart) == (None, "")


@pytest.mark.parametrize(
    ("interfaces", "field"),
    [
        ({"blocks": [{"kind": "FB", "number": "seventeen"}]}, "$.interfaces.blocks[0].number"),
        ({"blocks": [{"kind": "OB", "number": 1}]}, "$.interfaces.blocks[0].kind"),
        (
            {"blocks": [{"kind": "FC", "number": 5, "pins": [{"name": "a", "type": "INT"}]}]},
            "$.interfaces.blocks[0].pins[0]",
        ),
        (
            {
                "blocks": [
                    {
                        "kind": "FB",
                        "number": 1,
                        "pins": [{"name": "a", "direction": "UP", "type": "INT"}],
                    }
                ]
            },
            "$.interfaces.blocks[0].pins[0].direction",
        ),
        ({"global_dbs": [70000]}, "$.interfaces.global_dbs[0]"),
        ({"blocks": [{"kind": "FB", "number": 1}] * 4097}, "$.interfaces.blocks"),
        ({"instances": [[10, "x" * 81]]}, "$.interfaces.instances[0][1]"),
        ([1, 2], "$.interfaces"),
    ],
    ids=["number", "kind", "no-direction", "direction", "db", "too-many", "label", "not-a-map"],
)
def test_a_hostile_chart_sources_interfaces_are_refused_naming_the_field(
    interfaces: object, field: str
) -> None:
    hostile = {"fb": "Seq", "text": "x", "interfaces": interfaces}
    with pytest.raises(ProtocolError) as refused:
        decode(msgspec.json.encode(hostile), ChartSource)
    assert str(refused.value).startswith("invalid ChartSource: ")
    assert field in str(refused.value), refused.value


def test_s7_scl_sources_too_large_to_come_along_send_their_interfaces_instead(
    tmp_path: Path, bus_certs: BusCerts
) -> None:
    """A chart so large that the CPU's S7-SCL source does not fit beside it in the message
    (``left_out``): the interfaces come instead (the source by its file name, no directory,
    as the sources go), and the editor marks the unfit call."""
    padding = "".join(f"// line {n:06d} {'.' * 60}\n" for n in range(11_200))
    blocks = {"fb.scl": SCL_FB17}
    text = padding + CALLS_FB17
    with online_client(
        tmp_path, text, certs=bus_certs, user=None, name="seq.s7g", blocks=blocks
    ) as on:
        source = on.client.source("Seq")
    assert source is not None and source.left_out == ["fb.scl"] and source.blocks == {}
    assert source.interfaces is not None and source.interfaces.sources == "fb.scl"
    chart = parse_source(UNFIT, "seq.s7g")
    blocks, note = cpu_blocks(source, chart)
    assert note == ""
    found = [d for d in _located(chart, None, blocks).diagnostics if d.is_error]
    assert [d.message[:26] for d in found][:2] == [
        "FB17 has no parameter nope",
        "FB17: go is BOOL, REAL doe",
    ]


def test_a_chart_source_that_does_not_read_is_said_by_the_editor_which_goes_on() -> None:
    """A peer on a real zenoh session answers the chart's source with interfaces of the
    wrong shape: the editor's read of it gives no chart and the reason, naming the key and
    the field — never an internal error."""
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    hostile = {"fb": "Seq", "text": CALLS_FB17, "interfaces": {"blocks": [{"kind": "FB"}]}}
    with open_session(listen=[endpoint]) as peer:
        answer = msgspec.json.encode(hostile)
        peer.declare_queryable("s7graph/odd/**", lambda q: q.reply(q.key_expr, answer))
        with open_session(connect=[endpoint]) as session, BusClient(session, "odd") as client:
            editor = SimpleNamespace(eng=SimpleNamespace(source=lambda: client.source("Seq")))
            source, why = CpuCommands._source(editor)  # type: ignore[arg-type]
    assert source is None
    assert why.startswith("the CPU's chart cannot be read: s7graph/odd/fb/Seq/source: ")
    assert "invalid ChartSource: " in why and "$.interfaces.blocks[0]" in why, why


def test_the_editor_compiles_the_cpus_s7_scl_sources_to_the_interfaces_the_cpu_holds(
    tmp_path: Path, bus_certs: BusCerts
) -> None:
    """Sources that come with the chart are compiled in the page as the CPU compiled them
    (its symbol table and the chart's ``SYMBOLS``, which the source reads): the same
    blocks, instance DBs and global DBs as the CPU holds — the sources named by file name
    only, as they come."""
    from tests.web.harness.test_scl_blocks import CHART, SCL

    blocks = {"prog.scl": SCL}
    with online_client(
        tmp_path, CHART, certs=bus_certs, user=None, name="seq.s7g", blocks=blocks
    ) as on:
        source = on.client.source("Seq")
        held = on.rig.online.held_interfaces()
    assert source is not None and source.interfaces is None and list(source.blocks) == ["prog.scl"]
    blocks, note = cpu_blocks(source, parse_source(source.text, "seq.s7g"))
    assert note == "" and blocks is not None and held is not None
    assert (blocks.blocks, blocks.instances, blocks.global_dbs) == (
        held.blocks,
        held.instances,
        held.global_dbs,
    )
    assert (blocks.sources, held.sources) == ("prog.scl", str(tmp_path / "prog.scl"))
