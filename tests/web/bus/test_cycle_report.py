"""The cycle statistics as published in ``status`` and shown: the longest and the last long
cycle with where their time went (web/bus/scan_edge.py ``cycle_stats``, web/view/texts.py,
``s7graph status``)."""

from __future__ import annotations

import pytest

from s7graph.web.bus.protocol import CpuStatus, CycleStats, StepStateUpdate, decode, encode
from s7graph.web.bus.scan_edge import cycle_stats
from s7graph.web.cli.remote import status_lines
from s7graph.web.view.texts import status_html
from tests.engine.test_cycle_profile import runner_with, spin


@pytest.mark.timeout(30)
def test_the_status_carries_the_longest_and_the_last_long_cycle_with_their_phases() -> None:
    runner = runner_with({4: lambda: spin(0.030), 9: lambda: spin(0.016)})
    runner.run(duration_s=0.25)
    stats = decode(encode(cycle_stats(runner.cpu.stats, runner)), CycleStats)  # as sent
    assert stats.long >= 2 and stats.long_over_ms == 12.0 and stats.overruns >= 2
    assert stats.longest is not None and stats.longest.scan == 4
    assert stats.longest.cycle_ms >= 30 and stats.longest.parts["edge"] >= 30
    assert stats.longest.overrun
    assert stats.last_long is not None and stats.last_long.scan >= 9
    lines = status_lines(CpuStatus(cpu="cpu1", fbs=["Seq"], cycle=25, stats=stats))
    assert lines[0] == "CPU cpu1: RUN, cycle 25, FBs Seq, 0 force jobs"
    assert lines[2].startswith("longest: cycle 4 at ") and ", overran, " in lines[2]
    assert "edge 3" in lines[2]  # 30 ms and more after the scan
    assert lines[3].startswith(f"last over 12.0 ms ({stats.long} so far): cycle ")
    assert lines[4] == "communication: up to 20 % of the cycle at each scan boundary; never ran out"


def test_the_status_says_how_often_the_share_for_communication_ran_out() -> None:
    runner = runner_with({})
    runner.run(duration_s=0.05)
    stats = decode(encode(cycle_stats(runner.cpu.stats, runner, comm_limited=3)), CycleStats)
    assert stats.comm_load == 20 and stats.comm_limited == 3
    assert status_lines(CpuStatus(cpu="cpu1", stats=stats))[-1] == (
        "communication: up to 20 % of the cycle at each scan boundary; ran out at 3 scan "
        "boundaries (the commands left waited for the next)"
    )


def test_before_a_cycle_is_measured_the_status_says_so() -> None:
    lines = status_lines(CpuStatus(cpu="cpu1"))
    assert lines == [
        "CPU cpu1: RUN, cycle 0, FBs none, 0 force jobs",
        "cycle time: not measured yet",
    ]


def test_the_status_line_of_the_view_explains_the_longest_cycle_on_hover() -> None:
    runner = runner_with({3: lambda: spin(0.020)})
    runner.run(duration_s=0.1)
    update = StepStateUpdate(cycle=9, t_ms=90, mode="AUTO", active=[1])
    html = status_html(update, 9, "RUN", cycle_stats(runner.cpu.stats, runner))
    assert '<span title="longest: cycle 3 at ' in html
    assert "edge 2" in html and "cycle time " in html
