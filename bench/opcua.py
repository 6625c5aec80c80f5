"""OPC UA benchmark: how fast a step change in the CPU reaches an OPC UA client's
subscription (run as ``python bench/opcua.py``; see bench/README.md). A benchmark, not a
test: it prints figures and the target, met or not.

Each round runs ``loop8`` (``bench/page.py``'s generated loop of 8 steps, each leaving on
its own step time of 150–249 ms) in a CPU process of its own — the real ``run_chart`` of
``s7graph run CHART --opcua URL``: state file, bus on a unix socket, the OPC UA server in
its child process — at a 10 ms cycle on the system clock, its ``LiveGraph.changed`` (at the
end of every scan, before the scan is published) wrapped to stamp ``time.time()``
whenever the active steps change. asyncua's client in this process subscribes to the
FB's ``ActiveSteps`` at a 10 ms publishing interval (the face's minimum) and notes the
wall-clock time each data change arrives; the latency of a change is its arrival less the
scan's stamp (one machine, one clock).

Loads, one after the other in each round: ``idle`` (the subscription alone),
``clients`` (four more sessions as a plant's SCADA keeps them: each subscribed to every
step's ``Active``, ``T`` and ``Fault`` and the CPU's variables at 100 ms, and reading
100 values every 100 ms) and ``flood`` (two more processes of three anonymous clients
each, reading 400 values at a time, browsing, making and dropping subscriptions of 200
items and calling methods they are refused, as fast as the face serves them). The load
processes run at nice 10, standing for clients on other machines: the face serves all
their requests, but their own work does not take the processors from it. ``--page``
adds ``page``: the same CPU with ``--web`` too, its page open in headless Chromium
(``bench/page.py``'s hooks), and the OPC UA subscription watching the same changes — the
page's colour figure beside the OPC UA one, on the same changes. Without it the page's
last recorded figure (bench/README.md) is printed beside.

p50 / p99 / max per round over ``--changes`` changes; min/median/max over ``--repeat``
rounds; the load average. Target: p99 ≤ 100 ms.
"""

from __future__ import annotations

import argparse
import asyncio
import os
import re
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

BENCH = Path(__file__).resolve().parent
ROOT = BENCH.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(BENCH))

import page  # noqa: E402  (bench/page.py: the loop charts, the CPU's stamps, the page)
from figures import free_port, pct, spread  # noqa: E402

TARGET_MS = 100.0
CYCLE_MS = 10.0
PUBLISHING_MS = 10.0
FB = "Bench_loop"
MAX_CYCLE_MS = 5000.0
"""The CPU's cycle monitoring: on this shared machine a scan thread waiting seconds for a
processor would take the default 150 ms to STOP and end the round with no changes to
watch; a long cycle still shows in the latencies."""
FLOOD_NICE = 10
"""The flooding clients stand for clients on other machines: their own work (encoding
requests, decoding answers) yields the processors to the face and the CPU."""
WATCHDOG_S = 5.0
"""The clients' health probe (a read of the server's state every ``WATCHDOG_S`` s, given
as long to answer), as tests/web/opcua/helpers.py gives it: the face may hold a paced
request up to 1 s and a loaded machine adds to it; asyncua's default 1 s would take a
slow answer for a lost connection and drop the session mid-round."""
PAGE_RECORDED = "145/147/243 ms (loop8, bench/README.md, bench/page.py --repeat 3)"


# ---------------------------------------------------------------------------- the CPU


def worker(path: Path, endpoint: str, url: str, state: Path, port: int, max_cycle_ms: float) -> int:
    """Run ``path`` as ``s7graph run --opcua URL`` (and ``--web`` when ``port``) does, its
    changes stamped (``page.stamp_changes``: ``dump`` on stdin prints them, ``end`` stops)."""
    from s7graph.engine.runner import RT_PRIORITY
    from s7graph.web.cli.net import NetOptions
    from s7graph.web.cli.run_chart import OpcuaFace, run_chart

    page.stamp_changes()
    return int(
        run_chart(
            path,
            state=state,
            cycle_ms=CYCLE_MS,
            max_cycle_ms=max_cycle_ms,
            web=bool(port),
            port=port or 8080,
            net=NetOptions(listen=[endpoint]),
            rt_priority=RT_PRIORITY,
            opcua=OpcuaFace(url=url),
        )
    )


@contextmanager
def cpu(with_page: bool) -> Iterator[tuple[page.Cpu, str]]:
    """The CPU process of ``loop8`` serving OPC UA (and its page ``with_page``): the CPU
    (its ``url`` the page's, "" without) and the OPC UA server's URL, once it serves."""
    with tempfile.TemporaryDirectory(prefix="s7graph-opcua-") as tmp:
        path = Path(tmp) / "loop8.s7g"
        path.write_text(page.loop_source(8), encoding="utf-8")
        url = f"opc.tcp://127.0.0.1:{free_port()}"
        port = free_port() if with_page else 0
        sock = f"unixsock-stream/{tmp}/bus.sock"
        args = [path, sock, url, Path(tmp) / "state.sqlite", port, MAX_CYCLE_MS]
        proc = subprocess.Popen(
            [sys.executable, __file__, "--worker", *map(str, args)],
            cwd=ROOT,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
        )
        try:
            view = _serving(proc, with_page)
            time.sleep(2.0)  # let the start settle
            machine = page.Cpu(proc, view, path)
            asked = machine.changes
            lock = threading.Lock()

            def changes() -> list[tuple[float, list[int]]]:
                with lock:  # the page's watch and the OPC UA one ask from two threads
                    return asked()

            machine.changes = changes  # type: ignore[method-assign]
            yield machine, url
            assert proc.stdin is not None
            proc.stdin.write("end\n")
            proc.stdin.flush()
            proc.wait(30)
        finally:
            if proc.poll() is None:
                proc.kill()
            proc.wait(30)


def _serving(proc: subprocess.Popen[str], with_page: bool) -> str:
    """Wait for the OPC UA server (and the page); the page's URL."""
    assert proc.stdout is not None
    view, served = "", False
    for line in proc.stdout:
        found = re.search(r"view (\S+) \(bus ", line)
        view = found[1] if found else view
        served = served or line.startswith("s7graph: opcua ")
        if served and (view or not with_page):
            break
    if not served:
        raise RuntimeError("the CPU process ended before its OPC UA server served")
    if with_page:
        deadline = time.monotonic() + 60
        while not page.serves(view) and time.monotonic() < deadline:
            time.sleep(0.2)
    return view


# ---------------------------------------------------------------------------- the client


async def watch(url: str, machine: page.Cpu, changes: int) -> dict[str, list[float]]:
    """Subscribe to ``ActiveSteps`` and watch ``changes`` step changes: the ms from the
    scan of each to the notification's arrival (a change never notified: missed)."""
    from asyncua import Client, ua

    arrivals: list[tuple[float, list[int]]] = []

    class Handler:
        def datachange_notification(self, node: Any, value: Any, data: Any) -> None:
            arrivals.append((time.time(), list(value or [])))

    async with Client(url, timeout=10, watchdog_intervall=WATCHDOG_S) as client:
        sub = await client.create_subscription(PUBLISHING_MS, Handler())
        await sub.subscribe_data_change(client.get_node(ua.NodeId(f"cpu1/{FB}/ActiveSteps", 2)))
        start = time.time()
        loop = asyncio.get_running_loop()
        got = await loop.run_in_executor(None, page._watch, machine, changes, start)
        await sub.delete()
    out: dict[str, list[float]] = {"latency": [], "missed": []}
    for t, active in got:
        hit = next((a for a, value in arrivals if a >= t and value == active), None)
        if hit is None:
            out["missed"].append(t)
        else:
            out["latency"].append((hit - t) * 1000)
    return out


def flood(url: str, seconds: float, mode: str) -> int:
    """``flood``: three anonymous clients doing what a hostile client does, as fast as
    they are served; ``clients``: four sessions as a plant's SCADA keeps them, each
    subscribed to every step's and the CPU's variables at 100 ms and reading 100 values
    every 100 ms. For ``seconds``."""
    from asyncua import Client, ua
    from asyncua.ua.uaerrors import UaStatusCodeError

    paths = ["cpu1/State", "cpu1/Cycle", f"cpu1/{FB}/S2/T", f"cpu1/{FB}/Mode"]
    params = ua.ReadParameters()
    params.NodesToRead = [
        ua.ReadValueId(NodeId=ua.NodeId(p, 2), AttributeId=ua.AttributeIds.Value)
        for p in paths * 100
    ]

    async def hostile(kind: int) -> None:
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:  # a client the face dropped comes again
            try:
                await one_hostile(kind, deadline)
            except (ConnectionError, OSError, TimeoutError, UaStatusCodeError):
                await asyncio.sleep(0.5)

    async def one_hostile(kind: int, deadline: float) -> None:
        async with Client(url, timeout=10, watchdog_intervall=WATCHDOG_S) as c:
            fb = c.get_node(ua.NodeId(f"cpu1/{FB}", 2))
            cycle = c.get_node(ua.NodeId("cpu1/Cycle", 2))
            while time.monotonic() < deadline:
                try:
                    if kind == 0:
                        await c.uaclient.read(params)
                    elif kind == 1:
                        await fb.get_children()
                        sub = await c.create_subscription(10, None)
                        await sub.subscribe_data_change([cycle] * 200)
                        await sub.delete()
                    else:
                        await fb.call_method(ua.NodeId(f"cpu1/{FB}/Init", 2))
                except (TimeoutError, UaStatusCodeError):
                    pass

    async def scada() -> None:
        async with Client(url, timeout=10, watchdog_intervall=WATCHDOG_S) as c:
            steps = [f"cpu1/{FB}/S{n}/{v}" for n in range(1, 9) for v in ("Active", "T", "Fault")]
            watched = [c.get_node(ua.NodeId(p, 2)) for p in [*steps, *paths]]
            sub = await c.create_subscription(100, None)
            await sub.subscribe_data_change(watched)
            read = ua.ReadParameters()
            read.NodesToRead = params.NodesToRead[:100]
            deadline = time.monotonic() + seconds
            while time.monotonic() < deadline:
                await c.uaclient.read(read)
                await asyncio.sleep(0.1)

    async def all_of_them() -> None:
        if mode == "clients":
            await asyncio.gather(*(scada() for _ in range(4)))
        else:
            await asyncio.gather(hostile(0), hostile(1), hostile(2))

    asyncio.run(all_of_them())
    return 0


@contextmanager
def loaded(url: str, seconds: float, mode: str) -> Iterator[None]:
    """``mode``'s clients (``flood``: two processes of them) at nice ``FLOOD_NICE``."""
    procs = [
        subprocess.Popen(
            [sys.executable, __file__, "--flood", url, str(seconds), mode],
            cwd=ROOT,
            preexec_fn=lambda: os.nice(FLOOD_NICE),
        )
        for _ in range(2 if mode == "flood" else 1)
    ]
    try:
        time.sleep(3.0)  # connected and busy
        yield
    finally:
        for p in procs:
            p.kill()
            p.wait(30)


# ---------------------------------------------------------------------------- rounds


def watching(url: str, machine: page.Cpu, changes: int) -> threading.Thread:
    """:func:`watch` in a thread and an event loop of its own (Playwright's sync API
    keeps one running in the main thread); its result in ``thread.result``."""

    def run() -> None:
        thread.result = asyncio.run(watch(url, machine, changes))  # type: ignore[attr-defined]

    thread = threading.Thread(target=run, daemon=True)
    thread.result = {"latency": [], "missed": []}  # type: ignore[attr-defined]
    thread.start()
    return thread


def watched(url: str, machine: page.Cpu, changes: int) -> dict[str, list[float]]:
    thread = watching(url, machine, changes)
    thread.join(changes * 0.4 + 120)
    return thread.result  # type: ignore[attr-defined,no-any-return]


def one_round(changes: int, browser: Any | None) -> dict[str, dict[str, list[float]]]:
    result: dict[str, dict[str, list[float]]] = {}
    with cpu(with_page=False) as (machine, url):
        result["idle"] = watched(url, machine, changes)
        for mode in ("clients", "flood"):
            with loaded(url, changes * 0.4 + 60, mode):
                result[mode] = watched(url, machine, changes)
    if browser is not None:
        result.update(page_round(browser, changes))
    return result


def page_round(browser: Any, changes: int) -> dict[str, dict[str, list[float]]]:
    """The page and the OPC UA subscription watching the same changes of one CPU."""
    with cpu(with_page=True) as (machine, url):
        context = browser.new_context(viewport={"width": 1280, "height": 800})
        tab = context.new_page()
        tab.add_init_script(page.HOOK)
        try:
            page.first_paint(tab, machine.url, empty=False)
            thread = watching(url, machine, changes)
            colour = page.colour_latency(tab, machine, changes)
            thread.join(changes * 0.4 + 120)
        finally:
            context.close()
    return {
        "page": thread.result,  # type: ignore[attr-defined]
        "page: colour": {"latency": colour["colour"], "missed": colour["missed"]},
    }


def report(rounds: list[dict[str, dict[str, list[float]]]], loads: list[float]) -> None:
    print(f"\nstep change -> OPC UA subscription (ms; p99 target <= {TARGET_MS:.0f})")
    print(f"{'load':16} {'n':>7} {'p50':>15} {'p99':>15} {'max':>15}  target")
    for load in rounds[0]:
        runs = [r[load] for r in rounds if load in r]
        n = [len(r["latency"]) for r in runs]
        missed = max(len(r["missed"]) for r in runs)
        p50 = [pct(r["latency"], 0.5) for r in runs]
        p99 = [pct(r["latency"], 0.99) for r in runs]
        top = [max(r["latency"], default=float("nan")) for r in runs]
        met = "met" if all(v <= TARGET_MS for v in p99) and not missed else "MISSED"
        if load == "page: colour":
            met = "(the page)"
        seen = f"{min(n)}" + (f"-{missed}" if missed else "")
        cells = (spread(v, "{:.0f}") for v in (p50, p99, top))
        print(f"{load:16} {seen:>7} " + " ".join(f"{c:>15}" for c in cells) + f"  {met}")
    if not any("page: colour" in r for r in rounds):
        print(f"{'page: colour':16} p99 as last recorded: {PAGE_RECORDED}")
    print(f"\nload average during the rounds: {spread(loads, '{:.1f}')}")


# ---------------------------------------------------------------------------- start-up


def build_worker(steps: int) -> int:
    """Build the face's address space of one FB with ``steps`` supervised steps (every
    second one with an interlock too: 1.5 conditions a step) as ``s7graph opcua`` does in
    its own process (its collector's thresholds); print the wall and CPU seconds."""
    import gc

    from asyncua import Server

    from s7graph.web.bus.protocol import ChartLayout, SequenceInfo, StepInfo
    from s7graph.web.collector import GC_THRESHOLDS
    from s7graph.web.opcua.space import Space

    gc.set_threshold(*GC_THRESHOLDS)
    numbers = list(range(1, steps + 1))
    infos = [StepInfo(number=i, supervision=True, interlock=i % 2 == 0) for i in numbers]
    sequence = SequenceInfo(number=1, steps=numbers, transitions=[])
    layout = ChartLayout(fb=FB, steps=infos, transitions=[], sequences=[sequence])

    async def build() -> tuple[float, float, int]:
        server = Server()
        await server.init()
        space = Space(server, await server.register_namespace("urn:s7graph:plc"), "cpu1")
        await space.build_cpu(None, [])
        wall, cpu = time.perf_counter(), time.process_time()
        await space.build_fb(FB, layout, [])
        nids = server.iserver.aspace.keys()
        made = sum(1 for nid in nids if nid.NamespaceIndex == 2)
        return time.perf_counter() - wall, time.process_time() - cpu, made

    wall, cpu, made = asyncio.run(build())
    print(f"{wall:.3f} {cpu:.3f} {made}")
    return 0


def startup(steps: int, repeat: int) -> int:
    """``--startup N``: the address space of ``N`` supervised steps built ``repeat``
    times, each in a process of its own; min/median/max of the wall and CPU seconds."""
    walls, cpus, loads, made = [], [], [], 0
    for _ in range(repeat):
        before = os.getloadavg()[0]
        out = subprocess.run(
            [sys.executable, __file__, "--build-worker", str(steps)],
            cwd=ROOT,
            capture_output=True,
            text=True,
            check=True,
        ).stdout.split()
        loads.append((before + os.getloadavg()[0]) / 2)
        walls.append(float(out[0]))
        cpus.append(float(out[1]))
        made = int(out[2])
    conditions = steps + steps // 2
    print(
        f"address space of {steps} supervised steps ({conditions} conditions, {made} nodes), "
        f"{repeat} process(es): wall {spread(walls)} s, CPU {spread(cpus)} s, "
        f"load average {spread(loads, '{:.1f}')}"
    )
    return 0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    ap.add_argument("--repeat", type=int, default=3, help="rounds; min/median/max over them")
    ap.add_argument("--changes", type=int, default=100, help="step changes watched per load")
    ap.add_argument("--page", action="store_true", help="the page beside, on the same CPU")
    ap.add_argument(
        "--startup",
        type=int,
        metavar="N",
        help="instead: time building the address space of N supervised steps",
    )
    ap.add_argument("--worker", nargs=6, help=argparse.SUPPRESS)
    ap.add_argument("--build-worker", type=int, help=argparse.SUPPRESS)
    ap.add_argument("--flood", nargs=3, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.worker:
        path, endpoint, url, state, port, max_cycle = args.worker
        return worker(Path(path), endpoint, url, Path(state), int(port), float(max_cycle))
    if args.flood:
        return flood(args.flood[0], float(args.flood[1]), args.flood[2])
    if args.build_worker is not None:
        return build_worker(args.build_worker)
    if args.startup is not None:
        return startup(args.startup, args.repeat)
    print(
        f"python {sys.version.split()[0]}, {os.cpu_count()} cores, loop8 at a {CYCLE_MS:g} ms "
        f"cycle (max {MAX_CYCLE_MS:g} ms), publishing interval {PUBLISHING_MS:g} ms, "
        f"{args.changes} changes per load, {args.repeat} round(s)"
    )
    rounds, loads = [], []
    playwright = browser = None
    if args.page:
        from playwright.sync_api import sync_playwright

        playwright = sync_playwright().start()
        browser = playwright.chromium.launch(
            executable_path=page.CHROMIUM, headless=True, args=page.CHROMIUM_ARGS
        )
    try:
        for i in range(args.repeat):
            before = os.getloadavg()[0]
            r = one_round(args.changes, browser)
            loads.append((before + os.getloadavg()[0]) / 2)
            rounds.append(r)
            shown = ", ".join(
                f"{k} p50 {pct(v['latency'], 0.5):.0f} p99 {pct(v['latency'], 0.99):.0f}"
                + (f" ({len(v['missed'])} missed)" if v["missed"] else "")
                for k, v in r.items()
            )
            print(f"  round {i + 1}: {shown}; load {loads[-1]:.1f}", flush=True)
    finally:
        if browser is not None:
            browser.close()
        if playwright is not None:
            playwright.stop()
    report(rounds, loads)
    return 0


if __name__ == "__main__":
    sys.exit(main())
