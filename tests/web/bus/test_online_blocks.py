"""The S7-SCL blocks of an online change at the scan boundary (``web/bus/online_blocks.py``):
random changes of a running SCL FB — variables added, removed, retyped, its code changed —
end as a fresh CPU loaded from the new source with the kept variables set would be, or are
refused with a reason and leave the old program running; what a preview says they carry
over is what the download's notes say; the source files a download may bring are those the
CPU runs."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from s7graph.engine.clock import VirtualClock
from s7graph.web.bus.online_blocks import BlockFiles, BlocksRefused, swap_blocks
from s7graph.web.harness.scl import compile_texts, scl_of
from s7graph.web.harness.scl_reload import carry_notes
from s7graph.web.harness.session import ChartSession, compile_text
from tests.web.helpers import CALLS_FB17

CHART = CALLS_FB17

TYPES = ("INT", "DINT", "REAL", "BOOL", "BYTE", "WORD", "ARRAY[1..3] OF INT", "ARRAY[1..4] OF INT")
INITIAL = {"INT": "7", "DINT": "70000", "REAL": "1.5", "BOOL": "TRUE", "BYTE": "16#0F"}
INITIAL |= {"WORD": "16#00F0"}
# the type changes whose values carry over (the test's own table: every value survives)
CARRIES = {("INT", "DINT"): int, ("INT", "REAL"): float, ("BOOL", "BYTE"): int}
CARRIES |= {("BOOL", "WORD"): int, ("BYTE", "WORD"): int}
NAMES = ("a", "b", "c", "d", "e")


@dataclass(frozen=True)
class Var:
    name: str
    type: str
    step: int  # what the code adds (or flips with) each call
    init: bool  # declared with an initial value


def _code(v: Var) -> str:
    t, n, k = v.type, v.name, v.step
    if t in ("INT", "DINT"):
        return f"{n} := {n} + {k};"
    if t == "REAL":
        return f"{n} := {n} + {k}.25;"
    if t.startswith("ARRAY"):
        return f"{n}[1] := {n}[1] + {k}; {n}[3] := {n}[1];"
    return f"IF {k} > 2 THEN {n} := NOT {n}; END_IF;"  # BOOL, BYTE, WORD


def source(vs: list[Var]) -> str:
    decls = []
    for v in vs:
        init = f" := {INITIAL[v.type]}" if v.init and v.type in INITIAL else ""
        decls.append(f"  {v.name} : {v.type}{init};")
    body = "\n".join(f"    {_code(v)}" for v in vs)
    return (
        "FUNCTION_BLOCK FB17\nVAR_INPUT go : BOOL; END_VAR\nVAR\n"
        + "\n".join(decls)
        + f"\nEND_VAR\n  IF go THEN\n{body}\n  END_IF;\nEND_FUNCTION_BLOCK\n"
    )


def session_of(vs: list[Var], *, start: bool = True) -> ChartSession:
    """The chart calling FB17 of ``vs`` in a CPU (``start``: started, which calls it once)."""
    cc, table = compile_text(CHART, "seq.s7g")
    sources = compile_texts([("b.scl", source(vs))], table)
    session = ChartSession(cc, table, VirtualClock(), blocks=[sources])
    if start:
        session.start()
    return session


def scans(session: ChartSession, n: int) -> None:
    clock = session.clock
    assert isinstance(clock, VirtualClock)
    for _ in range(n):
        session.scan()
        clock.advance(10)


def values(session: ChartSession) -> dict[str, object]:
    return session.cpu.instance_dbs[10].snapshot()


var = st.builds(
    Var, st.sampled_from(NAMES), st.sampled_from(TYPES), st.integers(1, 5), st.booleans()
)
fb_vars = st.lists(var, min_size=1, max_size=4, unique_by=lambda v: v.name)


@st.composite
def changes(draw: st.DrawFn) -> tuple[list[Var], list[Var]]:
    """An FB and a changed one: variables removed, added, retyped, their code changed."""
    old = draw(fb_vars)
    new: list[Var] = []
    for v in old:
        what = draw(st.sampled_from(("keep", "remove", "retype", "code")))
        if what == "keep":
            new.append(v)
        elif what == "retype":
            new.append(Var(v.name, draw(st.sampled_from(TYPES)), v.step, v.init))
        elif what == "code":
            new.append(Var(v.name, v.type, draw(st.integers(1, 5)), v.init))
    names = {v.name for v in old}
    for v in draw(st.lists(var, max_size=2, unique_by=lambda v: v.name)):
        if v.name not in names:
            new.append(v)
            names.add(v.name)
    if not new:
        new.append(Var("z", "INT", 1, True))
    return old, draw(st.permutations(new))


@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(changes(), st.integers(1, 6), st.integers(1, 4))
def test_a_changed_running_fb_ends_as_a_fresh_one_with_the_kept_values_or_is_refused(
    change: tuple[list[Var], list[Var]], before: int, after: int
) -> None:
    old, new = change
    running = session_of(old)
    scans(running, before)
    was = values(running)
    program = dict(running.cpu.blocks)
    types = {v.name: v.type for v in new}
    blocked = [
        v.name
        for v in old
        if v.name in types and v.type != types[v.name] and (v.type, types[v.name]) not in CARRIES
    ]
    new_sources = compile_texts([("b.scl", source(new))], running.symbols)
    if blocked:
        with pytest.raises(BlocksRefused) as refused:
            swap_blocks(running, new_sources)
        assert "DB10" in str(refused.value)
        assert all(f"{n}: " in str(refused.value) for n in blocked)
        assert running.cpu.blocks == program and values(running) == was  # nothing changed
        twin = session_of(old)
        scans(twin, before + after)
        scans(running, after)
        assert values(running) == values(twin)  # the old FB runs on
        return
    said = carry_notes(running.cpu, scl_of(running.blocks), new_sources)  # the preview's
    assert running.cpu.blocks == program and values(running) == was  # it changes nothing
    notes, _ = swap_blocks(running, new_sources)
    assert notes == said  # the download's reply says what its preview said
    fresh = session_of(new)  # set as loaded, the kept variables as they were
    kept = values(session_of(new, start=False))
    kept["go"] = was["go"]  # the input, kept as every variable of the same type
    for v in old:
        if v.name in types:
            convert = CARRIES.get((v.type, types[v.name]), lambda x: x)
            kept[v.name] = convert(was[v.name])
    fresh.cpu.instance_dbs[10].restore(kept)
    dropped = sorted(v.name for v in old if v.name not in types)
    assert any(n in line for line in notes for n in dropped) or not dropped
    assert values(running) == values(fresh)
    scans(running, after)
    scans(fresh, after)
    assert values(running) == values(fresh)


def test_a_refused_change_names_the_db_the_variable_and_both_types() -> None:
    old = [Var("n", "INT", 1, False), Var("h", "ARRAY[1..3] OF INT", 1, False)]
    running = session_of(old)
    scans(running, 3)
    new = [Var("n", "BOOL", 1, False), Var("h", "ARRAY[1..4] OF INT", 1, False)]
    with pytest.raises(BlocksRefused) as refused:
        swap_blocks(running, compile_texts([("b.scl", source(new))], running.symbols))
    reason = str(refused.value)
    assert "DB10 (FB17): n: INT → BOOL" in reason
    assert "h: ARRAY[1..3] OF INT → ARRAY[1..4] OF INT" in reason
    assert "cannot be carried over" in reason and "rename" in reason
    assert running.get("DB10.n") == 4  # the old FB's value (the startup called it too)
    scans(running, 1)
    assert running.get("DB10.n") == 5  # and it runs on


def test_an_instance_db_the_new_sources_give_another_fb_is_refused() -> None:
    running = session_of([Var("n", "INT", 1, False)])
    other = source([Var("n", "INT", 1, False)]) + (
        "FUNCTION_BLOCK FB18\nVAR m : INT; END_VAR\n  m := m + 1;\nEND_FUNCTION_BLOCK\n"
        "ORGANIZATION_BLOCK OB1\n  FB18.DB10();\nEND_ORGANIZATION_BLOCK\n"
    )
    with pytest.raises(BlocksRefused, match="DB10 is the instance DB of FB17 in the CPU"):
        swap_blocks(running, compile_texts([("b.scl", other)], running.symbols))


def test_the_way_back_puts_the_old_program_and_values_back() -> None:
    running = session_of([Var("n", "INT", 2, False)])
    scans(running, 2)
    was, program = values(running), dict(running.cpu.blocks)
    notes, back = swap_blocks(
        running,
        compile_texts([("b.scl", source([Var("m", "INT", 1, False)]))], running.symbols),
    )
    assert notes == [
        "DB10 FB17 'FB17': interface changed; variables kept by name (1)",
        "DB10 FB17 'FB17': dropped (no longer declared): n",
        "DB10 FB17 'FB17': new, at their initial values: m",
    ]
    back()
    assert running.cpu.blocks == program and values(running) == was
    scans(running, 1)
    assert running.get("DB10.n") == was["n"] + 2  # type: ignore[operator]


def test_a_preview_notes_the_variables_kept_dropped_and_new_and_a_restructured_db() -> None:
    db = "DATA_BLOCK DB20\nSTRUCT {} END_STRUCT\nBEGIN\nEND_DATA_BLOCK\n"
    old = source([Var("n", "INT", 2, False), Var("gone", "INT", 1, False)])
    cc, table = compile_text(CHART, "seq.s7g")
    was = compile_texts([("b.scl", old + db.format("w : INT;"))], table)
    running = ChartSession(cc, table, VirtualClock(), blocks=[was])
    running.start()
    scans(running, 2)
    before = values(running)
    new = source([Var("n", "DINT", 2, False), Var("fresh", "INT", 1, True)])
    changed = compile_texts([("b.scl", new + db.format("w : INT; v : INT;"))], table)
    said = carry_notes(running.cpu, was, changed)
    assert said == [
        "DB10 FB17 'FB17': interface changed; variables kept by name (2)",
        "DB10 FB17 'FB17': dropped (no longer declared): gone",
        "DB10 FB17 'FB17': new, at their initial values: fresh",
        "DB20: its structure changed; at its new initial values",
    ]
    assert values(running) == before and running.cpu.block("FB17").interface[1].type == "INT"
    same = compile_texts([("b.scl", old.replace("+ 2", "+ 3") + db.format("w : INT;"))], table)
    assert carry_notes(running.cpu, was, same) == []  # the code only: every value stays
    notes, _ = swap_blocks(running, changed)
    assert notes == said


def test_a_download_brings_only_the_sources_the_cpu_runs(tmp_path: Path) -> None:
    a, b = tmp_path / "a.scl", tmp_path / "b.scl"
    a.write_text("A", encoding="utf-8")
    b.write_text("B", encoding="utf-8")
    files = BlockFiles([a, b])
    assert files.merged({"b.scl": "B2"}) == [(str(a), "A"), (str(b), "B2")]
    assert files.changes({"a.scl": "A", "b.scl": "B2"}) == {"b.scl": "B2"}
    with pytest.raises(
        BlocksRefused, match=r"runs no S7-SCL source c\.scl: it runs a\.scl, b\.scl"
    ):
        files.merged({"c.scl": "C"})
    with pytest.raises(BlocksRefused, match="run without --blocks"):
        BlockFiles([]).merged({"c.scl": "C"})
    written = files.write({"b.scl": "B2"})
    assert b.read_text(encoding="utf-8") == "B2"
    assert files.restore(written) == "" and b.read_text(encoding="utf-8") == "B"
