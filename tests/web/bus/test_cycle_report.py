"""The cycle statistics as published in ``status`` and shown: the longest and the last long
cycle with where their time went (web/bus/scan_edge.py ``cycle_stats``, web/view/texts.py,
``s7graph status``)."""

from __future__ import annotations

import pytest

from s7graph.web.bus.protocol import CpuStatus, CycleStats, StepStateUpdate, decode, encode
from s7graph.web.bus.scan_edge import cycle_report, cycle_stats
from s7graph.web.cli.remote import status_lines
from s7graph.web.view.texts import status_html
from tests.engine.test_cycle_profile import runner_with, spin


@pytest.mark.timeout(30)
def test_the_status_carries_the_longest_and_the_last_long_cycle_with_their_phases() -> None:
    # real time: scans 4 and 9 surely run long, and on a loaded machine any other may too —
    # the longest and the last long are the ones the run measured
    runner = runner_with(
        {4: lambda: spin(0.030), 9: lambda: spin(0.016), 12: lambda: runner.stop()}
    )
    runner.run(duration_s=20)  # until scan 12 (on a loaded machine, 0.25 s may not get there)
    stats = decode(encode(cycle_stats(runner.cpu.stats, runner)), CycleStats)  # as sent
    assert stats.long >= 2 and stats.long_over_ms == 12.0 and stats.overruns >= 2
    recent = list(runner.profile.recent)  # every long cycle of 12 scans
    spun = cycle_report(next(c for c in recent if c.scan == 4))
    assert spun.cycle_ms >= 30 and spun.parts["edge"] >= 30 and spun.overrun
    assert stats.longest == cycle_report(max(recent, key=lambda c: c.cycle_ns))
    assert stats.longest.cycle_ms >= spun.cycle_ms
    assert stats.last_long == cycle_report(recent[-1]) and stats.last_long.scan >= 9
    lines = status_lines(CpuStatus(cpu="cpu1", fbs=["Seq"], cycle=25, stats=stats))
    assert lines[0] == "CPU cpu1: RUN, cycle 25, FBs Seq, 0 force jobs"
    longest = stats.longest
    assert lines[2].startswith(f"longest: cycle {longest.scan} at ")
    assert (", overran, " in lines[2]) == longest.overrun  # scan 4 overran; one held, late
    assert f", {longest.cycle_ms:.1f} ms: " in lines[2]
    for name in ("edge", "late"):  # 30 ms and more of edge for scan 4
        if longest.parts.get(name, 0.0) >= 0.05:
            assert f"{name} {longest.parts[name]:.1f}" in lines[2], lines[2]
    assert lines[3].startswith(f"last over 12.0 ms ({stats.long} so far): cycle ")
    assert lines[4] == "communication: up to 20 % of the cycle at each scan boundary; never ran out"
    assert lines[5] == "scan thread: normal priority, on any processor"  # rt_priority None


def test_the_status_says_how_often_the_share_for_communication_ran_out() -> None:
    runner = runner_with({})
    runner.run(duration_s=0.05)
    stats = decode(encode(cycle_stats(runner.cpu.stats, runner, comm_limited=3)), CycleStats)
    assert stats.comm_load == 20 and stats.comm_limited == 3
    assert status_lines(CpuStatus(cpu="cpu1", stats=stats))[-2] == (
        "communication: up to 20 % of the cycle at each scan boundary; ran out at 3 scan "
        "boundaries (the commands left waited for the next)"
    )


def test_the_status_says_where_the_scan_thread_runs() -> None:
    stats = CycleStats(comm_load=20, priority=40, core=1)
    assert decode(encode(stats), CycleStats) == stats
    assert status_lines(CpuStatus(cpu="cpu1", stats=stats))[-1] == (
        "scan thread: real-time (SCHED_FIFO 40), on processor 1, kept for it"
    )
    plain = decode(encode(CycleStats(comm_load=20)), CycleStats)  # defaults left out
    assert (plain.priority, plain.core) == (0, -1)
    assert status_lines(CpuStatus(cpu="cpu1", stats=plain))[-1] == (
        "scan thread: normal priority, on any processor"
    )


def test_before_a_cycle_is_measured_the_status_says_so() -> None:
    lines = status_lines(CpuStatus(cpu="cpu1"))
    assert lines == [
        "CPU cpu1: RUN, cycle 0, FBs none, 0 force jobs",
        "cycle time: not measured yet",
    ]


def test_the_status_line_of_the_view_explains_the_longest_cycle_on_hover() -> None:
    runner = runner_with({3: lambda: spin(0.020), 5: lambda: runner.stop()})
    runner.run(duration_s=20)  # until scan 5
    longest = max(runner.profile.recent, key=lambda c: c.cycle_ns)  # 3, or one held longer
    update = StepStateUpdate(cycle=9, t_ms=90, mode="AUTO", active=[1])
    html = status_html(update, 9, "RUN", cycle_stats(runner.cpu.stats, runner))
    assert f'<span title="longest: cycle {longest.scan} at ' in html
    assert "cycle time " in html
    spun = next(c for c in runner.profile.recent if c.scan == 3)
    assert cycle_report(spun).parts["edge"] >= 20
    assert f"{cycle_report(longest).cycle_ms:.1f} ms: " in html
