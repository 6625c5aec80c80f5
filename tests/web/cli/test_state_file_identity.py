"""``s7graph run`` of a chart and an S7-SCL program of one name in one folder — the oven
example's ``oven.s7g`` and ``oven.scl`` — as real processes: each keeps a state file of
its own by default; the other's file given with ``--state`` is refused in one line naming
both, exit 2, byte for byte as it was; an older shared file stays the program's that wrote
it and the chart passes over it, saying so; a changed chart still warm-restarts with notes,
and so does a renamed one given its old file; run without it, the renamed chart starts
fresh naming its old file (docs/state-file.md, "Whose state it is")."""

from __future__ import annotations

import shutil
import sqlite3
import subprocess
import sys
from pathlib import Path

import pytest

from tests.paths import ROOT

OVEN = ROOT / "examples" / "oven"


@pytest.fixture
def oven(tmp_path: Path) -> Path:
    """The oven pair and its symbols in a folder of their own."""
    for name in ("oven.s7g", "oven.scl", "symbols.txt"):
        shutil.copy(OVEN / name, tmp_path / name)
    return tmp_path


def _run(folder: Path, program: str, *args: str) -> subprocess.CompletedProcess[str]:
    cmd = [sys.executable, "-m", "s7graph", "run", program, "--symbols", "symbols.txt"]
    return subprocess.run(
        [*cmd, "--duration-s", "0.3", "--rt-priority", "0", *args],
        cwd=folder,
        capture_output=True,
        text=True,
        timeout=120,
    )


def _files(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir()) if "sqlite" in p.name}


def test_a_chart_and_an_scl_program_of_one_name_keep_state_files_of_their_own(
    oven: Path,
) -> None:
    for program, state in (
        ("oven.scl", "oven.scl.state.sqlite"),
        ("oven.s7g", "oven.state.sqlite"),
    ):
        first = _run(oven, program)
        assert first.returncode == 0, first.stderr
        assert f"fresh start, state in {state}" in first.stderr
    for program, state in (
        ("oven.s7g", "oven.state.sqlite"),
        ("oven.scl", "oven.scl.state.sqlite"),
    ):
        again = _run(oven, program)
        assert again.returncode == 0, again.stderr
        assert f"warm restart from {state}" in again.stderr
        assert "note:" not in again.stderr  # its own state: nothing carried over, nothing new


def test_the_other_programs_state_file_is_refused_in_one_line_and_left_as_it_was(
    oven: Path,
) -> None:
    assert _run(oven, "oven.scl").returncode == 0
    before = _files(oven)
    refused = _run(oven, "oven.s7g", "--state", "oven.scl.state.sqlite")
    assert refused.returncode == 2
    assert refused.stderr.splitlines() == [
        "s7graph: error: oven.scl.state.sqlite: the state of another program: the S7-SCL "
        "program oven.scl's, not the chart oven.s7g's; run oven.s7g with a state file of its "
        "own (--state FILE), or start anew with --fresh (keeps this file, the other "
        "program's state, as oven.scl.state.sqlite.old-N)"
    ]
    assert _files(oven) == before
    back = _run(oven, "oven.scl")
    assert "warm restart from oven.scl.state.sqlite" in back.stderr, back.stderr


def test_an_older_shared_state_file_stays_the_programs_and_the_chart_passes_over_it(
    oven: Path,
) -> None:
    """The user's case: ``oven.state.sqlite`` written by ``run oven.scl`` before runs
    recorded their program. Before, ``run oven.s7g`` warm-restarted from it."""
    assert _run(oven, "oven.scl", "--state", "oven.state.sqlite").returncode == 0
    with sqlite3.connect(oven / "oven.state.sqlite") as con:
        con.execute("DELETE FROM meta WHERE key LIKE 'program_%'")  # as an older run left it
    con.close()
    before = _files(oven)
    chart = _run(oven, "oven.s7g")
    assert chart.returncode == 0, chart.stderr
    assert chart.stderr.splitlines()[0] == (
        "s7graph: note: oven.state.sqlite is passed over (written by an s7graph that did not "
        "record its program, and it holds no chart's sequencer (no GRAPH FB's instance DB): "
        "another program's (an S7-SCL or Python program of the same name?), not the chart "
        "oven.s7g's); the state of the chart oven.s7g is kept in oven.s7g.state.sqlite"
    )
    assert "fresh start, state in oven.s7g.state.sqlite" in chart.stderr
    assert "no state saved" not in chart.stderr
    assert _files(oven)["oven.state.sqlite"] == before["oven.state.sqlite"]
    program = _run(oven, "oven.scl")
    assert program.returncode == 0, program.stderr
    assert "warm restart from oven.state.sqlite" in program.stderr
    again = _run(oven, "oven.s7g")
    assert "warm restart from oven.s7g.state.sqlite" in again.stderr, again.stderr


def test_a_changed_chart_still_warm_restarts_from_its_file_with_notes(oven: Path) -> None:
    assert _run(oven, "oven.s7g").returncode == 0
    chart = oven / "oven.s7g"
    text = chart.read_text(encoding="utf-8")
    chart.write_text(
        text.replace("hold_time : TIME := T#5M;", "hold_time : TIME := T#5M;\n  extra : INT := 3;"),
        encoding="utf-8",
    )
    changed = _run(oven, "oven.s7g")
    assert changed.returncode == 0, changed.stderr
    assert "s7graph: note: DB1 FB1 'Oven_seq': chart changed" in changed.stderr
    assert "warm restart from oven.state.sqlite" in changed.stderr


def test_a_renamed_chart_given_its_old_state_file_warm_restarts_from_it_saying_so(
    oven: Path,
) -> None:
    """The user's case: ``oven.s7g`` renamed ``oven_v2.s7g`` between runs, its state kept
    with ``--state oven.state.sqlite`` (before: refused as another program's)."""
    first = _run(oven, "oven.s7g")
    assert first.returncode == 0, first.stderr
    (oven / "oven.s7g").rename(oven / "oven_v2.s7g")
    renamed = _run(oven, "oven_v2.s7g", "--state", "oven.state.sqlite")
    assert renamed.returncode == 0, renamed.stderr
    assert "warm restart from oven.state.sqlite" in renamed.stderr
    assert (
        "s7graph: note: the file was the state of the chart oven.s7g and now records the "
        "chart oven_v2.s7g (a renamed source: its instance DBs are this program's)"
    ) in renamed.stderr.splitlines()
    with sqlite3.connect(oven / "oven.state.sqlite") as con:
        source = con.execute("SELECT value FROM meta WHERE key='program_source'").fetchone()
    con.close()
    assert source == ("oven_v2.s7g",)
    again = _run(oven, "oven_v2.s7g", "--state", "oven.state.sqlite")
    assert "warm restart from oven.state.sqlite" in again.stderr, again.stderr
    assert "note:" not in again.stderr


def test_a_renamed_chart_run_without_state_starts_fresh_naming_its_old_file_beside_it(
    oven: Path,
) -> None:
    """``oven.s7g`` renamed ``oven2.s7g`` and run as before, without ``--state``: before, a
    fresh start in ``oven2.state.sqlite`` without a word, ``oven.state.sqlite`` beside it
    holding the plant's position. Now a note names it and ``--state`` (on stderr and in the
    new file's diagnostic buffer); it is not taken, and stays byte for byte as it was."""
    assert _run(oven, "oven.s7g").returncode == 0
    assert _run(oven, "oven.scl").returncode == 0  # another program's file beside: not named
    (oven / "oven.s7g").rename(oven / "oven2.s7g")
    before = _files(oven)
    renamed = _run(oven, "oven2.s7g")
    assert renamed.returncode == 0, renamed.stderr
    note = (
        "oven.state.sqlite beside it holds the state of the chart oven.s7g, whose instance "
        "DBs are the chart oven2.s7g's (a renamed source?): not taken without --state; to "
        "carry it over, run oven2.s7g with --state oven.state.sqlite"
    )
    assert renamed.stderr.splitlines()[0] == f"s7graph: note: {note}"
    assert "fresh start, state in oven2.state.sqlite" in renamed.stderr
    assert {k: v for k, v in _files(oven).items() if k in before} == before
    with sqlite3.connect(oven / "oven2.state.sqlite") as con:
        rows = con.execute("SELECT message FROM diagnostics WHERE event_id=?", (0x5F08,))
        assert rows.fetchall() == [(note,)]
    con.close()
