"""A DB passed by a chart's CALL to the BLOCK_DB input of an S7-SCL block: ``src := DB5``,
or a DB's symbol of the chart's ``SYMBOLS`` or of the symbol table, goes as the DB's number
(as the engine holds a BLOCK_DB: the WORD ``W#16#5``, which keeps working). A DB goes to a
BLOCK_DB input only, a BLOCK_DB input takes a DB or a WORD only, and a DB is numbered
1..65535: each mistake is an error at its place — at ``check --blocks``, at a compile with
the program's blocks, and at load against the block the CPU holds; an instance DB has no
bytes to pass (docs/chart-format.md; docs/scl.md, "Operands")."""

from __future__ import annotations

from pathlib import Path

import pytest

from s7graph import sfb
from s7graph.engine import Cpu, CpuMode, VirtualClock
from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.calls import call_sites, plan_calls, prepare_calls
from s7graph.sequencer.checks.interfaces import ProgramBlocks, program_blocks
from s7graph.sequencer.checks.validate import validate
from s7graph.sequencer.compile import ChartError, compile_chart
from s7graph.sequencer.fb import GraphFB, install_all
from s7graph.sequencer.text.parse import parse_chart
from s7graph.steps.scl import SclProgram, compile_scl
from s7graph.web.harness.session import ChartSession

SCL = """
DATA_BLOCK DB5
STRUCT a : INT := 11; END_STRUCT
BEGIN
END_DATA_BLOCK
DATA_BLOCK DB6
STRUCT a : INT := 22; END_STRUCT
BEGIN
END_DATA_BLOCK
FUNCTION_BLOCK FB17
VAR n : INT; END_VAR
  n := n + 1;
END_FUNCTION_BLOCK
DATA_BLOCK DB12 FB17
BEGIN
END_DATA_BLOCK
FUNCTION FC5 : VOID
VAR_INPUT src : BLOCK_DB; x : INT; END_VAR
  MW12 := src.DW0;
  MW14 := INT_TO_WORD(x);
END_FUNCTION
"""

TABLE = '"Other" ; DB 6 ; DB 6\n"Count" ; MW20 ; INT\n'


def chart_text(args: str, *, in_step: bool = False) -> str:
    """A chart calling FC 5 with ``args``: in its permanent instructions, or in step S2."""
    call = f"CALL FC 5 ({args});"
    return f"""FUNCTION_BLOCK "Seq" FB 1 DB 1
VAR n : INT; w : WORD; END_VAR
SYMBOLS
  "Recipe" : DB5 : DB5;
  "Lamp" : Q0.0 : BOOL;
END_SYMBOLS
PERMANENT BEFORE
  {"" if in_step else call}
END_PERMANENT
SEQUENCE 1 "S"
  INITIAL_STEP S1 "wait": END_STEP
  STEP S2 "read": {call if in_step else ""} END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.0;
  TRANSITION T2 FROM S2 TO S1 := FALSE;
END_SEQUENCE
END_FUNCTION_BLOCK
"""


def program() -> SclProgram:
    return compile_scl(SCL, "recipe.scl", blocks=sfb.SYSTEM_BLOCKS)


def interfaces() -> ProgramBlocks:
    built = program()
    return program_blocks(built.blocks, built.instances, sources="recipe.scl")


def table() -> SymbolTable:
    return SymbolTable.from_text(TABLE)


def loaded(text: str) -> tuple[Cpu, VirtualClock, list[str]]:
    """The chart compiled without the program's blocks (as a Python program may), the
    S7-SCL program loaded beside it, the calls prepared: the CPU and the problems."""
    clock = VirtualClock()
    cpu = Cpu(clock)
    cpu.mem.symbols = table()
    sfb.install(cpu)
    program().load(cpu)
    graph = GraphFB(compile_chart(parse_chart(text, "seq.s7g"), cpu.mem.symbols))
    install_all(cpu, [graph])
    return cpu, clock, prepare_calls(cpu, graph.cc.chart).problems


def errors(text: str, blocks: ProgramBlocks | None) -> list[tuple[str, int, int, str]]:
    found = validate(parse_chart(text, "seq.s7g"), table(), blocks=blocks)
    return [(d.code, d.loc.line, d.loc.col, d.message) for d in found if d.is_error]


@pytest.mark.parametrize(
    ("db", "value"),
    [("DB5", 11), ('"Recipe"', 11), ('"Other"', 22), ("db6", 22), ("W#16#6", 22)],
)
@pytest.mark.parametrize("in_step", [False, True])
def test_a_block_db_input_reads_the_db_the_chart_passes_by_number_or_symbol(
    db: str, value: int, in_step: bool
) -> None:
    text = chart_text(f"src := {db}, x := 3", in_step=in_step)
    assert errors(text, interfaces()) == []
    cpu, clock, problems = loaded(text)
    assert problems == []
    cpu.start()
    cpu.mem.periph_in[0] = 1
    for _ in range(3):
        cpu.scan()
        clock.advance(10)
    assert cpu.mode is CpuMode.RUN
    assert (cpu.mem.get("MW12"), cpu.mem.get("MW14")) == (value, 3)


def test_sim_with_blocks_and_symbols_passes_a_db_by_its_symbol(tmp_path: Path) -> None:
    (tmp_path / "seq.s7g").write_text(chart_text('src := "Other", x := 4'), encoding="utf-8")
    (tmp_path / "recipe.scl").write_text(SCL, encoding="utf-8")
    (tmp_path / "symbols.txt").write_text(TABLE, encoding="utf-8")
    session = ChartSession.load(
        tmp_path / "seq.s7g",
        tmp_path / "symbols.txt",
        VirtualClock(),
        blocks=[tmp_path / "recipe.scl"],
    )
    session.start()
    session.scan()
    assert session.cpu.mode is CpuMode.RUN and session.cpu.mem.get("MW12") == 22


WHAT_TO_PASS = "src is a BLOCK_DB: pass a DB (DB5, a DB's symbol) or its number as a WORD (W#16#5)"


@pytest.mark.parametrize(
    ("given", "kind"),
    [("n", "INT"), ('"Count"', "INT"), ("5", "INT"), ("M1.0", "BOOL"), ('"Lamp"', "BOOL")],
)
def test_a_block_db_input_given_no_db_and_no_word_is_told_what_to_pass(
    given: str, kind: str
) -> None:
    text = chart_text(f"src := {given}, x := 3")
    expected = [("E047", 8, 21, f"FC5: {WHAT_TO_PASS}, not {kind}")]
    assert errors(text, interfaces()) == expected  # s7graph check --blocks
    with pytest.raises(ChartError) as refused:  # sim and run: compiled with the blocks
        compile_chart(parse_chart(text, "seq.s7g"), table(), blocks=interfaces())
    assert [(d.code, d.message) for d in refused.value.diagnostics] == [("E047", expected[0][3])]


@pytest.mark.parametrize("given", ["w", "MW10", "W#16#5"])
def test_a_word_still_goes_to_a_block_db_input(given: str) -> None:
    assert errors(chart_text(f"src := {given}, x := 3"), interfaces()) == []


def test_a_db_to_an_input_that_is_no_block_db_is_refused_where_the_block_is_known() -> None:
    text = chart_text('src := DB5, x := "Recipe"')
    why = 'FC5: x is INT; "Recipe" is a DB, which only a BLOCK_DB input takes'
    assert errors(text, interfaces()) == [("E047", 8, 31, why)]
    with pytest.raises(ChartError, match="only a BLOCK_DB input takes"):  # sim and run
        compile_chart(parse_chart(text, "seq.s7g"), table(), blocks=interfaces())
    _, _, problems = loaded(text)  # compiled without the blocks: the CPU's block refuses
    assert problems == [f"seq.s7g:8:3: error: CALL FC 5: {why} (permanent before)"]


def test_a_downloads_calls_pass_dbs_of_the_cpus_symbol_table_to_block_db_inputs_only() -> None:
    """An online change plans the new chart's calls by their sites alone: a DB is ``DB6``
    or a DB symbol of the CPU's table."""
    cpu, _, _ = loaded(chart_text("src := DB5, x := 1"))
    for args, fits in [('src := "Other", x := 1', True), ('src := DB5, x := "Other"', False)]:
        plan = plan_calls(cpu, call_sites(parse_chart(chart_text(args), "new.s7g")))
        assert (plan.problems == []) is fits, plan.problems


def test_without_the_blocks_a_call_of_a_user_block_is_not_checked_but_a_db_is_a_db() -> None:
    assert errors(chart_text("src := DB5, x := DB6"), None) == []
    assert errors(chart_text("src := DB5, x := nope"), None)[0][0] == "E042"


def test_a_system_block_takes_no_db() -> None:
    text = chart_text("src := DB5, x := 1").replace(
        "CALL FC 5 (src := DB5, x := 1);", 'CALL "TON", DB 10 (IN := DB5, PT := T#1S);'
    )
    found = errors(text, None)
    assert found == [
        ("E046", 8, 28, "SFB4 TON: IN is BOOL; DB5 is a DB, which only a BLOCK_DB input takes")
    ]


@pytest.mark.parametrize(
    ("given", "code", "why"),
    [
        ("DB0", "E041", "DB0: a DB is numbered 1..65535"),
        ("DB65536", "E041", "DB65536: a DB is numbered 1..65535"),
        ("W#16#0", "E047", "FC5: src is a BLOCK_DB: W#16#0 is no DB (numbered 1..65535)"),
    ],
)
def test_a_db_numbered_outside_1_to_65535_is_an_error_at_its_place(
    given: str, code: str, why: str
) -> None:
    assert errors(chart_text(f"src := {given}, x := 3"), interfaces()) == [(code, 8, 21, why)]


@pytest.mark.parametrize(
    ("given", "owner"),
    [("DB1", "FB1 (this chart)"), ("DB10", "SFB4"), ("DB12", "FB17")],
)
def test_an_instance_db_passed_to_a_block_db_input_is_refused_it_has_no_bytes(
    given: str, owner: str
) -> None:
    text = chart_text(f"src := {given}, x := 3").replace(
        "END_PERMANENT", '  CALL "TON", DB 10 (IN := I0.1, PT := T#1S);\nEND_PERMANENT'
    )
    why = f"{given} is the instance DB of {owner}; it holds its variables by name, not the bytes"
    ((code, line, col, message),) = errors(text, interfaces())
    assert (code, line, col) == ("E041", 8, 21) and message.startswith(why)


def test_an_instance_db_of_the_cpu_is_refused_at_load() -> None:
    """Compiled without the program's blocks, the chart does not know DB12 is FB17's."""
    _, _, problems = loaded(chart_text("src := DB12, x := 3"))
    assert problems == [
        "seq.s7g:8:3: error: CALL FC 5: DB12: DB12 is the instance DB of FB17; it holds its "
        "variables by name, not the bytes a BLOCK_DB input reaches (permanent before)"
    ]
