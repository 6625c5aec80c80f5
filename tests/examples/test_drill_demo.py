"""The README demo's plant (``examples/drill/demo_plant.py``): the drill works piece after
piece and a slow clamp now and then faults S2 until someone acknowledges (docs/semantics.md,
"Supervision")."""

from __future__ import annotations

from pathlib import Path

from tests.examples.helpers import EXAMPLES, sim_example, stimulus_file

EXAMPLE = EXAMPLES / "drill"


def _sim(tmp_path: Path, stimulus: list[dict[str, object]], cycles: int) -> list[dict]:
    return sim_example(
        tmp_path,
        "drill",
        plant=EXAMPLE / "demo_plant.py",
        stimulus=stimulus_file(tmp_path, *stimulus),
        cycles=cycles,
        watch=("ERR_FLT", "pieces"),
        every_cycle=False,
    )


def test_demo_drill_faults_on_a_slow_clamp_and_holds_s2_without_acknowledgement(
    tmp_path: Path,
) -> None:
    records = _sim(tmp_path, [], 2000)
    fault = next(r for r in records if r["values"]["ERR_FLT"])
    assert fault["active"] == ["S2"]
    assert records[-1]["active"] == ["S2"] and records[-1]["values"]["ERR_FLT"]
    assert records[-1]["values"]["pieces"] >= 1


def test_demo_drill_goes_on_working_after_each_acknowledgement(tmp_path: Path) -> None:
    acks = [
        {"at_ms": t, "set": {"ACK_EF": on}}
        for k in range(1, 8)
        for t, on in ((k * 9000, True), (k * 9000 + 100, False))
    ]
    records = _sim(tmp_path, acks, 7000)
    assert any(r["values"]["ERR_FLT"] for r in records)
    assert records[-1]["values"]["pieces"] >= 5
