"""docs/semantics.md, "Decisions" (display paging) and §8: in MAN the operator shows a step in
``S_NO`` and an ``S_ON``/``S_OFF`` edge acts on it. ``S_PREV``/``S_NEXT`` then page through
every step by number — the next lower or higher, active or not — so a step can be shown and
activated without ``S_SEL``; in AUTO they page the display set (the active steps). An
``S_SEL`` naming a step the chart lacks is NO_SNO ("selected step does not exist", manual
15-18): ``S_NO`` shows 0 and ``S_ON``/``S_OFF`` act on no step — never on the step shown
before.

Through ``s7graph sim`` (the black-box contract), 10 ms per cycle."""

from __future__ import annotations

from pathlib import Path

from tests.sequencer.helpers import seq, sim_trace, source

CHART = source(
    seq("""
  INITIAL_STEP S1 "one":
    N Q0.0;
  END_STEP
  STEP S2 "two":
    N Q0.1;
  END_STEP
  STEP S3 "three":
    N Q0.2;
  END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.0;
  TRANSITION T2 FROM S2 TO S3 := I0.0;
  TRANSITION T3 FROM S3 TO S1 := I0.0;
"""),
    params="STANDARD",
)


def _press(at_ms: int, pin: str, **held: object) -> list[dict]:
    """A rising edge of ``pin`` at ``at_ms`` (back to FALSE 10 ms later), with ``held``."""
    return [
        {"at_ms": at_ms, "set": {pin: True, **held}},
        {"at_ms": at_ms + 10, "set": {pin: False}},
    ]


def test_in_man_s_next_shows_the_next_step_by_number_and_s_on_activates_it(
    tmp_path: Path,
) -> None:
    stim = [
        *_press(0, "SW_MAN"),
        *_press(20, "S_NEXT"),
        *_press(40, "S_NEXT"),
        *_press(60, "S_ON"),
        *_press(80, "S_PREV"),
    ]
    rc, lines = sim_trace(tmp_path, CHART, stim, cycles=10, watch="S_NO,Q0.2")
    assert rc == 0
    assert [line["values"]["S_NO"] for line in lines] == [1, 1, 2, 2, 3, 3, 3, 3, 2, 2]
    assert lines[6]["active"] == ["S1", "S3"] and lines[6]["values"]["Q0.2"] is True


def test_in_auto_s_next_pages_only_the_active_steps(tmp_path: Path) -> None:
    rc, lines = sim_trace(tmp_path, CHART, _press(20, "S_NEXT"), cycles=4, watch="S_NO")
    assert rc == 0
    assert [line["values"]["S_NO"] for line in lines] == [1, 1, 1, 1]


def test_s_on_after_selecting_a_step_the_chart_lacks_activates_nothing(tmp_path: Path) -> None:
    stim = [
        *_press(0, "SW_MAN"),
        {"at_ms": 20, "set": {"S_SEL": 3}},
        {"at_ms": 40, "set": {"S_SEL": 99}},
        *_press(60, "S_ON"),
        {"at_ms": 80, "set": {"S_SEL": 3}},
        *_press(100, "S_ON"),
    ]
    rc, lines = sim_trace(tmp_path, CHART, stim, cycles=12, watch="S_NO")
    assert rc == 0
    assert lines[3]["values"]["S_NO"] == 3
    assert lines[5]["values"]["S_NO"] == 0  # NO_SNO
    assert lines[7]["active"] == ["S1"]  # S_ON acted on no step
    assert lines[9]["values"]["S_NO"] == 3
    assert lines[11]["active"] == ["S1", "S3"]


def test_while_off_sq_is_held_s_on_activates_nothing(tmp_path: Path) -> None:
    stim = [
        *_press(0, "SW_MAN"),
        {"at_ms": 20, "set": {"OFF_SQ": True, "S_SEL": 3}},
        *_press(40, "S_ON"),
    ]
    rc, lines = sim_trace(tmp_path, CHART, stim, cycles=6, watch="Q0.2,S_NO")
    assert rc == 0
    assert [line["active"] for line in lines[2:]] == [[]] * 4
    assert not any(line["values"]["Q0.2"] for line in lines)
