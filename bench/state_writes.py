"""How much the state file is written for the drill demo (run as
``python bench/state_writes.py``; see bench/README.md).

The drill demo of the README (``examples/drill/drill.s7g`` with ``demo_plant.py``) runs for
``--seconds`` (60) of plant time at a 10 ms cycle, with its state file written as by
``s7graph run``: each scan's changes staged in the scan thread (``StateStore.stage``) and
committed by the writer thread (``engine/writer.py``). Two workloads:

* ``demo``: the demo as it is — it faults on its second piece and waits, red, for an
  operator who never comes;
* ``working``: the same with an operator who acknowledges every 9 s (ACK_EF), so the drill
  goes on working piece after piece (about 30 state changes per piece).

The virtual clock makes a 60 s run take a few seconds, so each workload is repeated
(``--repeat``) and the figures are min / median / max. Bytes written are those the process
passed to ``write()`` (``/proc/self/io`` ``wchar``) during the run, extrapolated to an
hour; the target is at most 50 MB an hour. Also printed: commits, rows, and the time
``stage`` takes in the scan thread — scan after scan, and in a shorter run
(``--cold-seconds``, 10) with the scan thread asleep for 9 ms after each scan as in a real
10 ms cycle, where it finds its caches cold (on this machine about five times the
back-to-back time). ``--real`` instead runs ``s7graph run`` for ``--seconds`` of real time
and reads the child's ``/proc/PID/io``.

``--synchronous FULL,NORMAL`` (the default) runs each workload with the state file's
``PRAGMA synchronous`` at each value: FULL (what ``s7graph run`` uses: the write-ahead log
synced at every commit, so an answered command survives a power cut) against NORMAL (in
WAL mode not durable across a power cut). Printed per value: the commit time (one
transaction, ``StateStore.write``, in the writer thread: what a command's reply waits
for, never the scan) as min / median / max over all commits, and the wall time of the
run. ``--dir`` puts the files on the disk to measure (default: the system's temporary
directory; a tmpfs there makes every sync free). ``--replies N`` instead times N commands
(``halt`` on and off) sent over a real zenoh bus to the drill chart run by a real
``Runner`` on the system clock at a 10 ms cycle, each answered once its commit is durable:
the round trip a sender sees, per ``synchronous`` value.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from s7graph.engine.clock import VirtualClock
from s7graph.engine.persistence import SYNCHRONOUS, StateStore
from s7graph.engine.writer import StoreWriter
from s7graph.web.harness.persist import persist_messages
from s7graph.web.harness.plant import load_plant
from s7graph.web.harness.session import ChartSession

ROOT = Path(__file__).resolve().parent.parent
DRILL = ROOT / "examples" / "drill"
CYCLE_MS = 10
TARGET_MB_H = 50.0
NAP_S = 0.009  # the idle part of a 10 ms cycle


def _io(pid: str = "self") -> dict[str, int]:
    out: dict[str, int] = {}
    for line in Path(f"/proc/{pid}/io").read_text().splitlines():
        key, _, value = line.partition(":")
        out[key] = int(value)
    return out


def simulate(
    seconds: float,
    *,
    ack_every_ms: int | None,
    nap_s: float = 0.0,
    synchronous: str = SYNCHRONOUS,
    where: str | None = None,
) -> dict[str, float]:
    """One run on the virtual clock; bytes written, commits, rows, stage and commit times;
    ``nap_s``: the scan thread sleeps that long (real time) after each scan's commit."""
    with tempfile.TemporaryDirectory(dir=where) as tmp:
        clock = VirtualClock()
        session = ChartSession.load(DRILL / "drill.s7g", DRILL / "symbols.txt", clock)
        plant = load_plant(DRILL / "demo_plant.py")
        store = StateStore(Path(tmp) / "drill.sqlite", synchronous=synchronous)
        persist_messages(store, session.cpu)
        commit_ns = _timed_writes(store)
        cpu = session.cpu
        cpu.start("warm")
        store.save(cpu, clean=False)
        writer = StoreWriter(store)
        commit_ns.clear()  # the runs' commits, not the first full save
        t0 = time.perf_counter()
        before = _io()
        stage_ns: list[int] = []
        cycles = int(seconds * 1000 / CYCLE_MS)
        for k in range(cycles):
            t_ms = k * CYCLE_MS
            if ack_every_ms:
                session.set("ACK_EF", t_ms % ack_every_ms < 100 and t_ms >= ack_every_ms)
            cpu.scan()
            plant.cycle(session, t_ms, CYCLE_MS)
            started = time.perf_counter_ns()
            batch = store.stage(cpu, upto=k + 1)
            stage_ns.append(time.perf_counter_ns() - started)
            writer.submit(batch, k + 1)
            if batch is not None:
                writer.flush(5.0)  # as in real time: committed before the next scan, one each
            if nap_s:
                time.sleep(nap_s)
            clock.advance(CYCLE_MS)
        writer.close()
        after = _io()
        wall_s = time.perf_counter() - t0
        store.close()
        written = after["wchar"] - before["wchar"]
        commits = sorted(commit_ns) or [0]
        return {
            "commit_min_ms": commits[0] / 1e6,
            "commit_median_ms": statistics.median(commits) / 1e6,
            "commit_max_ms": commits[-1] / 1e6,
            "wall_s": wall_s,
            "mb_h": written * 3600 / seconds / 1e6,
            "commits": writer.commits,
            "rows": writer.rows,
            "stage_median_us": statistics.median(stage_ns) / 1000,
            "stage_max_us": max(stage_ns) / 1000,
            "pieces": int(session.get("pieces")),
        }


def _timed_writes(store: StateStore) -> list[int]:
    """Time every ``store.write`` (one transaction and its commit) from now on."""
    times: list[int] = []
    write = store.write

    def timed(batch: Any) -> None:
        started = time.perf_counter_ns()
        write(batch)
        if batch:
            times.append(time.perf_counter_ns() - started)

    store.write = timed  # type: ignore[method-assign]
    return times


def real(seconds: float) -> dict[str, float]:
    """``s7graph run`` of the demo for ``seconds`` of real time; the child's bytes written."""
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [
            sys.executable,
            "-m",
            "s7graph",
            "run",
            str(DRILL / "drill.s7g"),
            "--plant",
            str(DRILL / "demo_plant.py"),
            "--symbols",
            str(DRILL / "symbols.txt"),
            "--state",
            str(Path(tmp) / "drill.sqlite"),
            "--duration-s",
            str(seconds),
        ]
        proc = subprocess.Popen(cmd, cwd=ROOT, stderr=subprocess.DEVNULL)
        pid = str(proc.pid)
        first: dict[str, int] | None = None
        last: dict[str, int] = {}
        t0 = time.monotonic()
        while proc.poll() is None:
            try:
                last = _io(pid)
            except OSError:
                break
            if first is None and time.monotonic() - t0 > 3:  # after imports and startup
                first, t_first = last, time.monotonic()
            time.sleep(0.2)
        proc.wait()
        if first is None or not last:
            raise SystemExit("the run ended too early to measure")
        span = time.monotonic() - t_first
        return {"mb_h": (last["wchar"] - first["wchar"]) * 3600 / span / 1e6, "span_s": span}


def replies(n: int, synchronous: str, where: str | None) -> list[float]:
    """Round trips (ms) of ``n`` commands answered once durable, as ``s7graph run`` does."""
    from s7graph.engine.clock import SystemClock
    from s7graph.engine.runner import Runner
    from s7graph.sfb.alarms import message_list
    from s7graph.web.bus.client import BusClient
    from s7graph.web.bus.gate import cpu_gate
    from s7graph.web.bus.live import LiveGraph
    from s7graph.web.bus.protocol import Command
    from s7graph.web.bus.publisher import BusPublisher
    from s7graph.web.bus.session import open_session

    fb = "Seq_drill"
    with tempfile.TemporaryDirectory(dir=where) as tmp:
        session = ChartSession.load(DRILL / "drill.s7g", DRILL / "symbols.txt", SystemClock())
        store = StateStore(Path(tmp) / "drill.sqlite", synchronous=synchronous)
        live = LiveGraph(session.graph, read=session.get, messages=message_list(session.cpu))
        endpoint = f"unixsock-stream/{tmp}/bus.sock"
        cpu_bus = open_session(listen=[endpoint])
        publisher = BusPublisher(cpu_bus, "cpu1", {fb: live.layout}, gate=cpu_gate(None, store))
        runner: Runner

        def on_record(record: Any) -> None:
            publisher.publish(fb, live.update(record))
            publisher.apply_commands(live.apply, cycle=record.cycle, durable=runner)

        runner = Runner(session.cpu, cycle_ms=CYCLE_MS, store=store, on_record=on_record)
        view_bus = open_session(connect=[endpoint])
        client = BusClient(view_bus, "cpu1")
        times: list[float] = []
        try:
            runner.startup("warm")
            runner.start_thread()
            token = client.login("bench").token
            for k in range(n):
                command = Command(
                    op="halt", fb=fb, user="bench", token=token, args={"on": k % 2 == 0}
                )
                started = time.perf_counter()
                reply = client.send(command)
                times.append((time.perf_counter() - started) * 1000)
                if not reply.applied:
                    raise SystemExit(f"refused: {reply.reason}")
        finally:
            runner.request_stop()
            runner.shutdown()
            client.close()
            publisher.close()
            view_bus.close()  # type: ignore[no-untyped-call]
            cpu_bus.close()  # type: ignore[no-untyped-call]
            store.close()
        return times


def _row(name: str, runs: list[dict[str, float]], key: str, unit: str, fmt: str = ".1f") -> str:
    values = sorted(r[key] for r in runs)
    lo, mid, hi = values[0], statistics.median(values), values[-1]
    return f"  {name:<22} {lo:{fmt}} / {mid:{fmt}} / {hi:{fmt}} {unit}"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument(
        "--cold-seconds",
        type=float,
        default=10.0,
        help="the run with a 9 ms sleep after each scan (0: none)",
    )
    ap.add_argument("--real", action="store_true", help="run s7graph run in real time instead")
    ap.add_argument(
        "--synchronous",
        default="FULL,NORMAL",
        help="PRAGMA synchronous values to compare, comma-separated",
    )
    ap.add_argument("--dir", default=None, help="where the state files go (the disk measured)")
    ap.add_argument(
        "--replies", type=int, default=0, help="time this many durable command replies instead"
    )
    args = ap.parse_args()
    if args.replies:
        print(
            f"{args.replies} commands answered once durable, drill chart at {CYCLE_MS} ms; "
            f"min / median / max of {args.repeat} runs"
        )
        for sync in args.synchronous.split(","):
            runs = []
            for _ in range(args.repeat):
                times = sorted(replies(args.replies, sync, args.dir))
                runs.append(
                    {
                        "median": statistics.median(times),
                        "max": times[-1],
                        "p90": times[int(0.9 * (len(times) - 1))],
                    }
                )
            print(f"synchronous={sync}:")
            for key in ("median", "p90", "max"):
                print(_row(f"reply, {key}", runs, key, "ms", ".1f"))
        return 0
    if args.real:
        got = real(args.seconds)
        print(
            f"s7graph run, drill demo, {got['span_s']:.0f} s real time: "
            f"{got['mb_h']:.2f} MB/hour written (target <= {TARGET_MB_H:.0f})"
        )
        return 0 if got["mb_h"] <= TARGET_MB_H else 1
    worst = 0.0
    print(
        f"drill demo, {args.seconds:.0f} s at {CYCLE_MS} ms, state file as in s7graph run; "
        f"min / median / max of {args.repeat} runs"
    )
    for name, ack in (("demo", None), ("working", 9000)):
        for sync in args.synchronous.split(","):
            runs = [
                simulate(args.seconds, ack_every_ms=ack, synchronous=sync, where=args.dir)
                for _ in range(args.repeat)
            ]
            print(f"{name} ({int(runs[0]['pieces'])} pieces), synchronous={sync}:")
            print(_row("written", runs, "mb_h", f"MB/hour (target <= {TARGET_MB_H:.0f})", ".2f"))
            print(_row("commits", runs, "commits", "", ".0f"))
            print(_row("rows", runs, "rows", "", ".0f"))
            print(_row("stage, median", runs, "stage_median_us", "µs per scan"))
            print(_row("stage, max", runs, "stage_max_us", "µs per scan"))
            print(_row("commit, min", runs, "commit_min_ms", "ms", ".2f"))
            print(_row("commit, median", runs, "commit_median_ms", "ms", ".2f"))
            print(_row("commit, max", runs, "commit_max_ms", "ms", ".2f"))
            print(_row("run, wall time", runs, "wall_s", "s", ".2f"))
            worst = max(worst, max(r["mb_h"] for r in runs))
    if args.cold_seconds > 0:
        cold = simulate(args.cold_seconds, ack_every_ms=None, nap_s=NAP_S, where=args.dir)
        print(
            f"demo, {args.cold_seconds:.0f} s, the scan thread asleep {NAP_S * 1000:.0f} ms "
            f"after each scan (caches cold, as in a real cycle):"
        )
        print(f"  {'stage, median':<22} {cold['stage_median_us']:.1f} µs per scan (one run)")
        print(f"  {'stage, max':<22} {cold['stage_max_us']:.1f} µs per scan")
    return 0 if worst <= TARGET_MB_H else 1


if __name__ == "__main__":
    sys.exit(main())
