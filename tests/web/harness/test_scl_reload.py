"""Changed S7-SCL sources downloaded into a running CPU between two scans
(``ChartSession.reload_blocks``, ``web/harness/scl_reload.py``): the chart runs on where it
was, the instance DBs of a changed FB keep their values by name and type, a global DB keeps
its bytes while its structure stays, and the new OBs run beside the chart."""

from __future__ import annotations

from pathlib import Path

from s7graph.engine.clock import VirtualClock
from s7graph.web.harness.scl import SclSources, compile_sources
from s7graph.web.harness.session import ChartSession, compile_text
from tests.web.helpers import CALLS_FB17

BLOCKS = """
FUNCTION_BLOCK FB17
VAR_INPUT go : BOOL; END_VAR
VAR n : INT; hist : ARRAY[1..3] OF INT; s : STRUCT a : INT; END_STRUCT; END_VAR
  IF go THEN n := n + 1; hist[1] := n; s.a := n; END_IF;
END_FUNCTION_BLOCK
DATA_BLOCK DB20
STRUCT total : DINT; END_STRUCT
BEGIN
END_DATA_BLOCK
DATA_BLOCK DB21
STRUCT x : INT; END_STRUCT
BEGIN x := 3;
END_DATA_BLOCK
ORGANIZATION_BLOCK OB1
  DB20.total := DB20.total + 1;
  DB21.x := DB21.x + 1;
END_ORGANIZATION_BLOCK
"""
CHART = CALLS_FB17


def _sources(tmp_path: Path, text: str, name: str) -> SclSources:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return compile_sources([path])


def _scans(session: ChartSession, n: int) -> None:
    clock = session.clock
    assert isinstance(clock, VirtualClock)
    for _ in range(n):
        session.scan()
        clock.advance(10)


def test_a_changed_fb_keeps_its_instances_values_by_name_and_type(tmp_path: Path) -> None:
    old = _sources(tmp_path, BLOCKS, "a.scl")
    cc, table = compile_text(CHART, "seq.s7g")
    session = ChartSession(cc, table, VirtualClock(), blocks=[old])
    session.start()
    _scans(session, 5)
    get = session.get
    assert (get("DB10.n"), get("DB10.hist"), get("DB20.total"), get("DB21.x")) == (
        6,  # S1's call in the startup too
        [6, 0, 0],
        5,
        8,
    )
    changed = BLOCKS.replace("ARRAY[1..3] OF INT", "ARRAY[1..4] OF INT; more : REAL")
    changed = changed.replace("x : INT; END_STRUCT", "x : DINT; END_STRUCT")
    changed = changed.replace("DB20.total + 1", "DB20.total + 10")
    new = _sources(tmp_path, changed, "b.scl")
    notes = session.reload_blocks(new)
    assert notes == [
        "DB10 FB17 'FB17': interface changed; variables kept by name (3)",
        "DB10 FB17 'FB17': of another type, at their initial values: hist",
        "DB10 FB17 'FB17': new, at their initial values: more",
        "DB21: its structure changed; at its new initial values",
    ]
    assert get("DB10.n") == 6 and get("DB10.s") == {"a": 6} and get("DB10.hist") == [0] * 4
    assert get("DB20.total") == 5 and get("DB21.x") == 3
    _scans(session, 1)
    assert session.cc.step_label(next(iter(session.graph.state.active))) == "S1"
    assert get("DB10.n") == 7 and get("DB10.hist") == [7, 0, 0, 0]  # the new FB runs
    assert get("DB20.total") == 15 and get("DB21.x") == 4  # and the new OB1


def test_an_unchanged_fb_keeps_its_instance_whole(tmp_path: Path) -> None:
    old = _sources(tmp_path, BLOCKS, "a.scl")
    cc, table = compile_text(CHART, "seq.s7g")
    session = ChartSession(cc, table, VirtualClock(), blocks=[old])
    session.start()
    _scans(session, 3)
    new = _sources(tmp_path, BLOCKS.replace("DB21.x + 1", "DB21.x + 2"), "b.scl")
    assert session.reload_blocks(new) == []
    assert session.get("DB10.n") == 4 and session.get("DB21.x") == 6
    _scans(session, 1)
    assert session.get("DB10.n") == 5 and session.get("DB21.x") == 8
