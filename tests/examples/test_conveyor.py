"""The two conveyor belts of STEP7 comprehensive guide vol. 2, section 14.6, example 1, run through
``s7graph sim`` (docs/cli.md, "s7graph sim") with the example's stimulus (the operator's buttons)
and plant (material on belt B)."""

from __future__ import annotations

import itertools
from pathlib import Path

import pytest

from tests.examples.helpers import EXAMPLES, edges, sim_example, stimulus_file

EXAMPLE = EXAMPLES / "conveyor"
WATCH = ("Belt_A", "Belt_B", "Spill", "Belt_B_empty", "Emergency_stop", "ERR_FLT")


def run_sim(
    tmp_path: Path, *, stimulus: Path = EXAMPLE / "stimulus.jsonl", cycles: int = 4500
) -> list[dict]:
    """Run the example's ``s7graph sim`` command (10 ms cycle); return the trace records."""
    return sim_example(tmp_path, "conveyor", watch=WATCH, stimulus=stimulus, cycles=cycles)


@pytest.fixture(scope="module")
def records(tmp_path_factory: pytest.TempPathFactory) -> list[dict]:
    """The trace of the example's own command (stimulus and plant as shipped)."""
    return run_sim(tmp_path_factory.mktemp("trace"))


def value_at(records: list[dict], name: str, t_ms: int) -> object:
    return next(rec["values"][name] for rec in records if rec["t_ms"] == t_ms)


def test_start_runs_belt_b_at_once_and_belt_a_five_seconds_later(records: list[dict]) -> None:
    b_on, a_on = edges(records, "Belt_B")[0], edges(records, "Belt_A")[0]
    assert b_on == 500  # Start pressed at 500 ms acts in that cycle (docs/cli.md, "s7graph sim")
    assert 5000 <= a_on - b_on <= 5010


def test_stop_halts_belt_a_at_once_and_belt_b_seven_seconds_later(records: list[dict]) -> None:
    a_off, b_off = edges(records, "Belt_A", False)[0], edges(records, "Belt_B", False)[0]
    assert a_off == 12000  # Stop pressed at 12 s acts in that cycle (docs/cli.md, "s7graph sim")
    assert 7000 <= b_off - a_off <= 7010
    # the run-on carried everything off belt B, and belt A never fed a standing belt
    assert value_at(records, "Belt_B_empty", b_off + 100) is True
    assert not any(rec["values"]["Spill"] for rec in records)


def test_emergency_stops_both_belts_at_once_while_belt_a_waits_to_start(
    records: list[dict],
) -> None:
    assert 22000 in edges(records, "Belt_B")  # Start at 22 s
    assert 24000 in edges(records, "Belt_B", False)  # Emergency at 24 s
    window = [rec for rec in records if 22000 <= rec["t_ms"] < 26000]
    assert not any(rec["values"]["Belt_A"] for rec in window)  # the 5 s delay was cut
    assert next(rec["active"] for rec in records if rec["t_ms"] == 24010) == ["S6"]


def test_emergency_stops_belt_b_at_once_while_it_runs_on(records: list[dict]) -> None:
    assert edges(records, "Belt_A", False)[-1] == 38000  # Stop at 38 s
    assert edges(records, "Belt_B", False)[-1] == 40000  # Emergency at 40 s, not at 45 s
    assert value_at(records, "Belt_B_empty", 40100) is False  # material left on belt B
    assert records[-1]["active"] == ["S1"]


def test_three_alternative_paths_leave_the_initial_step(records: list[dict]) -> None:
    after_s1 = {
        tuple(rec["active"])
        for prev, rec in itertools.pairwise(records)
        if prev["active"] == ["S1"] and rec["active"] != ["S1"]
    }
    assert after_s1 == {("S2",), ("S4",), ("S6",)}


def test_emergency_wins_over_start_pressed_in_the_same_cycle(tmp_path: Path) -> None:
    stim = stimulus_file(
        tmp_path,
        {"at_ms": 500, "set": {"Start_button": True, "Emergency_stop": True}},
        {"at_ms": 1000, "set": {"Start_button": False, "Emergency_stop": False}},
    )
    records = run_sim(tmp_path, stimulus=stim, cycles=200)
    assert not any(rec["values"]["Belt_B"] or rec["values"]["Belt_A"] for rec in records)
    assert ["S2"] not in [rec["active"] for rec in records]
    assert ["S6"] in [rec["active"] for rec in records]
