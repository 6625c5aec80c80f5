"""One synthetic file per construct the import and export fixes are about, beside the
tests (``tests/sequencer/exchange/``), each read by a test: the corpus shows that real
projects import; these pin each construct on its own."""

from __future__ import annotations

from tests.sequencer.exchange.helpers import HERE

# construct → the synthetic file that pins it
CONSTRUCTS: dict[str, str] = {
    "Beremiz: COMPUTE_FUNCTION_BLOCKS, an S action on the initial step": (
        "beremiz_compute_blocks.st"
    ),
    "Beremiz: TON and R_TRIG drawn in a chart's FBD network": "beremiz_chart_blocks.xml",
    "R_TRIG, F_TRIG, SR and RS instances": "edge_latch_blocks.st",
    "SEL on BOOLs in a condition, SEL on numbers refused": "sel_condition.st",
    "ST bodies with IF, CASE, FOR; END_IF without ';'": "codesys_statements.xml",
    "ST bodies run as SCL FCs": "codesys_scl_bodies.xml",
    "':= 1' as a transition condition": "literal_condition.st",
    "x(L, dt): an action time given by a TIME variable": "time_variable_action.st",
    "an IL POU beside a chart in a textual file": "il_beside_chart.st",
    "SFC bodies of actions (TwinCAT, CODESYS)": "twincat_action_charts.xml",
    "SimaticML: Scope=GlobalConstant operands": "tia_global_constant.xml",
    "SimaticML: a step's U compared with an untyped tag": "tia_time_compare.xml",
    "SimaticML: tags without address inside the CPU's M area": "tia_many_tags.xml",
    "SimaticML: transitions nobody named (TIA's default name, no name)": (
        "tia_unnamed_transitions.xml"
    ),
    "export to PLCopen: the permanent instructions": "plcopen_export_permanent.s7g",
    "export to PLCopen: IEC timer and counter calls": "plcopen_export_timers.s7g",
    "export to PLCopen: a six-sequence chart read by another tool": "six_sequences.s7g",
    "export to SimaticML: the addresses of action operands": "tia_export_addresses.s7g",
    "export to SimaticML: CALL rows": "tia_export_call_rows.s7g",
    "export to SimaticML: permanent CALLs and moves": "permanent_boxes.s7g",
    "export to both: instance DB variables read by name, DB symbols": "db_reads.s7g",
}


def test_each_construct_has_its_synthetic_file_and_a_test_reads_each_file() -> None:
    files = {p.name for p in HERE.iterdir() if p.suffix in (".st", ".xml", ".s7g")}
    assert sorted(set(CONSTRUCTS.values()) ^ files) == []
    tests = "".join(
        p.read_text(encoding="utf-8")
        for p in sorted(HERE.glob("test_*.py"))
        if p.name != "test_synthetic_files.py"
    )
    assert sorted(f for f in files if f'"{f}"' not in tests) == []
