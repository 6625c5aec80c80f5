"""The automatic drill of seed 000 §14.6 example 2 (000:6176-6225), run through ``s7graph sim``
(SPEC §4) with its plant (``examples/drill/plant.py``) and stimulus."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from web.cli import main

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "drill"
WATCH = (
    "Dr_mot_on", "Cool_pump_on", "Lower_drill", "Raise_drill", "Clamp_workp",
    "Cl_press_ok", "Drill_down", "Drill_up", "ERR_FLT", "S_NO",
)  # fmt: skip


def run_sim(
    tmp_path: Path,
    *,
    plant: Path = EXAMPLE / "plant.py",
    stimulus: Path = EXAMPLE / "stimulus.jsonl",
    cycles: int = 800,
    cycle_ms: int = 10,
) -> list[dict]:
    """Run the example's ``s7graph sim`` command; return the trace records."""
    trace = tmp_path / "trace.jsonl"
    rc = main([
        "sim", str(EXAMPLE / "drill.s7g"), "--symbols", str(EXAMPLE / "symbols.txt"),
        "--plant", str(plant), "--stimulus", str(stimulus), "--cycle-ms", str(cycle_ms),
        "--cycles", str(cycles), "--watch", ",".join(WATCH), "--trace", str(trace),
    ])  # fmt: skip
    assert rc == 0
    records = [json.loads(line) for line in trace.read_text().splitlines()]
    assert len(records) == cycles
    return records


@pytest.fixture(scope="module")
def records(tmp_path_factory: pytest.TempPathFactory) -> list[dict]:
    """The trace of the example's own command (stimulus and plant as shipped)."""
    return run_sim(tmp_path_factory.mktemp("trace"))


def path_of(records: list[dict]) -> list[list[str]]:
    """The successive sets of active steps, repeated sets collapsed."""
    path: list[list[str]] = []
    for rec in records:
        if not path or rec["active"] != path[-1]:
            path.append(rec["active"])
    return path


def entered(records: list[dict], step: str) -> list[int]:
    """The times (ms) of every cycle in which ``step`` became active."""
    times, before = [], False
    for rec in records:
        now = step in rec["active"]
        if now and not before:
            times.append(rec["t_ms"])
        before = now
    return times


def plant_variant(tmp_path: Path, **attrs: object) -> Path:
    """A plant file subclassing the example's ``Plant`` with other class attributes."""
    body = "".join(f"    {name} = {value!r}\n" for name, value in attrs.items())
    base = str(EXAMPLE / "plant.py")
    path = tmp_path / "plant_variant.py"
    path.write_text(
        "import importlib.util\n"
        f"_spec = importlib.util.spec_from_file_location('drill_plant', {base!r})\n"
        "_mod = importlib.util.module_from_spec(_spec)\n"
        "_spec.loader.exec_module(_mod)\n"
        f"class Plant(_mod.Plant):\n{body}"
    )
    return path


def stimulus_file(tmp_path: Path, *lines: dict) -> Path:
    path = tmp_path / "stimulus.jsonl"
    path.write_text("".join(json.dumps(line) + "\n" for line in lines))
    return path


def test_drill_clamps_lowers_dwells_raises_and_releases(records: list[dict]) -> None:
    assert path_of(records) == [["S1"], ["S2"], ["S3"], ["S4"], ["S5"], ["S6"], ["S7"], ["S1"]]
    (s2,), (s4,), (s5,), (s6,), (s7,) = (
        entered(records, s) for s in ("S2", "S4", "S5", "S6", "S7")
    )
    assert 1000 < s2 <= 1020  # the plant presses Start at 1000 ms, read in the next cycle
    assert 500 <= s6 - s5 <= 510  # the dwell of 0.5 s at the lower limit (000:6186)
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
    assert s2 + 500 <= fault[0] <= s2 + 520  # S2.U > T#500MS (000:6201)
    # the pressure arrives at about s2 + 1500, but the step waits for the acknowledgement
    (s3,) = entered(records, "S3")
    assert 4000 <= s3 <= 4030
    assert all(rec["active"] == ["S2"] for rec in records if s2 <= rec["t_ms"] < 4000)
    assert not any(rec["values"]["ERR_FLT"] for rec in records if rec["t_ms"] >= s3)
    assert path_of(records)[-1] == ["S1"]  # and the cycle completes
