"""The processor kept for the scan (engine/cores.py, engine/runner.py): which one ``--core``
chooses, and while the loop runs the scan thread on it (with the state writer's encoder,
which works while the scan sleeps) and the process's other threads on the rest, every
thread given all of them back when the loop ends."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
from collections.abc import Callable
from pathlib import Path

import pytest

from s7graph.engine import CallContext, Cpu, SystemClock, ob
from s7graph.engine.cores import CoreClaims, kept_free, machine_claims, others, scan_core
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


HOLDER = """
import sys
from pathlib import Path
from s7graph.engine.cores import CoreClaims
claims = CoreClaims(Path(sys.argv[1]))
if not all(claims.take(int(c)) for c in sys.argv[2:]):
    sys.exit(3)
print("held", flush=True)
sys.stdin.read()
"""


def _holder(folder: Path, *cores: int) -> subprocess.Popen[str]:
    """Another process (another CPU) that claims ``cores`` in ``folder`` and keeps them."""
    proc = subprocess.Popen(
        [sys.executable, "-c", HOLDER, str(folder), *map(str, cores)],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    assert proc.stdout is not None and proc.stdout.readline() == "held\n"
    return proc


def test_auto_leaves_the_processor_another_cpu_keeps_until_that_process_is_killed(
    tmp_path: Path,
) -> None:
    other = _holder(tmp_path, 3)
    try:
        claims = CoreClaims(tmp_path)
        assert scan_core("auto", realtime=True, allowed={0, 1, 2, 3}, claims=claims) == 2
        assert claims.holder(3) == other.pid and claims.holder(2) == os.getpid()
        assert scan_core("auto", realtime=True, allowed={0, 1, 2, 3}, claims=claims) == 2
    finally:
        other.send_signal(signal.SIGKILL)
        other.wait()
    later = CoreClaims(tmp_path)  # a CPU started after the other one was killed
    assert scan_core("auto", realtime=True, allowed={0, 1, 2, 3}, claims=later) == 3


def test_auto_keeps_none_when_other_cpus_keep_every_processor_but_the_first(
    tmp_path: Path,
) -> None:
    other = _holder(tmp_path, 1)
    try:
        assert scan_core("auto", realtime=True, allowed=TWO, claims=CoreClaims(tmp_path)) is None
        mine = CoreClaims(tmp_path)
        assert scan_core(1, realtime=True, allowed=TWO, claims=mine) == 1  # asked for: taken
        mine.release(1)
    finally:
        other.communicate("")
    assert other.returncode == 0


def test_a_claim_let_go_is_free_for_the_next_cpu(tmp_path: Path) -> None:
    first, second = CoreClaims(tmp_path), CoreClaims(tmp_path)
    assert first.take(1) and first.take(1)  # held already: still granted
    other = subprocess.run([sys.executable, "-c", HOLDER, str(tmp_path), "1"], input="")
    assert other.returncode == 3  # another process: refused
    first.release(1)
    assert second.take(1)
    second.release(1)


def test_a_run_lets_go_of_the_processor_it_claimed() -> None:
    core = max(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else 0
    claims = machine_claims()
    if not claims.take(core):
        pytest.skip(f"another CPU on this machine keeps processor {core}")
    with kept_free(core):
        pass
    assert core not in claims.held()


def test_the_others_are_the_rest_or_the_only_one_there_is() -> None:
    assert others(1, {0, 1, 2}) == {0, 2}
    assert others(0, {0}) == {0}


def test_the_others_leave_out_what_other_cpus_keep_or_else_share_the_own_core() -> None:
    assert others(2, {0, 1, 2}, kept={1}) == {0}
    assert others(0, {0, 1}, kept={1}) == {0}  # beside its own scan, not another CPU's
    assert others(0, {0, 1, 2}, kept={1, 2}) == {0}


def test_the_processors_other_cpus_keep_are_read_from_the_kernels_locks(tmp_path: Path) -> None:
    other = _holder(tmp_path, 1, 3)
    mine = CoreClaims(tmp_path)
    try:
        assert mine.take(2)
        if not Path("/proc/locks").exists():
            pytest.skip("no /proc/locks here")
        assert mine.kept_elsewhere({0, 1, 2, 3}) == {1, 3}  # not its own, not a free one
    finally:
        other.send_signal(signal.SIGKILL)
        other.wait()
    assert mine.kept_elsewhere({0, 1, 2, 3}) == set()  # the kernel let go with the process
    assert mine.take(1)  # and so may this CPU
    mine.release(1)
    mine.release(2)


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
    fifth scan; the runner (shut down) and what was seen. Skipped while another CPU of
    this machine keeps a processor: this one then keeps off it, by design
    (``engine.cores``), and the processors seen are not the test's to say."""
    elsewhere = machine_claims().kept_elsewhere(set(os.sched_getaffinity(0)))
    if elsewhere:
        pytest.skip(f"another CPU on this machine keeps processor(s) {sorted(elsewhere)}")
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


def test_a_thread_started_while_the_others_are_pinned_is_pinned_off_the_scans_core_too(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A thread inherits its starter's processors: one started by a thread not yet pinned
    would run everywhere. The threads are listed again until none is new."""
    from s7graph.engine import runner

    listings = iter([[11], [11, 12], [11, 12], [11, 12]])  # 12 appears while 11 is pinned
    pinned: dict[int, set[int]] = {}

    def pin(cpus: set[int], tid: int = 0) -> bool:
        pinned[tid] = set(cpus)
        return True

    monkeypatch.setattr(runner, "_other_threads", lambda: next(listings))
    monkeypatch.setattr(runner, "pin", pin)
    assert runner.keep_core(1, TWO)
    assert pinned == {11: {0}, 12: {0}, 0: {1}}  # both off core 1, the scan thread on it
