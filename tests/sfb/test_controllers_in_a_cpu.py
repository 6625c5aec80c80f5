"""The process-control blocks in a CPU: called from a chart's row (``CALL SFB 41, DB 41``)
and from a Python program's OB35, through the CPU's block table as any system block, with
the instance DB's initial values from the catalogue; the pin tables of docs/runtime.md are
the catalogue's (docs/runtime.md, "Process control: CONT_C, CONT_S, PULSEGEN")."""

from __future__ import annotations

import json
from dataclasses import fields
from pathlib import Path
from typing import Any

import pytest

from s7graph.engine.clock import VirtualClock
from s7graph.sfb import SYSTEM_BLOCKS, install
from s7graph.sfb.catalogue import lookup, pin_table
from s7graph.sfb.cont_c import SFB41, ContC, ContCIn, ContCOut
from s7graph.sfb.cont_s import ContSIn, ContSOut
from s7graph.sfb.pulsegen import PulseGenIn, PulseGenOut
from s7graph.web.cli import main
from s7graph.web.cli.run_program import build_cpu, import_program

ROOT = Path(__file__).resolve().parents[2]

CHART = """FUNCTION_BLOCK "Loop" FB 3 DB 3
VAR out : REAL; limited : BOOL; END_VAR
SEQUENCE 1 "Main"
  INITIAL_STEP S1 "Control":
    CALL SFB 41, DB 41 (MAN_ON := FALSE, CYCLE := T#10MS, SP_INT := 50.0, PV_IN := 40.0,
      GAIN := 2.0, TI := T#1S, LMN_HLM := 30.0, LMN => out, QLMN_HLM => limited);
  END_STEP
  STEP S2 "Limited":
  END_STEP
  TRANSITION T1 FROM S1 TO S2 := limited;
  TRANSITION T2 FROM S2 TO S1 := FALSE;
END_SEQUENCE
END_FUNCTION_BLOCK
"""

PROGRAM = """
from s7graph.engine import CallContext, Cpu, ob
from s7graph.sfb.cont_c import SFB41


@ob(35)
def control(ctx: CallContext) -> None:
    ctx.call("SFB41", 41, MAN_ON=False, CYCLE=100, SP_INT=50.0, PV_IN="MD10", TI=10_000,
             LMN_PER="QW4")


@ob(1)
def main(ctx: CallContext) -> None:
    pass


def setup(cpu: Cpu) -> None:
    cpu.interrupts.configure(35, 100)
    cpu.create_instance_db(41, SFB41)
"""


def test_a_chart_row_drives_cont_c_until_its_limit_switches_the_sequence(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """ErKp = 2 * (50 - 40) = 20; a call of T#10MS adds 20 * 0.01 / 1 = 0.2 to the I part,
    the first one 0.1. OB100's startup call of the chart is the first call, so cycle n is
    call n + 2: LMN = 20 + 0.1 + 0.2 * (n + 1) — 20.3 in cycle 0, 29.9 in cycle 48, 30.1
    limited to LMN_HLM 30 in cycle 49; QLMN_HLM switches to S2 in cycle 50."""
    path = tmp_path / "loop.s7g"
    path.write_text(CHART, encoding="utf-8")
    assert main(["check", str(path)]) == 0
    capsys.readouterr()
    rc = main(["sim", str(path), "--cycles", "52", "--watch", "out,limited"])
    out, err = capsys.readouterr()
    trace = [json.loads(line) for line in out.splitlines()]
    assert rc == 0 and err == ""
    values = [line["values"] for line in trace]
    assert values[0]["out"] == pytest.approx(20.3, abs=1e-4)
    assert values[48] == {"out": pytest.approx(29.9, abs=1e-4), "limited": False}
    assert values[49] == {"out": 30.0, "limited": True}
    assert next(line["cycle"] for line in trace if line["active"] == ["S2"]) == 50


def test_a_python_program_calls_cont_c_from_ob35_by_its_number(tmp_path: Path) -> None:
    """The CPU of ``s7graph run PROGRAM.py`` has the system blocks. The instance DB starts
    with Siemens' values (manual mode, GAIN 2.0, TI T#20S, ...); OB35 every 100 ms with
    CYCLE T#100MS, ER 5, GAIN 2, TI 10 s: call k gives LMN = 10 + 0.1 * k - 0.05, so after
    10 calls 10.95 and LMN_PER = 10.95 * 276.48 = 3027.456 -> 3027."""
    path = tmp_path / "loop.py"
    path.write_text(PROGRAM, encoding="utf-8")
    clock = VirtualClock()
    cpu = build_cpu(import_program(path), clock)
    idb = cpu.instance_db(41)
    assert (idb["MAN_ON"], idb["GAIN"], idb["TI"], idb["LMN_HLM"]) == (True, 2.0, 20_000, 100.0)
    cpu.mem.set("MD10", 45.0)
    cpu.start()
    for _ in range(10):
        clock.advance(100)
        cpu.scan()
    assert idb["LMN"] == pytest.approx(10.95)
    assert cpu.mem.get("QW4") == 3027
    assert isinstance(idb["STATE"], ContC)
    copy = cpu.create_instance_db(42, SFB41)
    copy.restore(idb.snapshot())
    assert copy["STATE"] == idb["STATE"]


def test_every_controller_is_a_system_block_of_the_cpu(clock: VirtualClock) -> None:
    from s7graph.engine.cpu import Cpu

    cpu = Cpu(clock)
    install(cpu)
    for label in ("SFB41", "SFB42", "SFB43"):
        block = cpu.block(label)
        assert block in SYSTEM_BLOCKS and cpu.block(block.name) is block


@pytest.mark.parametrize(
    ("name", "inputs", "outputs"),
    [
        ("CONT_C", ContCIn, ContCOut),
        ("CONT_S", ContSIn, ContSOut),
        ("PULSEGEN", PulseGenIn, PulseGenOut),
    ],
)
def test_the_step_records_are_the_catalogues_pins(name: str, inputs: Any, outputs: Any) -> None:
    """Names, order and initial values: the Python records and the catalogue agree."""
    entry = lookup(name)
    ins = [(f.name, f.default) for f in fields(inputs)]
    assert ins == [(p.name, p.initial) for p in entry.inputs]
    outs = [(n, outputs._field_defaults[n]) for n in outputs._fields]
    assert outs == [(p.name, p.initial) for p in entry.outputs]


def test_docs_runtime_md_shows_each_controllers_pins_as_the_catalogue_has_them() -> None:
    text = (ROOT / "docs" / "runtime.md").read_text(encoding="utf-8")
    assert "| `GAIN` | IN | REAL | `2.0` |" in pin_table(lookup("CONT_C"))
    for name in ("CONT_C", "CONT_S", "PULSEGEN"):
        table = pin_table(lookup(name))
        assert table in text, f"docs/runtime.md lacks the pin table of {name}:\n{table}"
