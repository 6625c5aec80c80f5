"""The automatic drill of STEP7 comprehensive guide vol. 2, section 14.6, example 2, run through
``s7graph sim`` (docs/cli.md, "s7graph sim") with its plant (``examples/drill/plant.py``) and
stimulus."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.examples import helpers
from tests.examples.helpers import EXAMPLES, entered, path_of, sim_example, stimulus_file

EXAMPLE = EXAMPLES / "drill"
WATCH = (
    "Dr_mot_on",
    "Cool_pump_on",
    "Lower_drill",
    "Raise_drill",
    "Clamp_workp",
    "Cl_press_ok",
    "Drill_down",
    "Drill_up",
    "ERR_FLT",
    "S_NO",
)


def run_sim(
    tmp_path: Path,
    *,
    plant: Path = EXAMPLE / "plant.py",
    stimulus: Path = EXAMPLE / "stimulus.jsonl",
    cycles: int = 800,
    cycle_ms: int = 10,
) -> list[dict]:
    """Run the example's ``s7graph sim`` command; return the trace records."""
    return sim_example(
        tmp_path,
        "drill",
        watch=WATCH,
        plant=plant,
        stimulus=stimulus,
        cycles=cycles,
        cycle_ms=cycle_ms,
    )


@pytest.fixture(scope="module")
def records(tmp_path_factory: pytest.TempPathFactory) -> list[dict]:
    """The trace of the example's own command (stimulus and plant as shipped)."""
    return run_sim(tmp_path_factory.mktemp("trace"))


def plant_variant(tmp_path: Path, **attrs: object) -> Path:
    return helpers.plant_variant(tmp_path, "drill", **attrs)


def test_drill_clamps_lowers_dwells_raises_and_releases(records: list[dict]) -> None:
    assert path_of(records) == [["S1"], ["S2"], ["S3"], ["S4"], ["S5"], ["S6"], ["S7"], ["S1"]]
    (s2,), (s4,), (s5,), (s6,), (s7,) = (
        entered(records, s) for s in ("S2", "S4", "S5", "S6", "S7")
    )
    assert 1000 < s2 <= 1020  # the plant presses Start at 1000 ms, read in the next cycle
    assert 500 <= s6 - s5 <= 510  # the dwell of 0.5 s at the lower limit
    assert 2000 <= s5 - s4 <= 2030  # 100 mm at 50 mm/s
    assert 2000 <= s7 - s6 <= 2030
    assert not any(rec["values"]["ERR_FLT"] for rec in records)


def test_drill_outputs_follow_the_active_steps(records: list[dict]) -> None:
    for rec in records:
        active, v = set(rec["active"]), rec["values"]
        assert v["Lower_drill"] == ("S4" in active), rec  # N: on exactly while S4 is active
        assert v["Raise_drill"] == ("S6" in active), rec
        # S on activation of S2/S3, R on activation of S7 (latching)
        assert v["Clamp_workp"] == bool(active & {"S2", "S3", "S4", "S5", "S6"}), rec
        assert v["Dr_mot_on"] == bool(active & {"S2", "S3", "S4", "S5", "S6"}), rec
        assert v["Cool_pump_on"] == bool(active & {"S3", "S4", "S5", "S6"}), rec


def test_drill_without_coolant_selected_skips_the_coolant_step(tmp_path: Path) -> None:
    stim = stimulus_file(tmp_path, {"at_ms": 0, "set": {"Coolant_sel": False}})
    records = run_sim(tmp_path, stimulus=stim)
    assert path_of(records) == [["S1"], ["S2"], ["S4"], ["S5"], ["S6"], ["S7"], ["S1"]]
    assert not any(rec["values"]["Cool_pump_on"] for rec in records)


def test_drill_halts_with_a_supervision_fault_when_clamping_takes_over_500_ms(
    tmp_path: Path,
) -> None:
    plant = plant_variant(tmp_path, CLAMP_RISE_MS=1500)
    stim = stimulus_file(
        tmp_path,
        {"at_ms": 0, "set": {"Coolant_sel": True}},
        {"at_ms": 4000, "set": {"ACK_EF": True}},
        {"at_ms": 4100, "set": {"ACK_EF": False}},
    )
    records = run_sim(tmp_path, plant=plant, stimulus=stim, cycles=1100)
    (s2,) = entered(records, "S2")
    fault = [rec["t_ms"] for rec in records if rec["values"]["ERR_FLT"]]
    assert fault, "no supervision fault"
    assert s2 + 500 <= fault[0] <= s2 + 520  # S2.U > T#500MS
    # the pressure arrives at about s2 + 1500, but the step waits for the acknowledgement
    (s3,) = entered(records, "S3")
    assert 4000 <= s3 <= 4030
    assert all(rec["active"] == ["S2"] for rec in records if s2 <= rec["t_ms"] < 4000)
    assert not any(rec["values"]["ERR_FLT"] for rec in records if rec["t_ms"] >= s3)
    assert path_of(records)[-1] == ["S1"]  # and the cycle completes
