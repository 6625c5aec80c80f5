"""The industrial mixing process of Siemens' Program Design for S7-300/400 (ch. 1 and appendix A) as
a GRAPH sequence, run through ``s7graph sim`` (docs/cli.md, "s7graph sim") with its plant
(``examples/mixing/plant.py``) and stimulus, 50 ms cycles."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.examples import helpers
from tests.examples.helpers import EXAMPLES, first, on, path_of, sim_example, stimulus_file

EXAMPLE = EXAMPLES / "mixing"
WATCH = (
    "Speisepumpe_A",
    "Einlassventil_A",
    "Speiseventil_A",
    "Speisepumpe_A_Fehler",
    "Speisepumpe_A_Ein",
    "Speisepumpe_B",
    "Einlassventil_B",
    "Speiseventil_B",
    "Ruehrwerk",
    "Abfluss",
    "Durchfluss_A",
    "Behaelter_nicht_Leer",
    "Behaelter_Leer_Anz",
    "ERR_FLT",
)


def run_sim(
    tmp_path: Path,
    *,
    plant: Path = EXAMPLE / "plant.py",
    stimulus: Path = EXAMPLE / "stimulus.jsonl",
    cycles: int = 1200,
) -> list[dict]:
    """Run the example's ``s7graph sim`` command; return the trace records."""
    return sim_example(
        tmp_path,
        "mixing",
        watch=WATCH,
        plant=plant,
        stimulus=stimulus,
        cycles=cycles,
        cycle_ms=50,
    )


@pytest.fixture(scope="module")
def records(tmp_path_factory: pytest.TempPathFactory) -> list[dict]:
    """The trace of the example's own command (stimulus and plant as shipped)."""
    return run_sim(tmp_path_factory.mktemp("trace"))


def plant_variant(tmp_path: Path, **attrs: object) -> Path:
    return helpers.plant_variant(tmp_path, "mixing", **attrs)


START = (
    {"at_ms": 0, "set": {"NOT_AUS_aus": True}},
    {"at_ms": 1000, "set": {"Batch_start": True}},
    {"at_ms": 1500, "set": {"Batch_start": False}},
)


def test_mixing_feeds_a_and_b_together_then_mixes_then_drains(records: list[dict]) -> None:
    assert path_of(records) == [
        ["S1"],
        ["S2", "S4"],
        ["S2", "S5"],
        ["S3", "S5"],
        ["S6"],
        ["S7"],
        ["S8"],
        ["S1"],
    ]
    # both feeds start in the same cycle (simultaneous branch), B (9 s) ends before A (15 s)
    pump_a, pump_b = first(records, on("Speisepumpe_A")), first(records, on("Speisepumpe_B"))
    assert pump_a == pump_b == 1000
    assert 9000 <= first(records, lambda r: r["active"] == ["S2", "S5"]) - pump_b <= 9050
    assert 15000 <= first(records, lambda r: r["active"] == ["S3", "S5"]) - pump_a <= 15050
    assert not any(rec["values"]["ERR_FLT"] for rec in records)
    assert records[-1]["values"]["Behaelter_Leer_Anz"] is True


def test_mixing_opens_the_valves_one_second_after_the_pump(records: list[dict]) -> None:
    pump = first(records, on("Speisepumpe_A"))
    for valve in ("Einlassventil_A", "Speiseventil_A", "Einlassventil_B", "Speiseventil_B"):
        assert 1000 <= first(records, on(valve)) - pump <= 1050, valve
    # and every valve closes with its pump, when the feed step is left
    for rec in records:
        v = rec["values"]
        assert not (v["Einlassventil_A"] or v["Speiseventil_A"]) or v["Speisepumpe_A"], rec
        assert not (v["Einlassventil_B"] or v["Speiseventil_B"]) or v["Speisepumpe_B"], rec


def test_mixing_runs_the_agitator_20_s_and_drains_only_once_it_has_stopped(
    records: list[dict],
) -> None:
    mix_on = first(records, on("Ruehrwerk"))
    mix_off = first(records, lambda r: r["t_ms"] > mix_on and not r["values"]["Ruehrwerk"])
    assert 20000 <= mix_off - mix_on <= 20050  # S6.U >= mix_time
    drain = first(records, on("Abfluss"))
    assert drain >= mix_off + 1000  # the agitator runs down for 1 s before the drain opens
    for rec in records:
        assert not (rec["values"]["Abfluss"] and rec["values"]["Ruehrwerk"]), rec
        assert rec["values"]["Abfluss"] == (rec["active"] == ["S8"]), rec
    drain_closed = first(records, lambda r: r["t_ms"] > drain and not r["values"]["Abfluss"])
    assert drain_closed == first(records, lambda r: r["t_ms"] > drain and r["active"] == ["S1"])


def test_mixing_missing_flow_of_a_faults_feed_a_only_until_acknowledged(tmp_path: Path) -> None:
    plant = plant_variant(tmp_path, FLOW_A_BROKEN_UNTIL_MS=12000)
    stim = stimulus_file(
        tmp_path,
        *START,
        {"at_ms": 20000, "set": {"ACK_EF": True}},
        {"at_ms": 20500, "set": {"ACK_EF": False}},
    )
    records = run_sim(tmp_path, plant=plant, stimulus=stim)
    fault = first(records, on("ERR_FLT"))
    assert 8000 <= fault <= 8100  # no flow 7 s after the pump started at 1 s
    assert first(records, on("Speisepumpe_A_Fehler")) == fault  # V1 S lamp
    # the other path carries on while S2 holds its fault
    assert 10000 <= first(records, lambda r: r["active"] == ["S2", "S5"]) <= 10050
    # flow comes back at 12 s, but S2 stays until ACK_EF at 20 s (acknowledge required)
    assert all("S2" in rec["active"] for rec in records if 1000 <= rec["t_ms"] < 20000)
    left = first(records, lambda r: r["t_ms"] >= 1000 and "S2" not in r["active"])
    assert 20000 <= left <= 20100
    lamp = "Speisepumpe_A_Fehler"
    lamp_off = first(records, lambda r: r["t_ms"] > fault and not r["values"][lamp])
    assert 20000 <= lamp_off <= 20050  # A1 R lamp
    assert path_of(records)[-4:] == [["S6"], ["S7"], ["S8"], ["S1"]]


def test_mixing_switches_pump_a_and_its_valves_off_during_its_no_flow_fault(
    tmp_path: Path,
) -> None:
    """The book's motor block (FB1, network 2) resets the motor when the feedback is missing
    after its time: pump A and its valves are off from the fault (8 s) until the
    acknowledgement lets S2 go (20 s), while feed B runs its own course."""
    plant = plant_variant(tmp_path, FLOW_A_BROKEN_UNTIL_MS=12000)
    stim = stimulus_file(
        tmp_path,
        *START,
        {"at_ms": 20000, "set": {"ACK_EF": True}},
        {"at_ms": 20500, "set": {"ACK_EF": False}},
    )
    records = run_sim(tmp_path, plant=plant, stimulus=stim)
    fault = first(records, on("Speisepumpe_A_Fehler"))
    left = first(records, lambda r: r["t_ms"] >= 1000 and "S2" not in r["active"])
    assert 8000 <= fault <= 8100 and 20000 <= left <= 20100
    for rec in records:
        v = rec["values"]
        if fault <= rec["t_ms"] < left:
            assert "S2" in rec["active"], rec
            assert not (v["Speisepumpe_A"] or v["Einlassventil_A"] or v["Speiseventil_A"]), rec
            assert v["Speisepumpe_A_Ein"] is False, rec
    assert all(r["values"]["Speisepumpe_B"] for r in records if 1000 <= r["t_ms"] < 10000)


def test_mixing_switches_the_agitator_off_when_it_never_reaches_speed(tmp_path: Path) -> None:
    """No "at speed" feedback 10 s after the agitator started: fault lamp on, agitator off
    (FB1 network 2 for the agitator's instance), the sequence holds in S6."""
    plant = plant_variant(tmp_path, AGITATOR_RUNUP_MS=10**9)
    records = run_sim(tmp_path, plant=plant, cycles=800)
    start = first(records, on("Ruehrwerk"))
    fault = first(records, on("ERR_FLT"))
    assert 10000 <= fault - start <= 10100
    after = [r for r in records if r["t_ms"] >= fault]
    assert after and all(r["active"] == ["S6"] for r in after)
    assert not any(r["values"]["Ruehrwerk"] for r in after)


def test_mixing_emergency_stop_switches_the_feeds_off_without_moving_the_sequence(
    tmp_path: Path,
) -> None:
    stim = stimulus_file(
        tmp_path,
        *START,
        {"at_ms": 5000, "set": {"NOT_AUS_aus": False}},
        {"at_ms": 6000, "set": {"NOT_AUS_aus": True}},
    )
    records = run_sim(tmp_path, stimulus=stim, cycles=200)
    for rec in records:
        t, v = rec["t_ms"], rec["values"]
        if 1000 <= t < 10000:
            assert rec["active"] == ["S2", "S4"], rec
            interlocked = 5000 <= t < 6000  # interlock lost: C rows off, step disturbed
            assert v["Speisepumpe_A"] is v["Speisepumpe_B"] is (not interlocked), rec
            assert v["ERR_FLT"] is interlocked, rec
            if interlocked:
                assert not (v["Einlassventil_A"] or v["Speiseventil_B"]), rec
