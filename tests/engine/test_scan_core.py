"""The processor kept for the scan (engine/cores.py, engine/runner.py): which one ``--core``
chooses, and while the loop runs the scan thread on it (with the state writer's encoder,
which works while the scan sleeps) and the process's other threads on the rest, every
thread given all of them back when the loop ends."""

from __future__ import annotations

import os
import threading
from collections.abc import Callable
from pathlib import Path

import pytest

from s7graph.engine import CallContext, Cpu, SystemClock, ob
from s7graph.engine.cores import kept_free, others, scan_core
from s7graph.engine.persistence import StateStore
from s7graph.engine.runner import Runner, core_for
from tests.engine.bystander import bystander

TWO = {0, 1}


@ob(1)
def idle(ctx: CallContext) -> None:
    pass


def test_auto_keeps_the_last_processor_for_a_real_time_scan_on_two_or_more() -> None:
    assert scan_core("auto", realtime=True, allowed={0, 1, 2, 3}) == 3
    assert scan_core(None, realtime=True, allowed={2, 5}) == 5


def test_auto_keeps_none_for_a_scan_at_normal_priority_or_on_one_processor() -> None:
    assert scan_core("auto", realtime=False, allowed=TWO) is None
    assert scan_core("auto", realtime=True, allowed={0}) is None


def test_off_keeps_none_and_a_number_keeps_that_one_real_time_or_not() -> None:
    assert scan_core("off", realtime=True, allowed=TWO) is None
    assert scan_core(0, realtime=False, allowed=TWO) == 0
    assert scan_core("1", realtime=True, allowed=TWO) == 1


@pytest.mark.parametrize(
    ("choice", "says"),
    [
        (7, "core 7 is not a processor this process may use (0, 1)"),
        ("-1", "core '-1' is none of auto, off or a processor number"),
        ("fast", "core 'fast' is none of auto, off or a processor number"),
        (True, "core True is none of auto, off or a processor number"),
        (1.5, "core 1.5 is none of auto, off or a processor number"),
    ],
)
def test_a_core_that_cannot_be_is_refused_naming_it(choice: object, says: str) -> None:
    with pytest.raises(ValueError) as info:
        scan_core(choice, realtime=True, allowed=TWO)  # type: ignore[arg-type]
    assert str(info.value) == says


def test_the_others_are_the_rest_or_the_only_one_there_is() -> None:
    assert others(1, {0, 1, 2}) == {0, 2}
    assert others(0, {0}) == {0}


def test_without_a_real_time_priority_auto_keeps_nothing() -> None:
    assert core_for("auto", None) is None
    assert core_for("off", 40) is None


needs_two = pytest.mark.skipif(
    not hasattr(os, "sched_setaffinity") or len(os.sched_getaffinity(0)) < 2,
    reason="one processor here: none to keep",
)


@needs_two
def test_kept_free_moves_the_thread_off_the_core_and_back() -> None:
    before = set(os.sched_getaffinity(0))
    core = max(before)
    with kept_free(core):
        inside = set(os.sched_getaffinity(0))
        born: list[set[int]] = []
        t = threading.Thread(target=lambda: born.append(set(os.sched_getaffinity(0))))
        t.start()
        t.join()
    assert inside == before - {core} and born == [inside]  # what it starts inherits it
    assert set(os.sched_getaffinity(0)) == before


def _at_scan_5(
    core: int, look: Callable[[Runner], dict[str, set[int]]], store: StateStore | None = None
) -> tuple[Runner, dict[str, set[int]]]:
    """Run an idle CPU with ``core`` kept, and ``look`` at the threads' processors in its
    fifth scan; the runner (shut down) and what was seen."""
    cpu = Cpu(SystemClock())
    cpu.load(idle)
    seen: dict[str, set[int]] = {}

    def on_record(_: object) -> None:
        if runner.scans == 5 and not seen:
            seen.update(look(runner))
            runner.stop()

    runner = Runner(cpu, cycle_ms=5, rt_priority=None, on_record=on_record, core=core, store=store)
    runner.startup()
    try:
        runner.run(duration_s=10)
    finally:
        runner.shutdown()
    return runner, seen


@needs_two
@pytest.mark.timeout(30)
def test_while_the_loop_runs_the_scan_has_its_core_and_the_other_threads_the_rest() -> None:
    allowed = set(os.sched_getaffinity(0))
    core = min(allowed)
    after: list[set[int]] = []
    with bystander() as helper:
        runner, seen = _at_scan_5(
            core,
            lambda _: {
                "scan": set(os.sched_getaffinity(0)),
                "helper": set(os.sched_getaffinity(helper)),
            },
        )
        after += [set(os.sched_getaffinity(0)), set(os.sched_getaffinity(helper))]
    assert seen == {"scan": {core}, "helper": allowed - {core}}
    assert after == [allowed, allowed] and not runner.pinned


@needs_two
@pytest.mark.timeout(30)
def test_the_writers_encoder_works_on_the_kept_core_while_the_scan_thread_sleeps(
    tmp_path: Path,
) -> None:
    """The encoder thread (``engine/writer.py``) encodes the instance DBs only while the
    scan thread idles, and runs below it: it shares the kept processor, which is idle then,
    instead of the others' load; the writer that commits stays off it."""
    allowed = set(os.sched_getaffinity(0))
    core = min(allowed)

    def look(runner: Runner) -> dict[str, set[int]]:
        writer = runner.writer
        assert writer is not None and writer.encoder_id is not None
        return {
            "encoder": set(os.sched_getaffinity(writer.encoder_id)),
            "writer": set(os.sched_getaffinity(writer._thread.native_id or -1)),
        }

    _, seen = _at_scan_5(core, look, StateStore(tmp_path / "s.sqlite"))
    assert seen == {"encoder": {core}, "writer": allowed - {core}}
