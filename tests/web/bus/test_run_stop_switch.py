"""The CPU's RUN/STOP switch on a running loop (``Runner.switch_stop`` / ``switch_start``,
the ops ``stop`` and ``start``) and a start in STOP after the supervisor killed a hung CPU
(``Runner.recover``): a STOP by the switch is not a STOP by an error, and a start does the
configured restart. ``status`` says why the CPU is in STOP, a startup it refused too."""

from __future__ import annotations

import mmap

import pytest

from s7graph.engine import Cpu, VirtualClock, ob
from s7graph.engine.diagnostics import EventId
from s7graph.engine.marks import MARKS_SIZE, MarkReader, ScanMarks
from s7graph.engine.modes import CpuMode, KeySwitch
from s7graph.engine.record import ScanRecord
from s7graph.engine.runner import refused_startup, stop_reason
from s7graph.web.bus.protocol import CpuStatus, StepStateUpdate
from s7graph.web.cli.remote import status_lines
from s7graph.web.view.texts import status_html
from tests.engine.test_cycle_profile import runner_with


@pytest.mark.timeout(30)
def test_the_switch_stops_without_an_error_and_starts_with_the_configured_restart() -> None:
    modes: list[CpuMode] = []
    runner = runner_with({})
    runner.end_on_stop = True  # as a run without a view: a STOP by an error would end it
    actions = {
        5: lambda: runner.switch_stop("STOP by the switch (eng)"),
        10: lambda: runner.switch_start("cold"),
    }

    def on_record(record: object) -> None:
        modes.append(runner.cpu.mode)
        action = actions.get(runner.scans)
        if action is not None:
            action()

    runner.on_record = on_record
    runner.run(duration_s=0.3)
    assert runner.stopped == ""  # never a STOP by itself: the loop went on
    assert CpuMode.STOP in modes and modes[-1] is CpuMode.RUN
    assert runner.cpu.last_restart == "cold"
    texts = [(e.event_id, e.message) for e in runner.cpu.diagnostics]
    assert (EventId.STOP_BY_REQUEST, "STOP by the switch (eng)") in texts
    assert (EventId.STARTUP_TO_RUN, "STARTUP → RUN (cold)") in texts


@pytest.mark.timeout(30)
def test_a_recovered_cpu_stays_in_stop_with_the_cause_until_started() -> None:
    runner = runner_with({})
    runner.cpu.stop("before the kill")
    page = mmap.mmap(-1, MARKS_SIZE)
    runner.marks = ScanMarks(memoryview(page))
    handed: list[ScanRecord] = []
    runner.on_record = handed.append
    record = runner.recover("plant p.py", "no scan ended for 1.3 s: hung in plant p.py")
    assert runner.cpu.mode is CpuMode.STOP
    assert handed == [record] and runner.scans == 0  # the bus says STOP before any scan
    assert record.mode is CpuMode.STOP
    assert [e.event_id for e in record.diagnostics] == [EventId.STOP_KILLED]
    assert runner.stopped == "plant p.py: no scan ended for 1.3 s: hung in plant p.py"
    runner.on_record = lambda record: runner.switch_start("warm") if runner.scans == 5 else None
    runner.run(duration_s=0.2)
    assert runner.cpu.mode is CpuMode.RUN and runner.stopped == ""
    reader = MarkReader(memoryview(page))
    assert reader.scans >= 10 and reader.busy_since_ns == 0  # every cycle marked, ended
    assert reader.max_cycle_ns == runner.cpu.watchdog.max_cycle_ns


def test_status_and_the_page_say_why_the_cpu_is_in_stop() -> None:
    why = "plant p.py: no scan ended for 1.3 s"
    lines = status_lines(CpuStatus(cpu="cpu1", state="STOP", reason=why))
    assert lines[:2] == ["CPU cpu1: STOP, cycle 0, FBs none, 0 force jobs", f"STOP: {why}"]
    update = StepStateUpdate(cycle=9, t_ms=90, mode="AUTO", active=[1])
    html = status_html(update, 9, "STOP", None, 0, why)
    assert '<b style="color:#c00">STOP</b>' in html and why in html


def _cpu(*, key_at_stop: bool = False, deselected: bool = False) -> Cpu:
    """A CPU with an empty OB1; its key switch at STOP, or OB35 loaded but deselected."""

    @ob(1)
    def main(ctx: object) -> None:
        pass

    @ob(35)
    def every_100_ms(ctx: object) -> None:
        pass

    cpu = Cpu(VirtualClock())
    cpu.load(main)
    if key_at_stop:
        cpu.key = KeySwitch.STOP
    if deselected:
        cpu.load(every_100_ms)
        cpu.interrupts.configure(35, 0)
    return cpu


@pytest.mark.parametrize(
    ("setup", "why"),
    [
        ({"key_at_stop": True}, "key switch is in STOP"),
        ({"deselected": True}, "OB35: OB35 is loaded but deselected: startup aborted"),
    ],
    ids=["the key switch at STOP", "a deselected OB"],
)
def test_status_says_that_the_cpu_refused_its_startup_and_why(
    setup: dict[str, bool], why: str
) -> None:
    """Before: ``STOP: the CPU is in STOP`` — a refusal writes no STOP entry. Now the words
    ``s7graph run`` says it with: the entry 16#4309's text, the block it names first."""
    cpu = _cpu(**setup)
    cpu.start("warm")
    assert cpu.mode is CpuMode.STOP
    reason = stop_reason(cpu)
    assert reason == f"the CPU refused its startup: {why}"
    lines = status_lines(CpuStatus(cpu="cpu1", state="STOP", reason=reason))
    assert lines[1] == f"STOP: the CPU refused its startup: {why}"


def test_a_startup_refused_after_a_stop_is_why_the_cpu_is_in_stop_now() -> None:
    cpu = _cpu()
    cpu.start("warm")
    cpu.stop("STOP by the switch (eng)")
    assert stop_reason(cpu) == "STOP by the switch (eng)"
    cpu.key = KeySwitch.STOP
    cpu.start("warm")
    assert stop_reason(cpu) == "the CPU refused its startup: key switch is in STOP"
    cpu.key = KeySwitch.RUN
    cpu.start("warm")  # started since: the refusal is no reason any more
    cpu.stop("STOP by the switch (eng)")
    assert stop_reason(cpu) == "STOP by the switch (eng)"


def test_a_hot_restart_turned_warm_is_no_refusal_in_status() -> None:
    cpu = _cpu()
    cpu.hot_blockers.add("program download")
    cpu.start("hot")
    assert cpu.mode is CpuMode.RUN and refused_startup(cpu) is None
    cpu.stop("STOP by the switch (eng)")
    assert stop_reason(cpu) == "STOP by the switch (eng)"
