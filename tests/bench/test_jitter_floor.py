"""``bench/jitter.py`` sets the machine's stalls, as its C floor saw them, aside: each cycle of
the CPU less the time the machine stalled in it is what s7graph itself lost."""

from __future__ import annotations

import importlib.util
import sys
from types import ModuleType

import pytest

from tests.paths import ROOT

BENCH = ROOT / "bench"
MS = 1_000_000


@pytest.fixture(scope="module")
def jitter() -> ModuleType:
    sys.path.insert(0, str(BENCH))
    try:
        spec = importlib.util.spec_from_file_location("jitter_under_test", BENCH / "jitter.py")
        assert spec is not None and spec.loader is not None
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        return module
    finally:
        sys.path.remove(str(BENCH))


def floor_waking(*late_at: tuple[int, float], until_ms: int = 100) -> list[int]:
    """One processor's floor stamps every ms from 0, woken ``late`` ms late at ``at`` ms (and
    on time after, as clock_nanosleep to absolute deadlines catches up)."""
    stamps, t, lates = [], 0, dict(late_at)
    for k in range(until_ms):
        t = max(t, k * MS) + int(lates.get(k, 0) * MS)
        stamps.append(t)
    return stamps


def test_a_wake_up_half_a_millisecond_late_or_more_is_a_stall_from_its_deadline(
    jitter: ModuleType,
) -> None:
    stalls = jitter.floor_stalls([floor_waking((20, 3.0), (50, 0.2))])
    assert stalls == [[(20 * MS, 23 * MS)]]  # the 0.2 ms at 50 is ordinary wake-up latency


def test_a_cycle_the_machine_stalled_is_counted_less_the_stall(jitter: ModuleType) -> None:
    starts = [k * 10 * MS for k in range(9)]
    starts[3:] = [s + 4 * MS for s in starts[3:]]  # the cycle 20..34 ms is 14 ms long
    quiet = floor_waking()
    stalled = floor_waking((25, 4.0))  # the other processor stalled 25..29 ms
    result = {"starts": starts, "floor": [quiet, stalled], "overran": []}
    own = jitter.own_figures(result)
    assert (own["long"], own["shared"], own["own_max"]) == (1.0, 1.0, 10.0)


def test_a_long_cycle_the_machine_did_not_stall_stays_own(jitter: ModuleType) -> None:
    starts = [0, 10 * MS, 24 * MS, 34 * MS]
    result = {"starts": starts, "floor": [floor_waking((60, 4.0))], "overran": [(10 * MS, 21 * MS)]}
    own = jitter.own_figures(result)
    assert (own["shared"], own["own_max"], own["own_overruns"]) == (0.0, 14.0, 1.0)


def test_a_stall_counts_only_where_it_overlaps_the_cycle(jitter: ModuleType) -> None:
    stalls = jitter.floor_stalls([floor_waking((8, 5.0))])  # 8..13 ms
    assert jitter.machine_share(stalls, 10 * MS, 20 * MS) == 3 * MS
    assert jitter.machine_share(stalls, 0, 9 * MS) == 1 * MS
    assert jitter.machine_share(stalls, 14 * MS, 30 * MS) == 0
