"""Scan-time benchmark: 200 GRAPH sequencers on the soft CPU vs. the same workload in
``transitions`` (run as ``python bench/scan.py``; see bench/README.md).

Workload (DESIGN "a scan costs in proportion to the active steps"): 200 sequencers, each a
loop of 25 steps (5000 steps, 200 active at any time). Every step holds

    S1 N c := 0;  N c := c + 1;      // an assignment every call (reset on activation)
    D Mb.d, T#20MS;  L Mb.l, T#20MS; // an on-delay and a pulse bit
    TRANSITION ... := c >= p;        // a comparison; p = 2, 3, 4 by sequencer

so a sequencer advances every ``p`` calls (phases drift, about 1/3 of the sequencers switch
per scan) and its D and L bits toggle inside every step at the 10 ms virtual cycle. Layout
(``--layout``): ``packed`` = 25 FBs of 8 sequencers each (SPEC §2.1 allows 1..8 per FB; the
default), ``single`` = 200 FBs of one sequencer each. The FBs are called from OB1 of one
``engine.cpu.Cpu`` driven by a ``VirtualClock`` advanced 10 ms per scan; the wall time of
``Cpu.scan()`` is measured with ``perf_counter_ns``.

Baseline: one ``transitions.Machine`` per sequencer (25 states, one ``scan`` trigger per scan
whose condition is a model callback ``c >= p``, ``after_state_change`` resets ``c`` and the
step's start time), then the same per-scan actions (``c += 1``, the D and L bits written into
a marker bytearray) in plain Python. Same number of scans, same virtual clock.

Also: parse and compile time of one 250-step chart (target: compile <= 100 ms).
"""

from __future__ import annotations

import argparse
import cProfile
import io
import pstats
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from engine.clock import VirtualClock  # noqa: E402
from engine.cpu import Cpu  # noqa: E402
from sequencer.compile import compile_chart  # noqa: E402
from sequencer.fb import GraphFB, install_all  # noqa: E402
from sequencer.parse import parse_chart  # noqa: E402

N_SEQUENCERS = 200
STEPS = 25
CYCLE_MS = 10
D_MS = 20
L_MS = 20


def threshold(g: int) -> int:
    """The transition threshold ``p`` of global sequencer ``g`` (2, 3 or 4)."""
    return 2 + g % 3


def marker_bits(g: int) -> tuple[str, str]:
    """The D and L operand of global sequencer ``g``: two bits of MB(g // 4)."""
    byte, bit = divmod(g, 4)
    return f"M{byte}.{2 * bit}", f"M{byte}.{2 * bit + 1}"


def chart_source(fb: int, first_g: int, n_seq: int, steps: int = STEPS) -> str:
    """The ``.s7g`` text (SPEC §3) of FB ``fb`` holding sequencers ``first_g ..``."""
    out = [
        f'FUNCTION_BLOCK "Bench_{fb}" FB {fb} DB {fb}',
        "  PARAMETERS := STANDARD;",
        "VAR",
        *(f"  c{s} : INT := 0;" for s in range(n_seq)),
        "END_VAR",
    ]
    for s in range(n_seq):
        g = first_g + s
        d_bit, l_bit = marker_bits(g)
        base = s * steps
        out.append(f'SEQUENCE {s + 1} "Loop_{g}"')
        for k in range(1, steps + 1):
            kw = "INITIAL_STEP" if k == 1 else "STEP"
            out += [
                f'  {kw} S{base + k} "s{k}":',
                f"    S1 N c{s} := 0;  N c{s} := c{s} + 1;",
                f"    D {d_bit}, T#{D_MS}MS;  L {l_bit}, T#{L_MS}MS;",
                "  END_STEP",
            ]
        for k in range(1, steps + 1):
            nxt = base + k % steps + 1
            out.append(
                f"  TRANSITION T{base + k} FROM S{base + k} TO S{nxt} := c{s} >= {threshold(g)};"
            )
        out.append("END_SEQUENCE")
    out.append("END_FUNCTION_BLOCK")
    return "\n".join(out) + "\n"


def stats(samples_ns: list[int]) -> dict[str, float]:
    """Mean, median, p99 and max in milliseconds."""
    s = sorted(samples_ns)
    p99 = s[min(len(s) - 1, int(0.99 * len(s)))]
    return {
        "mean": statistics.fmean(s) / 1e6,
        "p50": s[len(s) // 2] / 1e6,
        "p99": p99 / 1e6,
        "max": s[-1] / 1e6,
    }


# ---------------------------------------------------------------------------- the engine


def build_cpu(layout: str) -> tuple[Cpu, VirtualClock, list[GraphFB]]:
    per_fb = 8 if layout == "packed" else 1
    clock = VirtualClock()
    cpu = Cpu(clock)
    fbs = []
    for f in range(N_SEQUENCERS // per_fb):
        text = chart_source(f + 1, f * per_fb, per_fb)
        cc = compile_chart(parse_chart(text, f"<bench FB{f + 1}>"))
        fbs.append(GraphFB(cc))
    install_all(cpu, fbs)
    cpu.start("warm")
    return cpu, clock, fbs


def run_engine(layout: str, scans: int, warmup: int, profile: bool) -> dict[str, float]:
    cpu, clock, fbs = build_cpu(layout)
    for _ in range(warmup):
        clock.advance(CYCLE_MS)
        cpu.scan()
    active = sum(len(g.state.active) for g in fbs)
    samples: list[int] = []
    switches = 0
    prof = cProfile.Profile() if profile else None
    perf = time.perf_counter_ns
    for _ in range(scans):
        clock.advance(CYCLE_MS)
        if prof is not None:
            prof.enable()
        t0 = perf()
        rec = cpu.scan()
        samples.append(perf() - t0)
        if prof is not None:
            prof.disable()
        switches += sum(1 for e in rec.events if getattr(e, "event", "") == "S1")
    assert str(cpu.mode).endswith("RUN"), f"CPU left RUN: {cpu.mode}"
    assert active == N_SEQUENCERS, f"{active} active steps, expected {N_SEQUENCERS}"
    result = stats(samples)
    result["active"] = active
    result["switches_per_scan"] = switches / scans
    result["fbs"] = len(fbs)
    if prof is not None:
        buf = io.StringIO()
        pstats.Stats(prof, stream=buf).sort_stats("tottime").print_stats(20)
        print(buf.getvalue())
    return result


# ---------------------------------------------------------------------------- transitions


def run_transitions(scans: int, warmup: int) -> dict[str, float]:
    from transitions import Machine

    class Seq:
        """One sequencer: ``c`` and the step's start time; D/L bits go to ``mem``."""

        def __init__(self, g: int, mem: bytearray) -> None:
            self.p = threshold(g)
            self.c = 0
            self.now = 0
            self.since = 0
            self.mem = mem
            self.byte, bit = divmod(g, 4)
            self.d_mask = 1 << (2 * bit)
            self.l_mask = 1 << (2 * bit + 1)

        def ready(self) -> bool:
            return self.c >= self.p

        def entered(self) -> None:
            self.c = 0
            self.since = self.now

        def act(self) -> None:
            self.c += 1
            elapsed = self.now - self.since
            v = self.mem[self.byte] & ~(self.d_mask | self.l_mask)
            if elapsed >= D_MS:
                v |= self.d_mask
            if elapsed < L_MS:
                v |= self.l_mask
            self.mem[self.byte] = v

    states = [f"s{k}" for k in range(STEPS)]
    table = [
        {"trigger": "scan", "source": states[k], "dest": states[(k + 1) % STEPS],
         "conditions": "ready"}
        for k in range(STEPS)
    ]  # fmt: skip
    mem = bytearray(64)
    seqs = []
    for g in range(N_SEQUENCERS):
        m = Seq(g, mem)
        Machine(model=m, states=states, transitions=table, initial=states[0],
                auto_transitions=False, after_state_change="entered")  # fmt: skip
        seqs.append(m)

    now = 0
    samples: list[int] = []
    perf = time.perf_counter_ns
    for n in range(warmup + scans):
        now += CYCLE_MS
        t0 = perf()
        for m in seqs:
            m.now = now
            m.scan()  # type: ignore[attr-defined]
            m.act()
        if n >= warmup:
            samples.append(perf() - t0)
    return stats(samples)


# ---------------------------------------------------------------------------- compile time


def time_compile(steps: int = 250, repeat: int = 5) -> dict[str, float]:
    """Median parse and compile time (ms) of one chart with one ``steps``-step loop."""
    text = chart_source(1, 0, 1, steps)
    parse_ms, compile_ms = [], []
    for _ in range(repeat):
        t0 = time.perf_counter()
        chart = parse_chart(text, "<bench 250>")
        t1 = time.perf_counter()
        compile_chart(chart)
        t2 = time.perf_counter()
        parse_ms.append((t1 - t0) * 1e3)
        compile_ms.append((t2 - t1) * 1e3)
    return {"parse": statistics.median(parse_ms), "compile": statistics.median(compile_ms)}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scans", type=int, default=1000, help="measured scans (default 1000)")
    ap.add_argument("--warmup", type=int, default=100, help="unmeasured scans first")
    ap.add_argument("--layout", choices=("packed", "single", "both"), default="both")
    ap.add_argument("--profile", action="store_true", help="cProfile the engine scans")
    args = ap.parse_args(argv)

    line: Callable[..., None] = print
    line(f"python {sys.version.split()[0]}, {N_SEQUENCERS} sequencers x {STEPS} steps, "
         f"{args.scans} scans of {CYCLE_MS} ms virtual time")  # fmt: skip
    base = run_transitions(args.scans, args.warmup)
    line(f"transitions   mean {base['mean']:.3f} ms  p50 {base['p50']:.3f}  "
         f"p99 {base['p99']:.3f}  max {base['max']:.3f}")  # fmt: skip
    layouts = ("packed", "single") if args.layout == "both" else (args.layout,)
    for layout in layouts:
        r = run_engine(layout, args.scans, args.warmup, args.profile)
        per_step_us = r["mean"] * 1e3 / r["active"]
        line(f"engine {layout:6} mean {r['mean']:.3f} ms  p50 {r['p50']:.3f}  "
             f"p99 {r['p99']:.3f}  max {r['max']:.3f}  ({int(r['fbs'])} FBs, "
             f"{int(r['active'])} active, {r['switches_per_scan']:.1f} switches/scan)")  # fmt: skip
        line(f"       {layout:6} {per_step_us:.2f} us per active step; "
             f"transitions/engine = {base['mean'] / r['mean']:.2f}x "
             f"(target >= 10x, mean <= 2 ms)")  # fmt: skip
    c = time_compile()
    line(f"250-step chart: parse {c['parse']:.1f} ms, compile {c['compile']:.1f} ms "
         f"(target compile <= 100 ms)")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
