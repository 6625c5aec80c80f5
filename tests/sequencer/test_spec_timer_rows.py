"""Timer rows of a step: TL, TD, TF, TR on an S5 timer (docs/semantics.md, "Actions", timer
rows, and the rows "timer rows …" of "Decisions").

S7-GRAPH manual, ch. 13 (actions with timers): TL is an extended pulse — the timer bit 1 for
the time from the event —, TD a latching on delay — the bit 0 for the time from the event,
then 1 until TR —, TR stops the timer and clears its bit and value; TIA's qualifier list adds
TF, an off delay. The timer is a CPU timer: once started it runs on the CPU's time base,
whatever the step does. The driver ticks the T area before each call, as the CPU's OS does at
the start of each scan; a call is 10 ms and ``S5T#100MS`` is 10 units of 10 ms.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from s7graph.engine.memory import S5Timer
from s7graph.sfb import s5_timers as s5
from tests.sequencer.helpers import Run, enter, leave, sim_trace, two_steps


def ticking(run: Run) -> Run:
    """``run`` with the OS update of the T area before each FB call (start of the scan)."""
    execute = run.rt.execute

    def scan(inputs: dict[str, Any], now_ns: int) -> Any:
        s5.tick_all(run.mem.timers, now_ns)
        return execute(inputs, now_ns)

    run.rt.execute = scan  # type: ignore[method-assign]
    return run


def rows_in_s2(rows: str, **kw: Any) -> Run:
    """S1 -I0.0-> S2 (``rows``) -I0.1-> S3 -I0.2-> S1, with the OS timer update."""
    return ticking(two_steps(rows, **kw))


def t1(run: Run) -> S5Timer:
    return run.mem.timers[1]


def until_ms(run: Run, ms: int) -> None:
    """Calls until the next call is the one at ``ms`` (the clock reads ``ms``)."""
    while run.clock.now_ns() < ms * 1_000_000:
        run.call()


def back_to_s2(run: Run) -> None:
    """S3 -> S1 -> S2: the step is entered again (two calls)."""
    run.set(I0_2=True).call()
    run.set(I0_2=False, I0_0=True).call()
    run.set(I0_0=False)
    assert run.active == [2]


def test_tl_holds_the_timer_bit_for_its_time_from_its_event_even_after_the_step_is_left() -> None:
    run = rows_in_s2("S1 TL T 1, S5T#100MS;")
    enter(run)  # S1 of S2 in the call at 10 ms
    assert t1(run).q and t1(run).binary() == 10
    leave(run)  # at 20 ms: a CPU timer, the step's leaving does not stop it
    until_ms(run, 110)
    assert t1(run).q
    run.call()  # the update at 110 ms: 10 units of 10 ms since 10 ms
    assert not t1(run).q and t1(run).binary() == 0


def test_tl_started_again_by_its_event_runs_its_full_time_again() -> None:
    run = rows_in_s2("S1 TL T 1, S5T#100MS;")
    enter(run)  # started at 10 ms
    leave(run)
    back_to_s2(run)  # started again at 40 ms, while it runs
    until_ms(run, 130)
    run.call()
    assert t1(run).q  # the first start would have ended at 110 ms
    run.call()
    assert not t1(run).q  # 100 ms after 40 ms


def test_td_sets_the_timer_bit_after_its_time_and_keeps_it_after_the_step_is_left() -> None:
    run = rows_in_s2("S1 TD T 1, S5T#100MS;")
    enter(run)
    assert not t1(run).q and t1(run).running
    leave(run)
    until_ms(run, 110)
    assert not t1(run).q
    run.call()
    assert t1(run).q
    run.call(40)
    assert t1(run).q  # latched: until TR (or R T 1)


def test_td_started_again_by_its_event_after_it_elapsed_is_0_again_for_its_time() -> None:
    """The manual: "during the specified time the timer status is 0" — for every start, also
    one after the bit was set."""
    run = rows_in_s2("S1 TD T 1, S5T#100MS;")
    enter(run)
    leave(run)
    run.call(12)
    assert t1(run).q
    back_to_s2(run)  # S1 of S2 again, at 160 ms
    assert not t1(run).q and t1(run).binary() == 10
    until_ms(run, 260)
    run.call()
    assert t1(run).q


def test_tf_sets_the_timer_bit_at_its_event_and_drops_it_its_time_after_the_next_call() -> None:
    """An off delay whose start input is the event, a one-call pulse: the bit 1 in the event
    call, the time running from the pulse's falling edge in the next call (20 ms)."""
    run = rows_in_s2("S1 TF T 1, S5T#100MS;")
    enter(run)  # event at 10 ms
    assert t1(run).q
    leave(run)
    until_ms(run, 110)
    run.call()  # update at 110 ms: a TL started at 10 ms would be 0 here
    assert t1(run).q
    run.call()  # update at 120 ms: 100 ms after 20 ms
    assert not t1(run).q


def test_tf_started_again_while_its_delay_runs_keeps_the_bit_and_runs_its_full_time() -> None:
    run = rows_in_s2("S1 TF T 1, S5T#100MS;")
    enter(run)  # event at 10 ms, the delay from 20 ms
    leave(run)
    back_to_s2(run)  # event at 40 ms: the running delay stops, the bit stays 1
    assert t1(run).q
    until_ms(run, 140)
    run.call()  # update at 140 ms: the first delay would have ended at 120 ms
    assert t1(run).q
    run.call()  # 150 ms: 100 ms after the call after the second event
    assert not t1(run).q


def test_tr_stops_a_running_timer_and_clears_its_bit_and_value() -> None:
    run = ticking(
        Run(
            """FUNCTION_BLOCK "Tr"
  PARAMETERS := MAXIMUM;
SEQUENCE 1 "s"
  INITIAL_STEP S1 "a": END_STEP
  STEP S2 "b": S1 TL T 1, S5T#1S; END_STEP
  STEP S3 "c": S1 TR T 1; END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.0;
  TRANSITION T2 FROM S2 TO S3 := I0.1;
  TRANSITION T3 FROM S3 TO S1 := I0.2;
END_SEQUENCE
END_FUNCTION_BLOCK
""",
            file="tr.s7g",
        )
    )
    enter(run)
    run.call(5)
    assert t1(run).q and t1(run).binary() == 95
    leave(run)
    assert not t1(run).q and not t1(run).running and t1(run).binary() == 0
    run.call(150)
    assert not t1(run).q  # stopped: it does not come back


def test_a_timer_row_marked_c_starts_only_if_the_interlock_holds_at_its_event() -> None:
    run = rows_in_s2("S1 TLC T 1, S5T#100MS;", interlock="I0.5")
    enter(run)  # the interlock does not hold at the event
    assert not t1(run).q and not t1(run).running
    run.set(I0_5=True).call(3)  # it returns: the event is past, nothing starts
    assert not t1(run).running
    leave(run)
    run.set(I0_2=True).call()
    run.set(I0_2=False, I0_0=True).call()  # entered again with the interlock held
    assert t1(run).q and t1(run).running


def test_halt_tm_does_not_hold_a_timer_a_row_started() -> None:
    """HALT_TM freezes the step times and D, L; an S5 timer is the CPU's and runs on."""
    run = rows_in_s2("S1 TL T 1, S5T#100MS;")
    enter(run)
    run.set(HALT_TM=True)
    until_ms(run, 110)
    run.call()
    assert not t1(run).q


def test_the_time_of_a_timer_row_in_a_memory_word_is_an_s5time_word() -> None:
    """The manual: the time is an S5TIME constant or a word (IW, QW, MW, LW, DBW, DIW) holding
    an S5TIME: BCD count and time base, W#16#1001 = 1 × 100 ms, W#16#0200 = 200 × 10 ms."""
    run = rows_in_s2("S1 TL T 1, MW10;")
    run.mem.set("MW10", 0x1001)
    enter(run)
    assert (t1(run).preset_ms, t1(run).time_base_ms, t1(run).binary()) == (100, 100, 1)
    leave(run)
    run.mem.set("MW10", 0x0200)
    back_to_s2(run)
    assert (t1(run).preset_ms, t1(run).time_base_ms) == (2000, 10)


def test_a_tf_timer_contact_drops_its_time_after_the_call_after_its_event(tmp_path: Path) -> None:
    """In the CPU (``s7graph sim``): TF T0 on leaving Step1 at 10 ms; Step2 waits for
    ``NOT T0``, 800 ms after the falling edge of the event in the call at 20 ms."""
    text = """FUNCTION_BLOCK "Tf"
  PARAMETERS := STANDARD;
SEQUENCE 1 "s"
  INITIAL_STEP S1 "Step1": S0 TF T0, S5T#800MS; END_STEP
  STEP S2 "Step2": END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.0;
  TRANSITION T2 FROM S2 TO S1 := NOT T0;
END_SEQUENCE
END_FUNCTION_BLOCK
"""
    stim = [{"at_ms": 10, "set": {"I0.0": True}}, {"at_ms": 20, "set": {"I0.0": False}}]
    rc, lines = sim_trace(tmp_path, text, stim, cycles=95, watch="T0")
    assert rc == 0
    assert lines[1]["active"] == ["S2"] and lines[1]["values"] == {"T0": True}
    assert all(line["active"] == ["S2"] for line in lines[1:82])
    assert lines[82]["events"] == [["S2", "S1"]]  # a TL would have let go at line 81
