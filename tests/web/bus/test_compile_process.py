"""Compiling never holds the scan: a chart sent to the CPU is parsed, validated and
compiled in the compiler's own warm process (``web.bus.compiler``), with a size limit
checked before parsing and a time limit that kills and replaces a runaway compile; the
CPU's process only loads the finished chart, in small pieces, and swaps it at a scan
boundary. The CPU is ``s7graph run`` of the drill demo as a real process on a real bus;
its own cycle statistics (``s7graph status``) say whether any scan ran long."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

from bench.big_charts import contact_chain, huge_chart
from s7graph.engine.cores import allowed_cpus, kept_free, others
from s7graph.sequencer.change.base import MAX_SOURCE
from s7graph.web.bus.client import BusClient
from s7graph.web.bus.compiler import Compiled, Compiler, CompileRefused, Summary
from s7graph.web.bus.pieces import dumps_in_pieces, loads_in_pieces
from s7graph.web.bus.protocol import Command, CommandReply
from s7graph.web.harness.session import compile_text
from tests.paths import ROOT
from tests.web.helpers import cpu_process, wait_until

pytestmark = pytest.mark.timeout(300)
DRILL = ROOT / "examples" / "drill"
FB = "Seq_drill"
CYCLE_LIMIT_MS = 150.0  # the CPU's maximum cycle time (engine.cpu, the watchdog)
CORE = ["--core", "0"] if len(allowed_cpus()) >= 2 else []
"""The scan's processor named, not the default last one (``--core auto``) that other real-time
CPUs on a shared machine keep too; the compiler runs on the others."""


@contextmanager
def drill(tmp_path: Path) -> Iterator[tuple[subprocess.Popen[str], BusClient, str]]:
    """``s7graph run`` of a copy of the drill demo on a unix socket; a client logged in."""
    for name in ("drill.s7g", "symbols.txt"):
        shutil.copy(DRILL / name, tmp_path / name)
    args = [
        str(tmp_path / "drill.s7g"),
        "--symbols",
        str(tmp_path / "symbols.txt"),
        "--plant",
        str(DRILL / "demo_plant.py"),
        "--state",
        str(tmp_path / "state.sqlite"),
        "--duration-s",
        "280",
        *CORE,
    ]
    with cpu_process(tmp_path, args, fb=FB, user="tess") as running:
        yield running


def test_a_huge_chart_and_a_5000_contact_chain_compile_without_any_scan_over_the_limit(
    tmp_path: Path,
) -> None:
    with drill(tmp_path) as (proc, client, token):

        def send(**args: object) -> CommandReply:
            command = Command(op="download", fb=FB, user="tess", token=token, args=args)  # type: ignore[arg-type]
            return client.send(command, timeout=240)

        huge, chain = huge_chart(), contact_chain()
        preview = send(source=huge, preview=True)  # compiled, or refused by the time limit
        assert preview.applied or "time limit" in preview.reason, preview.reason
        assert send(source=chain, preview=True).applied
        chained = send(source=chain, removed="init")
        assert chained.applied, chained.reason
        layout = client.chart(FB)
        assert layout is not None and layout.version == 2 and len(layout.steps) == 2
        big = send(source=huge, removed="init")
        if big.applied:
            assert (tmp_path / "drill.s7g").read_text(encoding="utf-8") == huge
            # 1,000 steps (S7-GRAPH allows 250): its layout, with every step's action table,
            # is over the bus's message limit; it comes in parts, whole
            whole = client.chart(FB)
            assert whole is not None and whole.version == 3 and len(whole.steps) == 1000
            assert all(s.actions for s in whole.steps)
        else:  # a machine too busy to compile it in time: refused, the chain runs on
            assert "time limit" in big.reason, big.reason
            assert (tmp_path / "drill.s7g").read_text(encoding="utf-8") == chain
        count = client.status()
        assert count is not None
        assert wait_until(lambda: (s := client.status()) is not None and s.cycle > count.cycle)
        status = client.status()
        assert status is not None and status.state == "RUN" and status.stats is not None
        assert status.stats.max_ms < CYCLE_LIMIT_MS, status.stats  # not one scan held
        assert proc.poll() is None


def test_the_time_limit_kills_a_runaway_compile_and_a_fresh_compiler_takes_the_next() -> None:
    compiler = Compiler()
    running = (DRILL / "drill.s7g").read_text(encoding="utf-8")
    symbols = (DRILL / "symbols.txt").read_text(encoding="utf-8")
    try:
        compiler.check(running, "drill.s7g")  # started and warm (a loaded machine: > 0.3 s)
        first = compiler.pid
        compiler.time_limit_s = 0.3  # the huge chart takes seconds
        with pytest.raises(CompileRefused) as refused:
            compiler.compile(
                huge_chart(),
                "drill.s7g",
                symbols=symbols,
                running=running,
                active=(1,),
                fb=FB,
                version=2,
            )
        assert "time limit" in refused.value.reason and "0.3 s" in refused.value.reason
        assert first is not None and not _alive(first)
        assert compiler.started == 2  # replaced at once, warm for the next request
        edited = running.replace('"Ready"', '"Ready to drill"')
        compiler.time_limit_s = 60.0
        done = compiler.compile(
            edited, "drill.s7g", symbols=symbols, running=running, active=(1,), fb=FB, version=2
        )
        assert isinstance(done, Compiled) and done.cc.step_names[0] == "Ready to drill"
        assert done.live.layout.version == 2 and done.summary.count == 1
    finally:
        compiler.close()


def test_a_compiler_found_gone_before_a_request_is_replaced_and_the_request_answered() -> None:
    compiler = Compiler()
    running = (DRILL / "drill.s7g").read_text(encoding="utf-8")
    symbols = (DRILL / "symbols.txt").read_text(encoding="utf-8")
    edited = running.replace('"Ready"', '"Ready to drill"')
    try:
        compiler.check(running, "drill.s7g")
        proc = compiler._proc
        assert proc is not None and proc.stdin is not None
        proc.stdin.close()  # the pipe closed under the idle child ("write to closed file")
        done = compiler.compile(
            edited, "drill.s7g", symbols=symbols, running=running, active=(1,), fb=FB, version=2
        )
        assert isinstance(done, Compiled) and done.cc.step_names[0] == "Ready to drill"
        assert compiler.started == 2 and not _alive(proc.pid)
        proc = compiler._proc
        assert proc is not None
        proc.kill()  # gone while idle
        proc.wait()
        compiler.check(edited, "drill.s7g")
        assert compiler.started == 3
    finally:
        compiler.close()


def test_a_compiler_ending_during_a_request_refuses_it_and_does_not_send_it_again() -> None:
    compiler = Compiler(time_limit_s=600)
    result: list[BaseException] = []

    def compile_huge() -> None:
        try:
            compiler.compile(
                huge_chart(), "d.s7g", symbols="", running="", active=(), fb=FB, version=2
            )
        except CompileRefused as exc:
            result.append(exc)

    try:
        compiler.start()
        pid = compiler.pid
        assert pid is not None
        worker = threading.Thread(target=compile_huge)
        worker.start()
        assert wait_until(lambda: _busy(pid), 90)  # it has the request: compiling
        os.kill(pid, signal.SIGKILL)
        worker.join(60)
        assert len(result) == 1 and isinstance(result[0], CompileRefused)
        assert "the compiler process ended" in result[0].reason
        assert compiler.started == 2  # replaced, warm for the next; the request not resent
    finally:
        compiler.close()


def test_the_size_limit_refuses_before_anything_is_parsed() -> None:
    compiler = Compiler()
    too_big = "(*" + "x" * MAX_SOURCE + "*)"
    try:
        with pytest.raises(CompileRefused) as refused:
            compiler.compile(
                too_big, "big.s7g", symbols="", running="", active=(), fb=FB, version=2
            )
        assert f"at most {MAX_SOURCE:,}" in refused.value.reason
        assert "size limit" in refused.value.reason
        with pytest.raises(CompileRefused, match="size limit"):
            compiler.check(too_big, "big.s7g")
        assert compiler.started == 0  # no process ever saw it
    finally:
        compiler.close()


def test_a_refused_chart_comes_back_with_its_diagnostics_and_a_preview_with_its_summary() -> None:
    compiler = Compiler()
    running = (DRILL / "drill.s7g").read_text(encoding="utf-8")
    symbols = (DRILL / "symbols.txt").read_text(encoding="utf-8")
    try:
        with pytest.raises(CompileRefused) as refused:
            compiler.compile(
                running.replace("S1 S", "S1 Q"),
                "drill.s7g",
                symbols=symbols,
                running=running,
                active=(1,),
                fb=FB,
                version=2,
            )
        assert "does not parse" in refused.value.reason
        assert any("drill.s7g:" in line for line in refused.value.lines)
        summary = compiler.compile(
            contact_chain(),
            "drill.s7g",
            symbols=symbols,
            running=running,
            active=(1,),
            fb=FB,
            version=2,
            preview=True,
        )
        assert isinstance(summary, Summary) and summary.count > 0
    finally:
        compiler.close()


@pytest.mark.skipif(len(allowed_cpus()) < 2, reason="one processor: none can be kept")
def test_the_compiler_runs_off_the_processor_kept_for_the_scan_at_the_normal_policy() -> None:
    kept = max(allowed_cpus())
    with kept_free(kept):
        compiler = Compiler()
    try:
        compiler.check((DRILL / "drill.s7g").read_text(encoding="utf-8"), "drill.s7g")
        pid = compiler.pid
        assert pid is not None
        assert os.sched_getaffinity(pid) == others(kept) and kept not in os.sched_getaffinity(pid)
        assert os.sched_getscheduler(pid) == os.SCHED_OTHER
    finally:
        compiler.close()
    assert pid is not None and not _alive(pid)


def test_the_compiler_process_ends_with_the_cpus_even_in_the_middle_of_a_compile(
    tmp_path: Path,
) -> None:
    script = tmp_path / "cpu.py"
    script.write_text(
        "from bench.big_charts import huge_chart\n"
        "from s7graph.web.bus.compiler import Compiler\n"
        "c = Compiler(time_limit_s=600)\n"
        "c.start()\n"
        "print(c.pid, flush=True)\n"
        "c.compile(huge_chart(), 'd.s7g', symbols='', running=huge_chart(), active=(),\n"
        "          fb='Seq_drill', version=2)\n"
    )
    cpu = subprocess.Popen(
        [sys.executable, str(script)],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        text=True,
        env={
            **os.environ,
            "PYTHONPATH": os.pathsep.join([os.environ.get("PYTHONPATH", ""), str(ROOT)]),
        },
    )
    assert cpu.stdout is not None
    child = int(cpu.stdout.readline())
    assert wait_until(lambda: _busy(child), 90)  # compiling
    cpu.kill()
    cpu.wait(30)
    cpu.stdout.close()
    assert wait_until(lambda: not _alive(child), 2)  # not when its compile is done


def test_a_chart_pickled_in_small_pieces_comes_back_equal() -> None:
    cc, _ = compile_text(contact_chain(200), "chain.s7g")
    pieces = dumps_in_pieces(cc.chart)
    assert len(pieces) == 1 + len(cc.chart.all_steps()) + len(cc.chart.all_transitions())
    assert loads_in_pieces(pieces) == cc.chart


def _busy(pid: int) -> bool:
    """``pid`` has used 2 s of processor time (it imported, and compiles: 8 s or more)."""
    try:
        with open(f"/proc/{pid}/stat", encoding="ascii") as f:
            fields = f.read().rsplit(")", 1)[1].split()
    except OSError:
        return False
    return int(fields[11]) + int(fields[12]) > 2 * os.sysconf("SC_CLK_TCK")


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    with open(f"/proc/{pid}/stat", encoding="ascii") as f:  # a zombie is gone too
        return f.read().rsplit(")", 1)[1].split()[0] != "Z"


def test_a_request_that_breaks_the_compiler_is_refused_in_words(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A defect of ours in the compiler process: an internal error, which request, what it
    said."""
    from s7graph.web.bus import compile_jobs

    def broken(*args: object, **kwargs: object) -> None:
        raise KeyError("x")

    monkeypatch.setattr(compile_jobs, "_summary", broken)
    answer, _ = compile_jobs.answer({"op": "summary"})
    assert answer == {
        "refused": "summary refused: an internal error in the compiler while answering "
        "summary: 'x' (please report it)"
    }
