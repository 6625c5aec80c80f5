"""The oven of ``examples/oven/``: the PID temperature control of Eng. Hassan El-Shahat's
S7-300/400 advanced course — SFB41 CONT_C and SFB43 PULSEGEN in an S7-SCL OB35
(``oven.scl``) on a simulated oven (``plant.py``), a GRAPH chart (``oven.s7g``) walking
Idle → Heat_up → Hold → Cool and setting the setpoint — run on the virtual clock through
the harness's Python API (``ChartSession.load(…, blocks=…)``), 100 ms cycles as OB35's
period. Siemens' *System Software for S7-300/400, System and Standard Functions* describes
the two blocks (docs/runtime.md, "Process control: CONT_C, CONT_S, PULSEGEN")."""

from __future__ import annotations

import json
import re
import statistics
from pathlib import Path
from typing import Any

import pytest

from s7graph.engine.clock import VirtualClock
from s7graph.web.harness.plant import load_plant
from s7graph.web.harness.session import ChartSession
from tests.examples import helpers
from tests.examples.helpers import EXAMPLES, first, path_of
from tests.paths import ROOT

EXAMPLE = EXAMPLES / "oven"
CYCLE_MS = 100  # the scan, and OB35's period: OB35 runs once a scan
PERIOD_CALLS = 50  # PULSEGEN's PER_TM T#5S in calls of T#100MS
SETPOINT = 180.0
WATCH = ("Oven_temp", "Setpoint", "Heater", "Heater_pct", "ERR_FLT", "firings")


def run_oven(cycles: int, plant: Path = EXAMPLE / "plant.py") -> list[dict[str, Any]]:
    """The example on the virtual clock, as ``s7graph sim`` runs a chart: the stimulus of
    ``stimulus.jsonl`` (the operator presses Start from 1 s to 2 s) in the cycle of its
    time; each cycle a scan, then the plant. One record a cycle in ``sim``'s trace form."""
    session = ChartSession.load(
        EXAMPLE / "oven.s7g", EXAMPLE / "symbols.txt", VirtualClock(), blocks=[EXAMPLE / "oven.scl"]
    )
    lines = (EXAMPLE / "stimulus.jsonl").read_text(encoding="utf-8").splitlines()
    stimulus = {line["at_ms"]: line["set"] for line in map(json.loads, lines)}
    assert stimulus == {1000: {"Start": True}, 2000: {"Start": False}}
    oven = load_plant(plant)
    session.start()
    records = []
    for k in range(cycles):
        t_ms = k * CYCLE_MS
        for name, value in stimulus.get(t_ms, {}).items():
            session.set(name, value)
        record = session.scan()
        assert record.mode.name == "RUN"
        oven.cycle(session, t_ms, CYCLE_MS)
        active = [f"S{n}" for n in (1, 2, 3, 4) if session.get(f"S{n}.X")]
        values = {name: session.get(name) for name in WATCH}
        records.append({"t_ms": t_ms, "active": active, "values": values})
        session.clock.advance(CYCLE_MS)
    return records


@pytest.fixture(scope="module")
def records() -> list[dict[str, Any]]:
    """One firing: heat-up about 4 min, hold 5 min, cooling about 8.5 min."""
    return run_oven(11_000)


def temps(records: list[dict[str, Any]], step: str) -> list[tuple[int, float]]:
    return [(r["t_ms"], r["values"]["Oven_temp"]) for r in records if r["active"] == [step]]


def test_oven_walks_idle_heat_up_hold_cool_and_back(records: list[dict[str, Any]]) -> None:
    assert path_of(records) == [["S1"], ["S2"], ["S3"], ["S4"], ["S1"]]
    heat, hold = first(records, lambda r: r["active"] == ["S2"]), temps(records, "S3")
    cool = temps(records, "S4")
    assert heat == 1000
    reached = first(records, lambda r: r["values"]["Oven_temp"] >= SETPOINT - 2.0)
    assert 0 <= hold[0][0] - reached <= CYCLE_MS  # T2: within the band of the setpoint
    # at full power the oven would reach 178 C in 300 s * ln(300 / 142) = 224 s; the
    # controller leaves full power at 170 C, 10 K below the setpoint, after 212 s
    assert 224_000 <= hold[0][0] - heat <= 260_000
    assert 300_000 <= cool[0][0] - hold[0][0] <= 300_100  # T3: S3.T >= T#5M
    cooled = first(records, lambda r: r["active"] == ["S4"] and r["values"]["Oven_temp"] <= 50)
    assert cooled == cool[-1][0]  # T4 in the next cycle: cooled to 50 C
    # by its losses alone: 180 -> 50 C in 300 s * ln(160 / 30) = 502 s
    assert 490_000 <= cooled - cool[0][0] <= 515_000
    assert not any(r["values"]["ERR_FLT"] for r in records)
    assert records[-1]["values"]["firings"] == 1  # S4's S0 row
    setpoints = {
        step: {r["values"]["Setpoint"] for r in records if r["active"] == [step]}
        for step in ("S2", "S3", "S4")
    }
    assert setpoints == {"S2": {SETPOINT}, "S3": {SETPOINT}, "S4": {0.0}}


def test_oven_settles_in_hold_without_overshoot_or_sustained_oscillation(
    records: list[dict[str, Any]],
) -> None:
    """The PI loop (GAIN 10 %/K, TI 1 min) leaves the heater's full power 10 K below the
    setpoint and comes in without overshoot; what stays is the pulse width modulation's
    ripple (about 1.4 K peak to peak: a 5 s period at 53 % of the heater's power), not an
    oscillation of the loop: averaged over each pulse period the temperature never passes
    the setpoint by more than 0.2 K, and from the third minute of Hold stays within 0.2 K."""
    heat_up, hold = temps(records, "S2"), temps(records, "S3")
    start = hold[0][0]
    both = [t for _, t in heat_up + hold]
    averages = [statistics.fmean(both[i : i + PERIOD_CALLS]) for i in range(len(both) - 49)]
    assert max(averages) <= SETPOINT + 0.2  # overshoot of the period's mean
    assert max(both) <= SETPOINT + 1.0  # and of the ripple's top
    late = [t for ms, t in hold if ms - start >= 120_000]  # after 2 minutes of Hold
    assert all(abs(t - SETPOINT) <= 1.0 for t in late)
    assert max(late) - min(late) <= 1.5
    settled = late[600:]  # after 3 minutes
    periods = [statistics.fmean(settled[i : i + PERIOD_CALLS]) for i in range(len(settled) - 49)]
    assert all(abs(t - SETPOINT) <= 0.2 for t in periods)


def pulse_ms(lmn: float) -> float:
    """PULSEGEN's pulse for INV = ``lmn`` %: of the 5 s period, none below P_B_TM (200 ms),
    all of it above 5 s - P_B_TM."""
    ms = lmn / 100.0 * PERIOD_CALLS * CYCLE_MS
    return 0.0 if ms < 200 else PERIOD_CALLS * CYCLE_MS if ms > 4800 else ms


def test_oven_heater_pulses_with_the_duty_cycle_of_lmn(records: list[dict[str, Any]]) -> None:
    """PULSEGEN (two-step, unipolar, no synchronisation) takes LMN in the first call of each
    5 s period and switches the heater on for the period's first ``LMN / 100 * 50`` calls
    (rounded), off for the rest: full power through the heat-up, 53 % in Hold, off while
    the oven cools. The first pulse starts at the first period after Start."""
    heater = [bool(r["values"]["Heater"]) for r in records]
    begin = heater.index(True)
    assert 1000 < records[begin]["t_ms"] <= 1000 + PERIOD_CALLS * CYCLE_MS
    duties: dict[str, list[float]] = {"S2": [], "S3": [], "S4": []}
    for a in range(begin, len(records) - PERIOD_CALLS, PERIOD_CALLS):
        lmn = records[a]["values"]["Heater_pct"]
        on = sum(heater[a : a + PERIOD_CALLS])
        assert heater[a : a + PERIOD_CALLS] == [True] * on + [False] * (PERIOD_CALLS - on)
        assert abs(on - pulse_ms(lmn) / CYCLE_MS) <= 0.5 + 1e-3, (records[a]["t_ms"], on, lmn)
        step = records[a + PERIOD_CALLS - 1]["active"]
        if step == records[a]["active"] and step[0] in duties:
            duties[step[0]].append(on / PERIOD_CALLS)
    assert set(duties["S2"][:40]) == {1.0}  # the first 200 s of the heat-up at full power
    assert set(duties["S4"]) == {0.0}
    # holding 180 C takes 160 K / 300 K = 53 % of the heater's power
    assert statistics.fmean(duties["S3"][-30:]) == pytest.approx(160 / 300, abs=0.01)


def test_oven_too_weak_a_heater_is_a_supervision_fault_in_heat_up(tmp_path: Path) -> None:
    """Half the heater's power reaches at most 20 + 150 = 170 C: Heat_up never ends, and
    its supervision (S2.U > heat_limit, 15 min) reports the fault."""
    weak = helpers.plant_variant(tmp_path, "oven", HEATER_W=1500.0)
    records = run_oven(9_200, weak)
    fault = first(records, lambda r: r["values"]["ERR_FLT"])
    assert 901_000 <= fault <= 901_200
    assert records[-1]["active"] == ["S2"]
    assert max(r["values"]["Oven_temp"] for r in records) < 170.0


def test_oven_readme_python_way_runs_one_firing(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """The README's Python block, as written, from the repository's root, prints what the
    README says it prints: a line a minute, Idle → Heat_up → Hold → Cool → Idle."""
    text = (EXAMPLE / "README.md").read_text(encoding="utf-8")
    (code,) = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    (printed,) = re.findall(r"```text\n(.*?)```", text, flags=re.S)
    monkeypatch.chdir(ROOT)
    exec(compile(code, "examples/oven/README.md", "exec"), {})
    assert capsys.readouterr().out == printed
    steps = [line.split()[2] for line in printed.splitlines()]
    assert steps == ["S1"] + ["S2"] * 4 + ["S3"] * 5 + ["S4"] * 8 + ["S1"]


def test_the_readmes_command_line_runs_the_same_oven_as_the_harness(tmp_path: Path) -> None:
    """``s7graph sim … --blocks oven.scl`` (the README's command) and the Python session
    trace the same cycles."""
    from s7graph.web.cli import main
    from s7graph.web.cli.trace import traced

    trace = tmp_path / "oven.jsonl"
    args = ["sim", str(EXAMPLE / "oven.s7g"), "--blocks", str(EXAMPLE / "oven.scl")]
    args += ["--symbols", str(EXAMPLE / "symbols.txt"), "--plant", str(EXAMPLE / "plant.py")]
    args += ["--stimulus", str(EXAMPLE / "stimulus.jsonl"), "--cycle-ms", "100"]
    args += ["--cycles", "3000", "--watch", ",".join(WATCH[:5]), "--trace", str(trace)]
    assert main(args) == 0
    cli = [json.loads(line) for line in trace.read_text(encoding="utf-8").splitlines()]
    ours = run_oven(3000)
    assert len(cli) == len(ours) == 3000
    for k in (0, 999, 2999):
        assert cli[k]["active"] == ours[k]["active"]
        assert {n: cli[k]["values"][n] for n in WATCH[:5]} == {
            n: traced(ours[k]["values"][n]) for n in WATCH[:5]
        }
