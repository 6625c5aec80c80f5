"""Bus benchmark: what s7graph adds to zenoh between a step change in the CPU and the view's
delta callback in another process, and how many deltas a second it carries (run as
``python bench/bus.py``; see bench/README.md).

The CPU side runs in this process: the 200 sequencers of ``bench/scan.py`` (``--layout``
``packed``: 25 FBs of 8, ``single``: 200 FBs of 1) on the system clock, paced by the
engine's ``Runner``, each FB seen by a ``LiveGraph`` (one ``ScanEvents`` shared by all) and
published by one ``BusPublisher`` after every scan. ``--path batched`` (the default):
``web.bus.fb_deltas.publish_fbs`` — ``LiveGraph.changed`` (an update only for an FB that
may have changed), the FBs whose steps switched first, a message on ``deltas`` every
``--part`` changed FBs (default ``web.bus.deltas.PART``; 0: one message per scan) while
the scan thread builds the rest, and (a) replays messages of those sizes;
``--path per-fb``: ``LiveGraph.update`` and ``BusPublisher.publish`` for every FB, one
message per FB and scan (the way of the code before ``deltas``). The other side is a
second process (this file with ``--peer``) on its own zenoh session, connected over a
unix socket: it follows every FB with ``BusClient.follow`` (decode, ``seq`` order: the
view's code), what it built to start frozen as the view's process freezes its own
(``web.collector.freeze_start``), and subscribes to a raw key; with ``--old-readers`` it
also subscribes to every FB's own ``fb/<fb>/delta`` and decodes what comes there, as a
reader of the old key would (the CPU then puts each delta there too). Times are
``CLOCK_MONOTONIC``, which both processes share. In each round, per layout:

(a) **raw zenoh**: at every 10 ms tick, the messages the CPU published in the same tick
    of (b) — batched: one message carrying as many real encoded deltas as that scan's;
    per-fb: as many puts as deltas, each a real encoded delta — the sample's id in the
    attachment; latency = put → subscriber callback;
(b) **step change → delta callback**: the CPU at a 10 ms cycle; latency = end of the scan
    in which steps switched → the follower's callback with that FB's delta. The difference
    to (a) is what s7graph adds (LiveGraph, the publisher, its outbox thread, decoding);
(c) **throughput**: the CPU scanning back to back for ``--seconds``; deltas/s = deltas the
    other process received ÷ time until the last was sent; beside it raw zenoh carrying
    the messages of (a) back to back for as long (batched: each with as many deltas as a
    typical scan of (b)). The scan thread's time in ``Cpu.scan()`` and in the bus (the
    LiveGraph and ``BusPublisher``), and the process's CPU time beyond the scans (the bus
    all included: outbox thread, zenoh's threads), per scan; the deltas received per CPU
    second of this process and of the peer — what one core of each would carry, which the
    machine's load changes less than the deltas per second.

Targets: ≥ 20,000 deltas/s; the bus costing at most as much as the scan; added
p99 ≤ 2 ms over raw zenoh. ``--repeat`` rounds; min/median/max over them; the load
average at the start, after each round and at the end.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

import msgspec  # noqa: E402
import zenoh  # noqa: E402
from figures import pct, spread  # noqa: E402

from s7graph.engine.clock import SystemClock  # noqa: E402
from s7graph.engine.record import ScanRecord  # noqa: E402
from s7graph.engine.runner import Runner  # noqa: E402
from s7graph.engine.switching import switching  # noqa: E402
from s7graph.engine.watchdog import Watchdog  # noqa: E402
from s7graph.web.bus.client import BusClient  # noqa: E402
from s7graph.web.bus.deltas import PART  # noqa: E402
from s7graph.web.bus.fb_deltas import publish_fbs  # noqa: E402
from s7graph.web.bus.keys import keys  # noqa: E402
from s7graph.web.bus.live import LiveGraph  # noqa: E402
from s7graph.web.bus.protocol import ScanDeltas, StepStateUpdate, decode, encode  # noqa: E402
from s7graph.web.bus.publisher import BusPublisher  # noqa: E402
from s7graph.web.bus.scan_events import ScanEvents  # noqa: E402
from s7graph.web.bus.session import open_session  # noqa: E402
from s7graph.web.collector import freeze_start  # noqa: E402

RAW_KEY = "s7graph-bench/raw"
CYCLE_MS = 10.0
TARGET_RATE = 20_000
TARGET_ADDED_P99_MS = 2.0


# ---------------------------------------------------------------------------- the peer


def peer(endpoint: str, cpus: dict[str, list[str]], old_readers: bool = False) -> int:
    """The other process: follow every FB of ``cpus`` and the raw key (and, with
    ``old_readers``, every FB's own key); on ``dump`` print what came since the last dump
    as one JSON line."""
    lock = threading.Lock()
    raw: list[tuple[int, int]] = []
    deltas: dict[str, list[tuple[int, int]]] = {}
    old: list[int] = [0]
    subs = []
    with open_session(connect=[endpoint]) as session:

        def on_old(sample: zenoh.Sample) -> None:
            decode(sample.payload.to_bytes(), StepStateUpdate)
            old[0] += 1

        def on_raw(sample: zenoh.Sample) -> None:
            t = time.monotonic_ns()
            att = sample.attachment
            if att is not None:
                with lock:
                    raw.append((int.from_bytes(att.to_bytes(), "little"), t))

        sub = session.declare_subscriber(RAW_KEY, on_raw)
        clients = []
        for cpu, fbs in cpus.items():
            client = BusClient(session, cpu)
            clients.append(client)
            for fb in fbs:
                name = f"{cpu}/{fb}"
                got = deltas.setdefault(name, [])

                def on_update(u: StepStateUpdate, got: list[tuple[int, int]] = got) -> None:
                    got.append((u.seq, time.monotonic_ns()))

                client.follow(fb, on_update)
                if old_readers:
                    subs.append(session.declare_subscriber(keys(cpu).fb(fb, "delta"), on_old))
        freeze_start()  # as the view's process does (``s7graph web``)
        print("ready", flush=True)
        try:
            for line in sys.stdin:
                if line.strip() != "dump":
                    break
                with lock:
                    out = {"raw": raw[:], "deltas": {k: v[:] for k, v in deltas.items()}}
                    out["old"] = old[0]
                    out["cpu_ns"] = time.process_time_ns()
                    old[0] = 0
                    raw.clear()
                    for v in deltas.values():
                        v.clear()
                print(json.dumps(out), flush=True)
        finally:
            for client in clients:
                client.close()
            for s in (sub, *subs):
                s.undeclare()  # type: ignore[no-untyped-call]
    return 0


class Peer:
    """The peer process, started and stopped by the CPU side."""

    def __init__(self, endpoint: str, cpus: dict[str, list[str]], old_readers: bool) -> None:
        extra = ["--old-readers"] if old_readers else []
        self.proc = subprocess.Popen(
            [sys.executable, __file__, "--peer", endpoint, "--cpus", json.dumps(cpus), *extra],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
        )
        assert self.proc.stdout is not None
        line = self.proc.stdout.readline()
        if line.strip() != "ready":
            raise RuntimeError(f"the peer did not start: {line!r}")

    def dump(self) -> dict[str, Any]:
        assert self.proc.stdin is not None and self.proc.stdout is not None
        self.proc.stdin.write("dump\n")
        self.proc.stdin.flush()
        return json.loads(self.proc.stdout.readline())  # type: ignore[no-any-return]

    def close(self) -> None:
        if self.proc.stdin is not None:
            self.proc.stdin.close()
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()


# ---------------------------------------------------------------------------- the CPU side


@dataclass
class Cpu:
    """One layout of the workload as a CPU on the bus."""

    layout: str
    session: zenoh.Session
    path: str = "batched"
    part: int = PART  # batched: at most this many deltas a message (0: a scan's all)
    workload: Any = None
    lives: list[LiveGraph] = field(default_factory=list)
    publisher: BusPublisher | None = None
    seq: dict[str, int] = field(default_factory=dict)
    last: dict[str, StepStateUpdate] = field(default_factory=dict)

    def __post_init__(self) -> None:
        from scan import EngineWorkload

        self.workload = EngineWorkload(self.layout, SystemClock())
        # the CPU pauses between the phases: no time error for that
        self.workload.cpu.watchdog = Watchdog(max_cycle_ms=600_000)
        events = ScanEvents()
        self.lives = [LiveGraph(g, events=events) for g in self.workload.fbs]
        charts = {live.fb: live.layout for live in self.lives}
        self.publisher = BusPublisher(self.session, self.layout, charts)
        self.seq = dict.fromkeys(charts, 0)

    @property
    def fbs(self) -> list[str]:
        return [live.fb for live in self.lives]

    def publish(self, record: ScanRecord) -> list[tuple[str, int, bool]]:
        """Every FB's update published; (fb, seq, steps switched) of the deltas sent."""
        publisher = self.publisher
        assert publisher is not None
        seq = self.seq
        last = self.last
        sent = []
        if self.path == "batched":
            for fb, update in publish_fbs(publisher, self.lives, record, part=self.part):
                seq[fb] += 1
                last[fb] = update
                sent.append((fb, seq[fb], bool(update.events)))
            return sent
        for live in self.lives:
            update = live.update(record)
            last[live.fb] = update
            if publisher.publish(live.fb, update):
                seq[live.fb] += 1
                sent.append((live.fb, seq[live.fb], bool(update.events)))
        return sent

    def parts(self, count: int) -> list[int]:
        """The sizes of the messages that carry a scan's ``count`` deltas (batched)."""
        if not self.part or count <= self.part:
            return [count] if count else []
        whole, rest = divmod(count, self.part)
        return [self.part] * whole + ([rest] if rest else [])

    def payloads(self, per_scan: list[int]) -> list[bytes]:
        """Real encoded messages for (a) to replay: per-fb, a delta of each FB; batched, per
        number of deltas a scan of (b) sent, a ``deltas`` message carrying as many."""
        updates = [msgspec.structs.replace(self.last[fb], seq=1) for fb in self.fbs]
        if self.path != "batched":
            return [encode(u) for u in updates]
        out = [b""]
        for n in range(1, max(per_scan, default=0) + 1):
            fbs = {fb: updates[k] for k, fb in enumerate(self.fbs[:n])}
            out.append(encode(ScanDeltas(seq=1, cycle=1, t_ms=1, fbs=fbs)))
        return out

    def drain(self, timeout: float = 30.0) -> None:
        assert self.publisher is not None
        deadline = time.monotonic() + timeout
        while self.publisher.outbox.pending() and time.monotonic() < deadline:
            time.sleep(0.002)

    def close(self) -> None:
        if self.publisher is not None:
            self.publisher.close()


def run_cpu(
    cpu: Cpu, seconds: float, cycle_ms: float, on_record: Callable[[ScanRecord], None]
) -> Runner:
    runner = Runner(cpu.workload.cpu, cycle_ms=cycle_ms, on_record=on_record)
    runner.run(duration_s=seconds)
    return runner


def latency_cpu(cpu: Cpu, peer_: Peer, seconds: float) -> tuple[list[float], list[int]]:
    """(b): ms from the end of a scan that switched steps to the delta callback; and the
    deltas sent per scan (for (a) to replay)."""
    sent_at: dict[tuple[str, int], int] = {}
    per_scan: list[int] = []

    def on_record(record: ScanRecord) -> None:
        t0 = time.monotonic_ns()
        sent = cpu.publish(record)
        per_scan.append(len(sent))
        for fb, seq, switched in sent:
            if switched:
                sent_at[(fb, seq)] = t0

    peer_.dump()
    run_cpu(cpu, seconds, CYCLE_MS, on_record)
    cpu.drain()
    time.sleep(0.3)
    got = peer_.dump()["deltas"]
    out = []
    for name, samples in got.items():
        _, fb = name.split("/", 1)
        if not name.startswith(cpu.layout + "/"):
            continue
        for seq, t in samples:
            t0 = sent_at.get((fb, seq))
            if t0 is not None:
                out.append((t - t0) / 1e6)
    return out, per_scan


def latency_raw(cpu: Cpu, peer_: Peer, session: zenoh.Session, per_scan: list[int]) -> list[float]:
    """(a): ms from put to the raw subscriber's callback, the same traffic as (b)."""
    pub = session.declare_publisher(
        RAW_KEY,
        encoding=zenoh.Encoding.APPLICATION_JSON,
        congestion_control=zenoh.CongestionControl.BLOCK,
    )
    assert cpu.publisher is not None
    payloads = cpu.payloads(per_scan)  # real deltas
    batched = cpu.path == "batched"
    sent_at: dict[int, int] = {}
    n = 0
    try:
        peer_.dump()
        due = time.monotonic()
        for count in per_scan:
            sizes = cpu.parts(count) if batched else [1] * count
            for k, size in enumerate(sizes):
                n += 1
                t0 = time.monotonic_ns()
                data = payloads[size] if batched else payloads[k % len(payloads)]
                pub.put(data, attachment=n.to_bytes(8, "little"))
                sent_at[n] = t0
            due += CYCLE_MS / 1000
            delay = due - time.monotonic()
            if delay > 0:
                time.sleep(delay)
        time.sleep(0.3)
        got = peer_.dump()["raw"]
    finally:
        pub.undeclare()  # type: ignore[no-untyped-call]
    return [(t - sent_at[i]) / 1e6 for i, t in got if i in sent_at]


@dataclass
class Throughput:
    rate: float  # deltas/s received by the peer
    sent: int
    received: int
    scan_us: float  # CPU time per scan in Cpu.scan()
    bus_us: float  # CPU time per scan of the scan thread in LiveGraph.update + publish
    cpu_us: float  # per scan, the process's CPU time beyond Cpu.scan() (all threads)
    dropped: int
    old: int  # deltas the peer's readers of the FBs' own keys received
    per_cpu_s: float  # deltas received per CPU second of this process
    peer_per_cpu_s: float  # and of the peer process


def throughput(cpu: Cpu, peer_: Peer, seconds: float) -> Throughput:
    """(c): back-to-back scans for ``seconds``, every FB published after each, as the
    runner's loop does (with its switch interval, ``engine.switching``); CPU times of this thread
    (robust to other processes' load)."""
    assert cpu.publisher is not None
    scan = cpu.workload.cpu.scan
    publish = cpu.publish
    clock = time.thread_time_ns
    dropped0 = cpu.publisher.outbox.dropped
    peer0 = peer_.dump()["cpu_ns"]
    scans = sent = scan_ns = bus_ns = 0
    start = time.monotonic()
    deadline = start + seconds
    cpu0 = time.process_time_ns()
    with switching():
        while time.monotonic() < deadline:
            t0 = clock()
            record = scan()
            t1 = clock()
            sent += len(publish(record))
            bus_ns += clock() - t1
            scan_ns += t1 - t0
            scans += 1
    cpu.drain()
    end = time.monotonic()
    cpu_ns = time.process_time_ns() - cpu0
    time.sleep(0.5)
    dump = peer_.dump()
    got = dump["deltas"]
    received = sum(len(v) for k, v in got.items() if k.startswith(cpu.layout + "/"))
    scans = max(scans, 1)
    peer_ns = max(dump["cpu_ns"] - peer0, 1)
    return Throughput(
        rate=received / (end - start),
        sent=sent,
        received=received,
        scan_us=scan_ns / scans / 1e3,
        bus_us=bus_ns / scans / 1e3,
        cpu_us=(cpu_ns - scan_ns) / scans / 1e3,
        dropped=cpu.publisher.outbox.dropped - dropped0,
        old=dump["old"],
        per_cpu_s=received / (cpu_ns / 1e9),
        peer_per_cpu_s=received / (peer_ns / 1e9),
    )


def throughput_raw(
    cpu: Cpu, peer_: Peer, session: zenoh.Session, per_scan: list[int], seconds: float
) -> float:
    """(c) for raw zenoh: the messages of (b) — batched, one carrying as many deltas as a
    typical scan of (b) sent; per-fb, one delta each — put back to back for ``seconds``;
    deltas the peer's raw subscriber received ÷ time."""
    pub = session.declare_publisher(
        RAW_KEY,
        encoding=zenoh.Encoding.APPLICATION_JSON,
        congestion_control=zenoh.CongestionControl.BLOCK,
    )
    payloads = cpu.payloads(per_scan)
    typical = max(round(statistics.median(per_scan or [1])), 1)
    typical = min(typical, cpu.part or typical)
    batched = cpu.path == "batched"
    each = typical if batched else 1
    data = payloads[typical] if batched else payloads[0]
    n = 0
    try:
        peer_.dump()
        start = time.monotonic()
        deadline = start + seconds
        while time.monotonic() < deadline:
            n += 1
            pub.put(data, attachment=n.to_bytes(8, "little"))
        end = time.monotonic()
        time.sleep(0.5)
        got = len(peer_.dump()["raw"])
    finally:
        pub.undeclare()  # type: ignore[no-untyped-call]
    return got * each / (end - start)


def record(
    res: dict[str, list[float]],
    a: list[float],
    b: list[float],
    per_scan: list[int],
    t: Throughput,
    raw_rate: float,
) -> None:
    """Keep one round's figures of one layout."""

    def add(key: str, value: float) -> None:
        res.setdefault(key, []).append(value)

    for q, name in ((0.5, "p50"), (0.99, "p99")):
        add(f"raw {name}", pct(a, q))
        add(f"cpu {name}", pct(b, q))
        add(f"added {name}", pct(b, q) - pct(a, q))
    add("samples", len(b))
    add("raw rate", raw_rate)
    add("rate/raw", t.rate / raw_rate if raw_rate else float("nan"))
    add("deltas/scan", statistics.fmean(per_scan))
    for k in ("rate", "scan_us", "bus_us", "cpu_us", "per_cpu_s", "peer_per_cpu_s"):
        add(k, getattr(t, k))
    add("bus/scan", t.bus_us / t.scan_us)
    add("cpu/scan", t.cpu_us / t.scan_us)
    add("lost", t.sent - t.received)
    add("dropped", t.dropped)
    add("old", t.old / max(t.received, 1))


def one_line(a: list[float], b: list[float], t: Throughput, raw_rate: float) -> str:
    return (
        f"raw p50/p99 {pct(a, 0.5):.3f}/{pct(a, 0.99):.3f} ms, CPU→callback "
        f"{pct(b, 0.5):.3f}/{pct(b, 0.99):.3f} ms ({len(b)} deltas); {t.rate:,.0f} deltas/s "
        f"(raw zenoh {raw_rate:,.0f}; {t.per_cpu_s:,.0f} per CPU second, the peer "
        f"{t.peer_per_cpu_s:,.0f}), "
        f"scan {t.scan_us:.0f} µs, bus {t.bus_us:.0f} µs in the scan thread, {t.cpu_us:.0f} µs "
        f"CPU beyond the scan; lost {t.sent - t.received}, dropped {t.dropped}"
        + (f", old-key readers got {t.old}" if t.old else "")
    )


def verdict(r: dict[str, list[float]]) -> str:
    """The targets, met or the distance (medians of the rounds)."""
    rate = statistics.median(r["rate"])
    added = statistics.median(r["added p99"])
    ratio = statistics.median(r["bus/scan"])
    total = statistics.median(r["cpu/scan"])
    out = [
        f">= {TARGET_RATE:,} deltas/s "
        + ("met" if rate >= TARGET_RATE else f"missed by {TARGET_RATE - rate:,.0f}")
        + f" ({rate:,.0f})",
        "bus <= scan "
        + ("met" if ratio <= 1 else f"missed, {ratio:.2f}x")
        + f" ({ratio:.2f}x in the scan thread, {total:.2f}x with all the process's CPU)",
        f"added p99 <= {TARGET_ADDED_P99_MS:g} ms "
        + (
            "met"
            if added <= TARGET_ADDED_P99_MS
            else f"missed by {added - TARGET_ADDED_P99_MS:.2f}"
        )
        + f" ({added:.3f} ms)",
    ]
    return "; ".join(out)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seconds", type=float, default=5.0, help="per phase and round (5)")
    ap.add_argument("--repeat", type=int, default=3, help="rounds (3)")
    ap.add_argument("--layout", choices=("packed", "single", "both"), default="both")
    ap.add_argument(
        "--path",
        choices=("batched", "per-fb"),
        default="batched",
        help="batched: publish_fbs, switched FBs first, a message every --part (default); "
        "per-fb: LiveGraph.update + publish for every FB, one message per FB and scan",
    )
    ap.add_argument(
        "--part",
        type=int,
        default=PART,
        help="batched: a message leaves every PART changed FBs, while the scan's others "
        f"are still being built (0: one message a scan; default {PART}, as web.bus.deltas)",
    )
    ap.add_argument(
        "--old-readers",
        action="store_true",
        help="the peer also subscribes to every FB's own fb/<fb>/delta key",
    )
    ap.add_argument("--peer", help=argparse.SUPPRESS)
    ap.add_argument("--cpus", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.peer:
        return peer(args.peer, json.loads(args.cpus), args.old_readers)

    layouts = ("packed", "single") if args.layout == "both" else (args.layout,)
    print(
        f"python {sys.version.split()[0]}, {os.cpu_count()} cores; {args.repeat} rounds, "
        f"{args.seconds:g} s per phase; CPU and peer processes over a unix socket; path "
        f"{args.path}" + (", old-key readers" if args.old_readers else "")
    )
    print("load average at the start: " + load())
    res: dict[str, dict[str, list[float]]] = {lay: {} for lay in layouts}

    with tempfile.TemporaryDirectory(prefix="s7graph-busbench-") as tmp:
        endpoint = f"unixsock-stream/{tmp}/bus.sock"
        with open_session(listen=[endpoint]) as session:
            cpus = {lay: Cpu(lay, session, args.path, args.part) for lay in layouts}
            for cpu in cpus.values():
                cpu.workload.cpu.start("warm")
            peer_ = Peer(endpoint, {lay: cpu.fbs for lay, cpu in cpus.items()}, args.old_readers)
            try:
                for r in range(args.repeat):
                    for lay, cpu in cpus.items():
                        b, per_scan = latency_cpu(cpu, peer_, args.seconds)
                        a = latency_raw(cpu, peer_, session, per_scan)
                        t = throughput(cpu, peer_, args.seconds)
                        raw_rate = throughput_raw(cpu, peer_, session, per_scan, args.seconds)
                        record(res[lay], a, b, per_scan, t, raw_rate)
                        print(f"round {r + 1} {lay}: " + one_line(a, b, t, raw_rate), flush=True)
                        print(f"  load average: {load()}", flush=True)
            finally:
                peer_.close()
                for cpu in cpus.values():
                    cpu.close()
    print()
    print(f"{'min/median/max':26}" + "".join(f"{lay:>32}" for lay in layouts))
    rows = [
        ("raw zenoh p50 ms", "raw p50", "{:.3f}"),
        ("raw zenoh p99 ms", "raw p99", "{:.3f}"),
        ("CPU→delta p50 ms", "cpu p50", "{:.3f}"),
        ("CPU→delta p99 ms", "cpu p99", "{:.3f}"),
        ("added p50 ms", "added p50", "{:.3f}"),
        ("added p99 ms", "added p99", "{:.3f}"),
        ("deltas/s", "rate", "{:,.0f}"),
        ("raw zenoh deltas/s", "raw rate", "{:,.0f}"),
        ("deltas/s ÷ raw zenoh", "rate/raw", "{:.2f}"),
        ("deltas per CPU s (CPU)", "per_cpu_s", "{:,.0f}"),
        ("deltas per CPU s (peer)", "peer_per_cpu_s", "{:,.0f}"),
        ("deltas per scan", "deltas/scan", "{:.0f}"),
        ("scan µs", "scan_us", "{:.0f}"),
        ("bus µs (scan thread)", "bus_us", "{:.0f}"),
        ("bus ÷ scan (scan thread)", "bus/scan", "{:.2f}"),
        ("CPU µs beyond the scan", "cpu_us", "{:.0f}"),
        ("that ÷ scan", "cpu/scan", "{:.2f}"),
        ("deltas lost", "lost", "{:.0f}"),
        ("deltas dropped (outbox)", "dropped", "{:.0f}"),
    ]
    if args.old_readers:
        rows.append(("old-key deltas ÷ followed", "old", "{:.2f}"))
    for label, key, fmt in rows:
        cells = (spread(res[lay][key], fmt) for lay in layouts)
        print(f"{label:26}" + "".join(f" {cell:>31}" for cell in cells))  # one blank at least
    print()
    for lay in layouts:
        print(f"targets, {lay}: " + verdict(res[lay]))
    print("load average at the end: " + load())
    return 0


def load() -> str:
    """The 1, 5 and 15 minute load averages."""
    return "/".join(f"{x:.2f}" for x in os.getloadavg())


if __name__ == "__main__":
    sys.exit(main())
