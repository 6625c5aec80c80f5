"""docs/cli.md, "s7graph sim": the black-box contract of ``s7graph sim`` — the details not pinned in
``test_sim_contract.py``. Driven through the command line entry point ``web.cli.main``."""

from __future__ import annotations

from pathlib import Path

import pytest

from s7graph.web.cli import main
from tests.sequencer.helpers import read_trace, write_sim_inputs

CHART = """FUNCTION_BLOCK "Sim"
  PARAMETERS := STANDARD;
VAR x : INT := 30000; END_VAR
SYMBOLS "Go" : I0.0 : BOOL; "Lamp" : Q0.0 : BOOL; END_SYMBOLS
SEQUENCE 1 "Main"
  INITIAL_STEP S10 "Ten": END_STEP
  STEP S2 "Two": N "Lamp"; END_STEP
  STEP S3 "Three": END_STEP
  TRANSITION T1 FROM S10 TO (S2, S3) := "Go";
  TRANSITION T2 FROM (S2, S3) TO STOP := I0.1;
END_SEQUENCE
SEQUENCE 2 "Side"
  INITIAL_STEP S1 "One": END_STEP
  STEP S4 "Four": N x := x + 1000; END_STEP
  TRANSITION T11 FROM S1 TO S4 := I0.2;
END_SEQUENCE
END_FUNCTION_BLOCK
"""


def sim(
    tmp_path: Path, stim: list[dict], *, cycles: int = 8, watch: str = "Lamp", chart: str = CHART
) -> tuple[int, list[dict]]:
    c, s, out = write_sim_inputs(tmp_path, chart, stim)
    argv = [
        "sim",
        str(c),
        "--stimulus",
        str(s),
        "--cycle-ms",
        "10",
        "--cycles",
        str(cycles),
        "--trace",
        str(out),
    ]
    if watch:
        argv += ["--watch", watch]
    try:
        rc = main(argv)
    except SystemExit as exc:  # a Typer app may exit instead of returning
        rc = int(exc.code or 0)
    return rc, read_trace(out)


def test_active_is_sorted_by_step_number_not_by_name(tmp_path: Path) -> None:
    """docs/cli.md, "s7graph sim": `active` sorted by step number (S2 before S10)."""
    rc, lines = sim(tmp_path, [{"at_ms": 0, "set": {"Go": True}}], cycles=3)
    assert rc == 0
    assert lines[0]["active"] == ["S1", "S2", "S3"]  # T1 holds already in cycle 0
    rc, lines = sim(tmp_path, [], cycles=2)
    assert lines[-1]["active"] == ["S1", "S10"]


def test_a_stimulus_between_two_cycles_is_applied_before_the_next_cycle(tmp_path: Path) -> None:
    """docs/cli.md, "s7graph sim": each cycle applies the stimuli with at_ms <= now, then calls the
    FB."""
    rc, lines = sim(tmp_path, [{"at_ms": 15, "set": {"Go": True}}], cycles=4)
    assert rc == 0
    assert [line["active"] for line in lines[:3]] == [
        ["S1", "S10"],
        ["S1", "S10"],
        ["S1", "S2", "S3"],
    ]
    assert lines[2]["t_ms"] == 20 and lines[2]["values"] == {"Lamp": True}


def test_a_stimulus_at_exactly_now_acts_in_that_cycle(tmp_path: Path) -> None:
    """docs/cli.md, "s7graph sim": at_ms <= now — a stimulus at 30 ms acts in the cycle with t_ms
    30."""
    rc, lines = sim(tmp_path, [{"at_ms": 30, "set": {"Go": True}}], cycles=5)
    assert rc == 0
    switched = [line["t_ms"] for line in lines if line["events"]]
    assert switched == [30]
    assert lines[3]["events"] == [["S10", "S2"], ["S10", "S3"]]


def test_values_stay_until_set_again(tmp_path: Path) -> None:
    """docs/cli.md, "s7graph sim": stimulus values stay until set again — I0.1 set once at 40 ms is
    still 1."""
    stim = [
        {"at_ms": 0, "set": {"Go": True}},
        {"at_ms": 10, "set": {"Go": False}},
        {"at_ms": 40, "set": {"I0.1": True}},
    ]
    rc, lines = sim(tmp_path, stim, cycles=8, watch="I0.1,Go")
    assert rc == 0
    assert [line["values"]["I0.1"] for line in lines] == [False] * 4 + [True] * 4
    assert [line["values"]["Go"] for line in lines] == [True] + [False] * 7
    assert lines[4]["events"] == [["S2", "STOP"], ["S3", "STOP"]]
    assert lines[4]["active"] == ["S1"]


def test_int_overflow_in_an_assignment_does_not_stop_the_simulation(tmp_path: Path) -> None:
    """docs/cli.md, "s7graph sim", and semantics.md, "Actions": an INT overflow sets the overflow
    status; sim runs to the end."""
    rc, lines = sim(tmp_path, [{"at_ms": 0, "set": {"I0.2": True}}], cycles=10, watch="x")
    assert rc == 0 and len(lines) == 10
    assert all(-32768 <= line["values"]["x"] <= 32767 for line in lines)
    assert lines[-1]["active"] == ["S4", "S10"]


def test_a_pin_outside_a_minimum_parameter_set_is_refused(tmp_path: Path, capsys) -> None:
    """docs/cli.md, "s7graph sim"; docs/semantics.md, "FB pins": FB input pins of the chart's
    parameter set only (MINIMUM: INIT_SQ)."""
    chart = CHART.replace("STANDARD", "MINIMUM")
    rc, _ = sim(tmp_path, [{"at_ms": 0, "set": {"SW_MAN": True}}], chart=chart)
    assert rc == 2 and "SW_MAN" in capsys.readouterr().err
    rc, lines = sim(tmp_path, [{"at_ms": 0, "set": {"INIT_SQ": True}}], chart=chart, cycles=2)
    assert rc == 0 and len(lines) == 2


def test_a_syntax_error_exits_2_with_its_place_on_stderr(tmp_path: Path, capsys) -> None:
    """docs/cli.md, "s7graph sim": a chart that does not compile exits 2, diagnostics on stderr
    (`file:line:column`), no trace."""
    rc, lines = sim(tmp_path, [], chart=CHART.replace('N "Lamp";', 'N "Lamp"'))
    captured = capsys.readouterr()
    assert rc == 2 and lines == []
    assert "c.s7g:7:26:" in captured.err
    assert captured.out.strip() == ""


@pytest.mark.parametrize("name", ["S2.X", "T1.TT", "AUTO_ON", "Lamp", "Q0.0", "x"])
def test_every_watched_name_has_a_value_in_every_line(tmp_path: Path, name: str) -> None:
    """docs/cli.md, "s7graph sim": `values` for every watched name (addresses, symbols, pins,
    variables, step and transition operands)."""
    rc, lines = sim(tmp_path, [], cycles=3, watch=name)
    assert rc == 0 and all(set(line["values"]) == {name} for line in lines)


def test_stimuli_written_out_of_time_order_are_still_applied_by_their_time(
    tmp_path: Path,
) -> None:
    """docs/cli.md, "s7graph sim": every stimulus with at_ms <= now is applied, whatever its
    line."""
    stim = [{"at_ms": 50, "set": {"I0.1": True}}, {"at_ms": 10, "set": {"Go": True}}]
    rc, lines = sim(tmp_path, stim, cycles=8)
    assert rc == 0
    assert lines[1]["active"] == ["S1", "S2", "S3"]
    assert lines[5]["active"] == ["S1"]
