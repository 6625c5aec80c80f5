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
- ``downloads``: an engineer previewing downloads one after the other, at most one a
  second, in turn a chart of about 1 MB and a chain of 5,000 ANDed contacts
  (``bench/big_charts.py``), each parsed, checked and compiled by the CPU's compiler
  process (``web/bus/compiler.py``); against ``idle``, the scan thread's own work per cycle
  (the runner's breakdown, ``encode`` to ``gc``) must be no larger, and the CPU must not
  go to STOP;

and prints, per workload, view and load, the cycle (start to start of two scans) at
p50 / p99 / p99.9 / max, the scans the runner found overrunning their 10 ms, and the scan
time (p50 / p99). Target: the view in its own process, p99.9 of the cycle at most
cycle + 2 ms and no overrun under ``pages`` and ``flood``.

Beside each run cycles the *C floor* (``bench/cycle_floor.c``: a 1 ms loop that does
nothing on each processor, ``SCHED_FIFO`` above the scan): how evenly this machine wakes
a real-time thread at all. A wake-up of the floor 0.5 ms late or more is a stall of the
machine (from its deadline to when it woke); the *own* figures take from each cycle of the
CPU the time the machine stalled in it, and count an overrun as own only when the machine
stalled neither it nor the cycle before (what s7graph itself lost). The load makers keep
small pages, as the CPU does, unless ``--huge-pages``, and keep off the processor the CPU
keeps for its scan (``--core auto``, ``engine/cores.py``): they stand for clients on other
machines.

Each of the own long cycles is put down to a cause from the runner's breakdown of it
(``engine/profile.py``, as ``s7graph status`` shows it): the phase that took longest
(``scan``, ``stage``, ``edge``, ...), or a late start of the next scan — ``late: lock``
when the scan thread was blocked (the interpreter's lock) more than it waited for a
processor, else ``late: processor``. Each run's line also gives the mean of each phase.
"""

from __future__ import annotations

import argparse
import bisect
import collections
import functools
import itertools
import json
import os
import re
import resource
import shutil
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

from s7graph.engine.cores import allowed_cpus, others, pin  # noqa: E402
from s7graph.engine.profile import LONG_MARGIN_NS  # noqa: E402
from s7graph.engine.runner import RT_PRIORITY, core_for, keep_small_pages  # noqa: E402

DRILL = ROOT / "examples" / "drill"
CYCLE_MS = 10.0
WORKLOADS = ("drill", "scan200")
VIEWS = ("separate", "inline", "normal")
"""The view in its own process (``run --web``), in the CPU's process (``view_in_process``),
and in its own process with the scan thread at the normal priority (``--rt-priority 0``)."""
LOADS = ("idle", "pages", "flood", "downloads")
PAGES = 3
PAGE_LIFE_S = 5.0
FLOOD_SENDERS = 4
FIREHOSE_PER_S = 1000
CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--enable-unsafe-swiftshader",
    "--use-angle=swiftshader",
]
RESULT = "JITTER "


# ---------------------------------------------------------------------------- the CPU process


def worker(workload: str, view: str, endpoint: str, port: int, state: Path) -> int:
    """Run ``workload`` as ``s7graph run --web`` does, stamping every scan; ``start`` and
    ``end`` lines on stdin mark the measured window, ``end`` also stops the run. Prints the
    window's figures as one ``JITTER {json}`` line."""
    from s7graph.engine.cpu import Cpu
    from s7graph.engine.profile import PHASE_NAMES
    from s7graph.engine.runner import Runner
    from s7graph.web.bus.publisher import BusPublisher
    from s7graph.web.cli.net import NetOptions
    from s7graph.web.cli.run_chart import run_chart

    starts: list[int] = []
    ends: list[int] = []
    runners: list[Runner] = []
    scan = Cpu.scan
    run = Runner.run

    overruns_seen: list[int] = []  # the runner's overrun count at each scan's start

    def stamped_scan(self: Cpu) -> Any:
        starts.append(time.perf_counter_ns())
        overruns_seen.append(runners[0].overruns if runners else 0)
        record = scan(self)
        ends.append(time.perf_counter_ns())
        return record

    def kept_run(self: Runner, **kw: Any) -> None:
        runners.append(self)
        self.profile.recent = collections.deque(maxlen=100_000)  # every long cycle
        run(self, **kw)

    publishers: list[BusPublisher] = []
    init = BusPublisher.__init__

    def kept_init(self: BusPublisher, *args: Any, **kw: Any) -> None:
        init(self, *args, **kw)
        publishers.append(self)  # the CPU's bus: one in the CPU's process

    Cpu.scan = stamped_scan  # type: ignore[method-assign]
    Runner.run = kept_run  # type: ignore[method-assign]
    BusPublisher.__init__ = kept_init  # type: ignore[method-assign]
    marks: dict[str, tuple[int, int]] = {}

    faults: dict[str, int] = {}
    comm: dict[str, int] = {}  # the bus's count of boundaries whose share ran out, at a mark

    def control() -> None:
        for line in sys.stdin:
            word = line.strip()
            overruns = runners[0].overruns if runners else 0
            marks[word] = (len(ends), overruns)
            faults[word] = resource.getrusage(resource.RUSAGE_SELF).ru_majflt
            comm[word] = publishers[0].comm_limited if publishers else 0
            if word == "end" and runners:
                runners[0].request_stop()

    threading.Thread(target=control, daemon=True).start()
    net = NetOptions(listen=[endpoint])
    common: dict[str, Any] = {
        "state": state,
        "cycle_ms": CYCLE_MS,
        "web": True,
        "port": port,
        "net": net,
        "view_in_process": view == "inline",
        "rt_priority": None if view == "normal" else RT_PRIORITY,
    }
    if workload == "drill":
        rc = run_chart(
            DRILL / "drill.s7g",
            plant=DRILL / "demo_plant.py",
            symbols=DRILL / "symbols.txt",
            **common,
        )
    else:
        rc = run_chart(Path("scan200.s7g"), session=_scan200_session(), **common)
    a, over_a = marks.get("start", (0, 0))
    b, over_b = marks.get("end", (len(ends), runners[0].overruns if runners else 0))
    cycles = [starts[i + 1] - starts[i] for i in range(a, min(b, len(starts)) - 1)]
    scans = [ends[i] - starts[i] for i in range(a, b)]
    overran = [
        (starts[i], starts[i + 1])
        for i in range(a, min(b, len(starts)) - 1)
        if overruns_seen[i + 1] > overruns_seen[i]
    ]
    window = (starts[a], starts[min(b, len(starts)) - 1]) if b > a else (0, -1)
    wall_to_perf = time.time_ns() - time.perf_counter_ns()
    long = [
        {"start": c.at_ns - wall_to_perf, "cycle": c.cycle_ns, "parts": c.parts()}
        for c in (runners[0].profile.recent if runners else ())
        if window[0] <= c.at_ns - wall_to_perf <= window[1]
    ]
    stopped = runners[0].stopped if runners else "never ran"
    majflt = faults.get("end", 0) - faults.get("start", 0)
    result = {
        "rc": rc,
        "cycles": cycles,
        "scans": scans,
        "overruns": over_b - over_a,
        "stopped": stopped,
        "majflt": majflt,
        "starts": starts[a:b],
        "overran": overran,
        "long": long,
        "comm_limited": comm.get("end", 0) - comm.get("start", 0),
        "means": {name: runners[0].profile.mean_ns(name) / 1e6 for name in PHASE_NAMES}
        if runners
        else {},
    }
    print(RESULT + json.dumps(result), flush=True)
    return 0


def _scan200_session() -> Any:
    """bench/scan.py's workload in one CPU: 25 FBs of 8 sequencers, the first shown."""
    from scan import N_SEQUENCERS, chart_source

    from s7graph.engine.clock import SystemClock
    from s7graph.engine.symbols import SymbolTable
    from s7graph.sequencer.compile import compile_chart
    from s7graph.sequencer.text.parse import parse_chart
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
            browser = p.chromium.launch(executable_path=CHROMIUM, headless=True, args=CHROMIUM_ARGS)
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

    from s7graph.web.bus.client import BusClient
    from s7graph.web.bus.keys import keys
    from s7graph.web.bus.protocol import Command, encode
    from s7graph.web.bus.session import open_session

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
        yield (
            lambda: (
                f"{counts['answered']} sent and answered ({counts['applied']} applied"
                + "".join(f"; {n} {why}" for why, n in sorted(refusals.items()))
                + f"), {counts['fired']} fired ({counts['replies']} replies)"
            )
        )
    finally:
        stop.set()
        for t in threads:
            t.join(10)
        client.close()
        session.close()  # type: ignore[no-untyped-call]


@contextmanager
def downloads(url: str, endpoint: str, fb: str) -> Iterator[Callable[[], str]]:
    """Download previews one after the other, at most one a second: a chart of about 1 MB
    and a 5,000-contact chain in turn, as FB ``fb`` (the CPU compiles each, changes
    nothing)."""
    from big_charts import contact_chain, huge_chart

    from s7graph.web.bus.client import BusClient
    from s7graph.web.bus.protocol import Command
    from s7graph.web.bus.session import open_session

    stop = threading.Event()
    charts = itertools.cycle([("1 MB", huge_chart(name=fb)), ("chain", contact_chain(name=fb))])
    done: collections.Counter[str] = collections.Counter()
    took: list[float] = []
    session = open_session(connect=[endpoint])
    client = BusClient(session, "cpu1")
    token = client.login("engineer").token

    def previews() -> None:
        while not stop.is_set():
            kind, text = next(charts)
            args = {"source": text, "preview": True}
            begun = time.monotonic()
            reply = client.send(
                Command(op="download", fb=fb, user="engineer", token=token, args=args), timeout=120
            )
            took.append(time.monotonic() - begun)
            done[f"{kind} {'previewed' if reply.applied else 'refused: ' + reply.reason[:60]}"] += 1
            stop.wait(max(0.0, 1.0 - (time.monotonic() - begun)))

    thread = threading.Thread(target=previews, daemon=True)
    thread.start()
    try:
        yield (
            lambda: (
                ", ".join(f"{n} {what}" for what, n in sorted(done.items()))
                + (f"; answered in {spread(sorted(took))} s" if took else "")
            )
        )
    finally:
        stop.set()
        thread.join(180)
        client.close()
        session.close()  # type: ignore[no-untyped-call]


LOAD_MAKERS = {"idle": no_load, "pages": pages, "flood": flood, "downloads": downloads}


# ---------------------------------------------------------------------------- one scenario


def build_floor(build_dir: Path) -> Path | None:
    """``bench/cycle_floor.c`` built with the system's C compiler (None: there is none)."""
    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        return None
    exe = build_dir / "cycle_floor"
    src = Path(__file__).with_name("cycle_floor.c")
    subprocess.run([cc, "-O2", "-pthread", "-o", str(exe), str(src)], check=True)
    return exe


EVERY_PROCESSOR = allowed_cpus()


def _every_processor() -> None:
    """In the CPU's process before it runs: every processor, as a shell starts it."""
    pin(EVERY_PROCESSOR)


def scenario(
    workload: str, view: str, load: str, seconds: float, floor: Path | None = None
) -> dict[str, Any]:
    """One measured run: the CPU process up with its view, ``load`` on it for ``seconds``;
    with ``floor``, the C floor cycling beside it over the same window."""
    with tempfile.TemporaryDirectory(prefix="s7graph-jitter-") as tmp:
        endpoint = f"unixsock-stream/{tmp}/bus.sock"
        port = free_port()
        errors = Path(tmp) / "stderr.txt"
        with errors.open("w") as err:
            proc = subprocess.Popen(
                [
                    sys.executable,
                    __file__,
                    "--worker",
                    workload,
                    view,
                    endpoint,
                    str(port),
                    str(Path(tmp) / "state.sqlite"),
                ],
                cwd=ROOT,
                stdin=subprocess.PIPE,
                stdout=subprocess.PIPE,
                stderr=err,
                text=True,
                preexec_fn=_every_processor,
            )
            beside = None
            if floor is not None:
                beside = subprocess.Popen(
                    [str(floor), str(int(FLOOR_PERIOD_MS * 1000)), str(FLOOR_PRIORITY)],
                    stdin=subprocess.PIPE,
                    stdout=subprocess.PIPE,
                    text=True,
                )
            try:
                result = _measure(proc, load, seconds, endpoint, workload, beside)
                if beside is not None:
                    out, _ = beside.communicate(timeout=60)
                    result["floor"] = json.loads(out)["starts"]
                return result
            except BaseException:
                proc.kill()
                if beside is not None:
                    beside.kill()
                raise
            finally:
                proc.wait(60)
                said = errors.read_text()
                if proc.returncode not in (0, None) or "Traceback" in said or "error" in said:
                    print(said, file=sys.stderr)


def _measure(
    proc: subprocess.Popen[str],
    load: str,
    seconds: float,
    endpoint: str,
    workload: str,
    beside: subprocess.Popen[str] | None = None,
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
        for word in ("start", "end"):
            for p in (proc, beside):
                if p is not None and p.stdin is not None:
                    p.stdin.write(f"{word}\n")
                    p.stdin.flush()
            if word == "start":
                time.sleep(seconds)
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


LONG_MS = CYCLE_MS + LONG_MARGIN_NS / 1e6
"""A cycle longer than this misses the target's p99.9 bound (the runner's *long* cycle)."""
FLOOR_PRIORITY = RT_PRIORITY + 10
"""The C floor runs above the scan (and its monitor), so that a scan never delays it: a late
wake-up of the floor is the machine's alone."""
FLOOR_PERIOD_MS = 1.0
"""The C floor wakes every millisecond, so that a stall of the machine of 2 ms or more makes
it late wherever the stall falls in the CPU's 10 ms cycle (a floor at the CPU's own period
would see only a stall over one of its wake-ups)."""
FLOOR_LATE_MS = 0.5
"""A wake-up of the C floor this late counts as a stall of the machine; less is the ordinary
latency of waking a thread here and is not set aside."""


def floor_stalls(floor: list[list[int]]) -> list[list[tuple[int, int]]]:
    """Per processor, the stalls of the machine the C floor saw, as ``(deadline, woke)`` in
    time order: each wake-up ``FLOOR_LATE_MS`` or more late, from its deadline (the wake-up
    before plus the period; a lower bound of the stall, which may have begun up to a period
    earlier) to when it woke."""
    period, limit = FLOOR_PERIOD_MS * 1e6, (FLOOR_PERIOD_MS + FLOOR_LATE_MS) * 1e6
    return [
        [(int(prev + period), t) for prev, t in itertools.pairwise(one) if t - prev >= limit]
        for one in floor
    ]


def machine_share(stalls: list[list[tuple[int, int]]], a: int, b: int) -> int:
    """The time, ns, within ``a``..``b`` that the machine stalled: per processor the overlap
    of its stalls with the window, the largest over processors (a stall of either holds the
    scan up: of the one it runs on, or of the one whose thread holds the interpreter's
    lock)."""
    share = 0
    for one in stalls:
        i = bisect.bisect_left(one, (a, a))  # a stall ending after a may begin before it
        i = max(0, i - 1)
        lost = 0
        while i < len(one) and one[i][0] < b:
            lost += max(0, min(b, one[i][1]) - max(a, one[i][0]))
            i += 1
        share = max(share, lost)
    return share


def own_figures(result: dict[str, Any]) -> dict[str, float]:
    """What s7graph itself lost: each cycle of the CPU less the time the machine stalled in
    it (``machine_share``); the cycles over ``LONG_MS``, how many of them the machine's share
    explains, and the p99.9 and longest of the own cycles; the overruns whose scan and the
    cycle before it the machine did not stall."""
    stalls = floor_stalls(result.get("floor") or [])
    starts = result.get("starts") or []
    long = shared = 0
    own: list[int] = []
    for a, b in itertools.pairwise(starts):
        mine = b - a - machine_share(stalls, a, b)
        long += b - a > LONG_MS * 1e6
        shared += b - a > LONG_MS * 1e6 >= mine
        own.append(mine)
    own.sort()
    # an overrun also follows from a start the machine made late: the cycle before counts
    before = int(CYCLE_MS * 1e6)
    overran = [machine_share(stalls, a - before, b) > 0 for a, b in result.get("overran") or []]
    return {
        "long": float(long),
        "shared": float(shared),
        "own_p999": _pct(own, 0.999),
        "own_max": own[-1] / 1e6 if own else float("nan"),
        "own_overruns": float(overran.count(False)),
    }


def own_causes(result: dict[str, Any]) -> collections.Counter[str]:
    """The long cycles the runner kept that are still long with the machine's share set
    aside, by ``cause``."""
    stalls = floor_stalls(result.get("floor") or [])
    return collections.Counter(
        cause(c["parts"])
        for c in result.get("long") or []
        if c["cycle"] - machine_share(stalls, c["start"], c["start"] + c["cycle"]) > LONG_MS * 1e6
    )


WORK = ("encode", "scan", "alarms", "edge", "stage", "gc")


def cause(parts: dict[str, int]) -> str:
    """What made a long cycle long, from the runner's breakdown (``engine.profile``): the
    late start of the next scan (``late: lock`` when the scan thread was blocked more than
    it waited for a processor, else ``late: processor``), or the longest work phase."""
    work = max(WORK, key=lambda name: parts.get(name, 0))
    if parts.get("late", 0) >= parts.get(work, 0):
        if "processor" not in parts:
            return "late"
        return "late: lock" if parts["lock"] >= parts["processor"] else "late: processor"
    return work


def figures(result: dict[str, Any]) -> dict[str, float]:
    cycles = sorted(result["cycles"])
    scans = sorted(result["scans"])
    floor = result.get("floor") or []
    period = FLOOR_PERIOD_MS * 1e6
    floor_late = sorted(int(b - a - period) for one in floor for a, b in itertools.pairwise(one))
    return {
        **own_figures(result),
        "floor_p999": _pct(floor_late, 0.999),
        "floor_max": floor_late[-1] / 1e6 if floor_late else float("nan"),
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
    ap.add_argument(
        "--huge-pages",
        action="store_true",
        help="leave the load makers' memory to transparent huge pages",
    )
    ap.add_argument(
        "--worker",
        nargs=5,
        metavar=("WORKLOAD", "VIEW", "EP", "PORT", "STATE"),
        help=argparse.SUPPRESS,
    )
    args = ap.parse_args(argv)
    if args.worker:
        workload, view, endpoint, port, state = args.worker
        return worker(workload, view, endpoint, int(port), Path(state))
    if not args.huge_pages:
        keep_small_pages()  # the load makers (and the browsers they start) too
    kept = core_for("auto", RT_PRIORITY)
    if kept is not None:
        pin(others(kept, EVERY_PROCESSOR))  # the load makers too; the CPU gets every one
    workloads = [w for w in args.workloads.split(",") if w]
    views = [v for v in args.views.split(",") if v]
    loads = [x for x in args.loads.split(",") if x]
    if "pages" in loads and not os.path.exists(CHROMIUM):
        print(f"no browser at {CHROMIUM}: the pages load is left out")
        loads.remove("pages")
    build = tempfile.TemporaryDirectory(prefix="s7graph-floor-")
    floor = build_floor(Path(build.name))
    print(
        f"python {sys.version.split()[0]}, {os.cpu_count()} cores, cycle {CYCLE_MS:g} ms, "
        f"{args.seconds:g} s per scenario, {args.repeat} run(s); cycle = start to start of "
        "two scans, ms; min/median/max over runs"
    )
    print(
        f"transparent huge pages: {_thp_setting()} (the CPU, its view"
        f"{' and the load makers' if not args.huge_pages else ''} keep small pages); "
        + (
            "the C floor (bench/cycle_floor.c) cycles beside each run"
            if floor is not None
            else "no C compiler: no C floor"
        )
    )
    print(
        f"the CPU keeps processor {kept} for its scan (--core auto; not with --rt-priority 0, "
        "the normal view); the load makers run on the others"
        if kept is not None
        else "no processor kept for the scan (--core auto: not real-time, or one processor)"
    )
    runs: dict[tuple[str, str, str], list[dict[str, float]]] = {}
    notes: dict[tuple[str, str, str], str] = {}
    whys: dict[tuple[str, str, str], collections.Counter[str]] = {}
    works: dict[tuple[str, str, str], list[float]] = {}
    stops: dict[tuple[str, str, str], int] = {}
    for _ in range(args.repeat):
        for workload in workloads:
            for view in views:
                for load in loads:
                    result = scenario(workload, view, load, args.seconds, floor)
                    if "cycles" not in result:
                        print(f"{workload} {view} {load}: no figures")
                        continue
                    runs.setdefault((workload, view, load), []).append(figures(result))
                    why = own_causes(result)
                    whys.setdefault((workload, view, load), collections.Counter()).update(why)
                    notes[(workload, view, load)] = result["load"]
                    works.setdefault((workload, view, load), []).append(scan_work(result))
                    stops[(workload, view, load)] = stops.get((workload, view, load), 0) + bool(
                        result["stopped"]
                    )
                    if result["stopped"]:
                        print(
                            f"  {workload} {view} {load}: the CPU went to STOP: {result['stopped']}"
                        )
                    f = runs[(workload, view, load)][-1]
                    print(
                        f"  {workload:8} {view:9} {load:6} p99.9 {f['p999']:.2f} max "
                        f"{f['max']:.2f} overruns {f['overruns']:.0f}, page faults "
                        f"{result['majflt']}; C floor late p99.9 {f['floor_p999']:.2f} max "
                        f"{f['floor_max']:.2f}; cycles over {LONG_MS:g} ms "
                        f"{f['long']:.0f}, {f['shared']:.0f} of them within {LONG_MS:g} "
                        f"ms less the machine's stalls; own p99.9 {f['own_p999']:.2f} max "
                        f"{f['own_max']:.2f} overruns {f['own_overruns']:.0f}; own long "
                        f"cycles by cause: {_causes(why)}; mean ms {_means(result)}; "
                        f"communication share ran out at {result['comm_limited']} "
                        f"boundaries  ({result['load']})",
                        flush=True,
                    )
    head = (
        f"{'workload':9} {'view':9} {'load':6} {'cycles':>6} {'p50':>17} {'p99':>17} "
        f"{'p99.9':>17} {'max':>17} {'overruns':>10} {'scan p50':>17} {'scan p99':>17} "
        f"{'load avg':>14} {'floor late p99.9':>17} {'floor late max':>17} {'>12 (floor)':>11} "
        f"{'own p99.9':>17} {'own max':>17} {'own over':>10}  target  own target"
    )
    print(head)
    met = own_met = True
    for (workload, view, load), fs in runs.items():
        col = functools.partial(_column, fs)
        target = own_target = ""
        if view == "separate" and load in ("pages", "flood"):
            ok = all(f["p999"] <= LONG_MS and f["overruns"] == 0 for f in fs)
            own_ok = all(f["own_p999"] <= LONG_MS and f["own_overruns"] == 0 for f in fs)
            met, own_met = met and ok, own_met and own_ok
            target, own_target = ("met" if ok else "MISSED"), ("met" if own_ok else "MISSED")
        print(
            f"{workload:9} {view:9} {load:6} {int(statistics.median(col('n'))):>6} "
            f"{spread(col('p50')):>17} {spread(col('p99')):>17} {spread(col('p999')):>17} "
            f"{spread(col('max')):>17} {spread(col('overruns'), '{:.0f}'):>10} "
            f"{spread(col('scan_p50'), '{:.3f}'):>17} {spread(col('scan_p99'), '{:.3f}'):>17} "
            f"{spread(col('loadavg'), '{:.1f}'):>14} {spread(col('floor_p999')):>17} "
            f"{spread(col('floor_max')):>17} {_over(fs):>11} {spread(col('own_p999')):>17} "
            f"{spread(col('own_max')):>17} {spread(col('own_overruns'), '{:.0f}'):>10}  "
            f"{target:6}  {own_target}"
        )
    print(
        f"target (view in its own process, pages and flood): p99.9 <= {LONG_MS:g} ms, no "
        f"overrun: {'met' if met else 'MISSED'}; own target, the same with each cycle less "
        f"the time the machine stalled the C floor in it: {'met' if own_met else 'MISSED'}"
    )
    print(
        f"floor late: how late the C floor woke, every {FLOOR_PERIOD_MS:g} ms on each "
        f"processor; >12 (floor): cycles over {LONG_MS:g} ms in all runs (in brackets: of "
        f"them, those within {LONG_MS:g} ms less the machine's stalls, the C floor "
        f"{FLOOR_LATE_MS:g} ms late or more)"
    )
    print(
        f"own long cycles (over {LONG_MS:g} ms with the machine's stalls set aside) by cause,"
        " all runs, from"
        " the runner's breakdown of each cycle (engine/profile.py):"
    )
    for key, why in whys.items():
        print(f"  {' '.join(key):28} {_causes(why)}")
    _compare_downloads(works, stops)
    build.cleanup()
    return 0


def scan_work(result: dict[str, Any]) -> float:
    """The scan thread's own work per cycle, ms: the mean of each work phase of the
    runner's breakdown (``WORK``: ``encode`` to ``gc``), added up."""
    means = result.get("means") or {}
    return float(sum(means.get(name, 0.0) for name in WORK))


DOWNLOADS_MARGIN = 1.10
"""``downloads`` against ``idle``: the scan thread's work per cycle counts as no larger
within this factor (the spread of repeated ``idle`` runs on a shared machine)."""


def _compare_downloads(
    works: dict[tuple[str, str, str], list[float]], stops: dict[tuple[str, str, str], int]
) -> None:
    """The ``downloads`` target: no STOP, and the scan thread's work per cycle no larger
    than under ``idle`` (medians over runs, within ``DOWNLOADS_MARGIN``)."""
    for (workload, view, load), with_downloads in works.items():
        without = works.get((workload, view, "idle"))
        if load != "downloads" or not without:
            continue
        a, b = statistics.median(without), statistics.median(with_downloads)
        met = b <= a * DOWNLOADS_MARGIN and not stops.get((workload, view, load))
        print(
            f"downloads target, {workload} {view}: scan thread's work per cycle idle "
            f"{spread(without, '{:.3f}')} ms, downloads {spread(with_downloads, '{:.3f}')} "
            f"ms; STOPs {stops.get((workload, view, load), 0)}: "
            f"{'met' if met else 'MISSED'}"
        )


def _means(result: dict[str, Any]) -> str:
    """The mean of each phase of the cycle but the wait (``engine.profile``), in ms."""
    means = result.get("means") or {}
    return " ".join(f"{k} {v:.2f}" for k, v in means.items() if k != "idle") or "none"


def _causes(why: collections.Counter[str]) -> str:
    return ", ".join(f"{name} {n}" for name, n in why.most_common()) or "none"


def _over(fs: list[dict[str, float]]) -> str:
    """Cycles over ``LONG_MS`` in all runs and (in brackets) how many the machine's stalls
    explain."""
    return f"{sum(f['long'] for f in fs):.0f} ({sum(f['shared'] for f in fs):.0f})"


def _thp_setting() -> str:
    """The machine's transparent huge page mode (the bracketed word), or "unknown"."""
    try:
        text = Path("/sys/kernel/mm/transparent_hugepage/enabled").read_text()
    except OSError:
        return "unknown"
    found = re.search(r"\[(\w+)\]", text)
    return found[1] if found else text.strip()


if __name__ == "__main__":
    sys.exit(main())
