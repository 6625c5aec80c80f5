"""Jitter benchmark: how evenly ``s7graph run --web`` scans at a 10 ms cycle while pages load
and commands flood the bus — the view in its own process (as ``run --web`` runs it) and, for
comparison, in the CPU's process (run as ``python bench/jitter.py``; see bench/README.md).

Workloads: ``drill``, the README's demo (the drill chart with ``demo_plant.py``), and
``scan200``, the 200-sequencer workload of ``bench/scan.py`` (25 GRAPH FBs of 8 sequencers
in one CPU, the view showing the first). Each runs in a CPU process of its own — the real
``run_chart`` of ``s7graph run CHART --web`` with a state file, on the system clock — that
stamps the start and end of every scan; this process measures it ``--seconds`` under

- ``idle``: nothing but the view, no page open;
- ``pages``: three headless Chromium pages (Playwright driving /usr/bin/chromium) opening
  the view, and closing, every 5 s;
- ``flood``: a flood of commands on the bus — four clients sending one after the other as
  fast as they are answered, and a fire hose of 1000 queries a second that waits for
  nothing (one in ten unreadable);

and prints, per workload, view and load, the cycle (start to start of two scans) at
p50 / p99 / p99.9 / max, the scans the runner found overrunning their 10 ms, and the scan
time (p50 / p99). Target: the view in its own process, p99.9 of the cycle at most
cycle + 2 ms and no overrun under ``pages`` and ``flood``.
"""

from __future__ import annotations

import argparse
import functools
import json
import os
import re
import resource
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

BENCH = Path(__file__).resolve().parent
ROOT = BENCH.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(1, str(BENCH))

from figures import free_port, serves, spread  # noqa: E402

DRILL = ROOT / "examples" / "drill"
CYCLE_MS = 10.0
WORKLOADS = ("drill", "scan200")
VIEWS = ("separate", "inline", "normal")
"""The view in its own process (``run --web``), in the CPU's process (``view_in_process``),
and in its own process with the scan thread at the normal priority (``--rt-priority 0``)."""
LOADS = ("idle", "pages", "flood")
PAGES = 3
PAGE_LIFE_S = 5.0
FLOOD_SENDERS = 4
FIREHOSE_PER_S = 1000
CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--enable-unsafe-swiftshader",
                 "--use-angle=swiftshader"]  # fmt: skip
RESULT = "JITTER "


# ---------------------------------------------------------------------------- the CPU process


def worker(workload: str, view: str, endpoint: str, port: int, state: Path) -> int:
    """Run ``workload`` as ``s7graph run --web`` does, stamping every scan; ``start`` and
    ``end`` lines on stdin mark the measured window, ``end`` also stops the run. Prints the
    window's figures as one ``JITTER {json}`` line."""
    from s7graph.engine.cpu import Cpu
    from s7graph.engine.runner import RT_PRIORITY, Runner
    from s7graph.web.cli.net import NetOptions
    from s7graph.web.cli.run_chart import run_chart

    starts: list[int] = []
    ends: list[int] = []
    runners: list[Runner] = []
    scan = Cpu.scan
    run = Runner.run

    def stamped_scan(self: Cpu) -> Any:
        starts.append(time.perf_counter_ns())
        record = scan(self)
        ends.append(time.perf_counter_ns())
        return record

    def kept_run(self: Runner, **kw: Any) -> None:
        runners.append(self)
        run(self, **kw)

    Cpu.scan = stamped_scan  # type: ignore[method-assign]
    Runner.run = kept_run  # type: ignore[method-assign]
    marks: dict[str, tuple[int, int]] = {}

    faults: dict[str, int] = {}

    def control() -> None:
        for line in sys.stdin:
            word = line.strip()
            overruns = runners[0].overruns if runners else 0
            marks[word] = (len(ends), overruns)
            faults[word] = resource.getrusage(resource.RUSAGE_SELF).ru_majflt
            if word == "end" and runners:
                runners[0].request_stop()

    threading.Thread(target=control, daemon=True).start()
    net = NetOptions(listen=[endpoint])
    common: dict[str, Any] = {
        "state": state, "cycle_ms": CYCLE_MS, "web": True, "port": port, "net": net,
        "view_in_process": view == "inline",
        "rt_priority": None if view == "normal" else RT_PRIORITY,
    }  # fmt: skip
    if workload == "drill":
        rc = run_chart(DRILL / "drill.s7g", plant=DRILL / "demo_plant.py",
                       symbols=DRILL / "symbols.txt", **common)  # fmt: skip
    else:
        rc = run_chart(Path("scan200.s7g"), session=_scan200_session(), **common)
    a, over_a = marks.get("start", (0, 0))
    b, over_b = marks.get("end", (len(ends), runners[0].overruns if runners else 0))
    cycles = [starts[i + 1] - starts[i] for i in range(a, min(b, len(starts)) - 1)]
    scans = [ends[i] - starts[i] for i in range(a, b)]
    stopped = runners[0].stopped if runners else "never ran"
    majflt = faults.get("end", 0) - faults.get("start", 0)
    result = {"rc": rc, "cycles": cycles, "scans": scans, "overruns": over_b - over_a,
              "stopped": stopped, "majflt": majflt}  # fmt: skip
    print(RESULT + json.dumps(result), flush=True)
    return 0


def _scan200_session() -> Any:
    """bench/scan.py's workload in one CPU: 25 FBs of 8 sequencers, the first shown."""
    from scan import N_SEQUENCERS, chart_source

    from s7graph.engine.clock import SystemClock
    from s7graph.engine.symbols import SymbolTable
    from s7graph.sequencer.compile import compile_chart
    from s7graph.sequencer.parse import parse_chart
    from s7graph.web.harness.session import ChartSession

    per_fb = 8
    charts = [
        compile_chart(parse_chart(chart_source(f + 1, f * per_fb, per_fb), f"<bench FB{f + 1}>"))
        for f in range(N_SEQUENCERS // per_fb)
    ]
    return ChartSession(charts[0], SymbolTable(), SystemClock(), beside=charts[1:])


# ---------------------------------------------------------------------------- the loads


@contextmanager
def no_load(url: str, endpoint: str, fb: str) -> Iterator[Callable[[], str]]:
    yield lambda: ""


@contextmanager
def pages(url: str, endpoint: str, fb: str) -> Iterator[Callable[[], str]]:
    """Three headless pages opening the view and closing, every ``PAGE_LIFE_S``, in a thread
    (Playwright's sync API stays in the thread that started it)."""
    stop = threading.Event()
    opened = [0]
    failed: list[str] = []

    def churn() -> None:
        from playwright.sync_api import sync_playwright

        with sync_playwright() as p:
            browser = p.chromium.launch(
                executable_path=CHROMIUM, headless=True, args=CHROMIUM_ARGS
            )
            try:
                while not stop.is_set():
                    born = time.monotonic()
                    tabs = []
                    for _ in range(PAGES):
                        page = browser.new_page(viewport={"width": 1280, "height": 800})
                        try:
                            page.goto(url, timeout=20_000)
                            opened[0] += 1
                        except Exception as exc:  # a page that does not load is counted
                            failed.append(type(exc).__name__)
                        tabs.append(page)
                    stop.wait(max(0.0, PAGE_LIFE_S - (time.monotonic() - born)))
                    for page in tabs:
                        page.close()
            finally:
                browser.close()

    thread = threading.Thread(target=churn, daemon=True)
    thread.start()
    try:
        yield lambda: f"{opened[0]} pages opened, {len(failed)} failed"
    finally:
        stop.set()
        thread.join(60)


@contextmanager
def flood(url: str, endpoint: str, fb: str) -> Iterator[Callable[[], str]]:
    """Four clients commanding back to back, and a fire hose of queries answered or not."""
    import zenoh

    from s7graph.web.bus.protocol import Command, encode
    from s7graph.web.bus.zenoh_bus import BusClient, keys, open_session

    stop = threading.Event()
    counts = {"answered": 0, "applied": 0, "fired": 0, "replies": 0}
    lock = threading.Lock()
    session = open_session(connect=[endpoint])
    client = BusClient(session, "cpu1")
    login = client.login("flood")
    command = Command(op="halt", fb=fb, user="flood", token=login.token, args={"on": False})
    payload = encode(command)

    refusals: dict[str, int] = {}

    def sender() -> None:
        while not stop.is_set():
            reply = client.send(command)
            with lock:
                counts["answered"] += 1
                counts["applied"] += reply.applied
                if not reply.applied:
                    why = reply.reason.split(":")[0][:40]
                    refusals[why] = refusals.get(why, 0) + 1

    def on_reply(reply: zenoh.Reply) -> None:
        with lock:
            counts["replies"] += 1

    def firehose() -> None:
        key = keys("cpu1").cmd
        period = 1.0 / FIREHOSE_PER_S
        due = time.monotonic()
        n = 0
        while not stop.is_set():
            n += 1
            data = b"not a command" if n % 10 == 0 else payload
            session.get(key, on_reply, payload=data, timeout=5.0)
            counts["fired"] += 1
            due += period
            delay = due - time.monotonic()
            if delay > 0:
                time.sleep(delay)

    threads = [threading.Thread(target=sender, daemon=True) for _ in range(FLOOD_SENDERS)]
    threads.append(threading.Thread(target=firehose, daemon=True))
    for t in threads:
        t.start()
    try:
        yield lambda: (
            f"{counts['answered']} sent and answered ({counts['applied']} applied"
            + "".join(f"; {n} {why}" for why, n in sorted(refusals.items()))
            + f"), {counts['fired']} fired ({counts['replies']} replies)"
        )
    finally:
        stop.set()
        for t in threads:
            t.join(10)
        client.close()
        session.close()  # type: ignore[no-untyped-call]


LOAD_MAKERS = {"idle": no_load, "pages": pages, "flood": flood}


# ---------------------------------------------------------------------------- one scenario


def scenario(workload: str, view: str, load: str, seconds: float) -> dict[str, Any]:
    """One measured run: the CPU process up with its view, ``load`` on it for ``seconds``."""
    with tempfile.TemporaryDirectory(prefix="s7graph-jitter-") as tmp:
        endpoint = f"unixsock-stream/{tmp}/bus.sock"
        port = free_port()
        errors = Path(tmp) / "stderr.txt"
        with errors.open("w") as err:
            proc = subprocess.Popen(
                [sys.executable, __file__, "--worker", workload, view, endpoint, str(port),
                 str(Path(tmp) / "state.sqlite")],
                cwd=ROOT, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=err, text=True,
            )  # fmt: skip
            try:
                return _measure(proc, load, seconds, endpoint, workload)
            except BaseException:
                proc.kill()
                raise
            finally:
                proc.wait(60)
                said = errors.read_text()
                if proc.returncode not in (0, None) or "Traceback" in said or "error" in said:
                    print(said, file=sys.stderr)


def _measure(
    proc: subprocess.Popen[str], load: str, seconds: float, endpoint: str, workload: str
) -> dict[str, Any]:
    assert proc.stdin is not None and proc.stdout is not None
    url = ""
    for line in proc.stdout:
        found = re.search(r"view (\S+) \(bus ", line)
        if found:
            url = found[1]
            break
    if not url:
        raise RuntimeError("the CPU process ended before its view was up")
    deadline = time.monotonic() + 60
    while not serves(url) and time.monotonic() < deadline:
        time.sleep(0.2)
    time.sleep(2.0)  # let the start settle
    fb = "Seq_drill" if workload == "drill" else "Bench_1"
    load_before = os.getloadavg()[0]
    with LOAD_MAKERS[load](url, endpoint, fb) as said:
        time.sleep(1.0 if load != "idle" else 0.0)  # the load running
        proc.stdin.write("start\n")
        proc.stdin.flush()
        time.sleep(seconds)
        proc.stdin.write("end\n")
        proc.stdin.flush()
        what = said()
    result: dict[str, Any] = {}
    for line in proc.stdout:
        if line.startswith(RESULT):
            result = json.loads(line[len(RESULT) :])
    result["load"] = what
    result["loadavg"] = (load_before + os.getloadavg()[0]) / 2
    return result


# ---------------------------------------------------------------------------- figures


def _pct(sorted_ns: list[int], q: float) -> float:
    if not sorted_ns:
        return float("nan")
    return sorted_ns[min(len(sorted_ns) - 1, int(q * len(sorted_ns)))] / 1e6


def figures(result: dict[str, Any]) -> dict[str, float]:
    cycles = sorted(result["cycles"])
    scans = sorted(result["scans"])
    return {
        "n": len(cycles),
        "p50": _pct(cycles, 0.5),
        "p99": _pct(cycles, 0.99),
        "p999": _pct(cycles, 0.999),
        "max": cycles[-1] / 1e6 if cycles else float("nan"),
        "overruns": float(result["overruns"]),
        "scan_p50": _pct(scans, 0.5),
        "scan_p99": _pct(scans, 0.99),
        "loadavg": float(result["loadavg"]),
    }


def _column(runs: list[dict[str, float]], key: str) -> list[float]:
    return [f[key] for f in runs]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seconds", type=float, default=60.0, help="measured per scenario (60)")
    ap.add_argument("--repeat", type=int, default=1, help="runs; min/median/max over them")
    ap.add_argument("--workloads", default=",".join(WORKLOADS))
    ap.add_argument("--views", default=",".join(VIEWS))
    ap.add_argument("--loads", default=",".join(LOADS))
    ap.add_argument("--worker", nargs=5, metavar=("WORKLOAD", "VIEW", "EP", "PORT", "STATE"),
                    help=argparse.SUPPRESS)  # fmt: skip
    args = ap.parse_args(argv)
    if args.worker:
        workload, view, endpoint, port, state = args.worker
        return worker(workload, view, endpoint, int(port), Path(state))
    workloads = [w for w in args.workloads.split(",") if w]
    views = [v for v in args.views.split(",") if v]
    loads = [x for x in args.loads.split(",") if x]
    if "pages" in loads and not os.path.exists(CHROMIUM):
        print(f"no browser at {CHROMIUM}: the pages load is left out")
        loads.remove("pages")
    print(f"python {sys.version.split()[0]}, {os.cpu_count()} cores, cycle {CYCLE_MS:g} ms, "
          f"{args.seconds:g} s per scenario, {args.repeat} run(s); cycle = start to start of "
          "two scans, ms; min/median/max over runs")  # fmt: skip
    runs: dict[tuple[str, str, str], list[dict[str, float]]] = {}
    notes: dict[tuple[str, str, str], str] = {}
    for _ in range(args.repeat):
        for workload in workloads:
            for view in views:
                for load in loads:
                    result = scenario(workload, view, load, args.seconds)
                    if "cycles" not in result:
                        print(f"{workload} {view} {load}: no figures")
                        continue
                    runs.setdefault((workload, view, load), []).append(figures(result))
                    notes[(workload, view, load)] = result["load"]
                    if result["stopped"]:
                        print(f"  {workload} {view} {load}: the CPU went to STOP: "
                              f"{result['stopped']}")  # fmt: skip
                    f = runs[(workload, view, load)][-1]
                    print(f"  {workload:8} {view:9} {load:6} p99.9 {f['p999']:.2f} max "
                          f"{f['max']:.2f} overruns {f['overruns']:.0f}, page faults "
                          f"{result['majflt']}  ({result['load']})", flush=True)  # fmt: skip
    head = (f"{'workload':9} {'view':9} {'load':6} {'cycles':>6} {'p50':>17} {'p99':>17} "
            f"{'p99.9':>17} {'max':>17} {'overruns':>10} {'scan p50':>17} {'scan p99':>17} "
            f"{'load avg':>14}  target")  # fmt: skip
    print(head)
    met = True
    for (workload, view, load), fs in runs.items():
        col = functools.partial(_column, fs)
        target = ""
        if view == "separate" and load in ("pages", "flood"):
            ok = all(f["p999"] <= CYCLE_MS + 2 and f["overruns"] == 0 for f in fs)
            met = met and ok
            target = "met" if ok else "MISSED"
        print(f"{workload:9} {view:9} {load:6} {int(statistics.median(col('n'))):>6} "
              f"{spread(col('p50')):>17} {spread(col('p99')):>17} {spread(col('p999')):>17} "
              f"{spread(col('max')):>17} {spread(col('overruns'), '{:.0f}'):>10} "
              f"{spread(col('scan_p50'), '{:.3f}'):>17} {spread(col('scan_p99'), '{:.3f}'):>17} "
              f"{spread(col('loadavg'), '{:.1f}'):>14}  {target}")  # fmt: skip
    print(f"target (view in its own process, pages and flood): p99.9 <= {CYCLE_MS + 2:g} ms, "
          f"no overrun: {'met' if met else 'MISSED'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
