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
a marker bytearray) in plain Python. Same number of scans, same virtual clock. The workloads
run in rounds of 50 scans each, in turn, so load from other processes on the machine hits
them alike; at the end the run checks that the engine and the baseline left every
sequencer in the same step with the same D/L bits (exit status 1 if not).

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
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from s7graph.engine.clock import VirtualClock
from s7graph.engine.cpu import Cpu
from s7graph.sequencer.compile import compile_chart
from s7graph.sequencer.fb import GraphFB, install_all
from s7graph.sequencer.parse import parse_chart

N_SEQUENCERS = 200
STEPS = 25
CYCLE_MS = 10
D_MS = 20
L_MS = 20
BLOCK = 50  # scans per workload per round


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


class EngineWorkload:
    """The sequencers as GraphFBs called from OB1 of one CPU on a virtual clock."""

    def __init__(self, layout: str) -> None:
        per_fb = 8 if layout == "packed" else 1
        self.name = f"engine {layout}"
        self.clock = VirtualClock()
        self.cpu = Cpu(self.clock)
        self.fbs = []
        for f in range(N_SEQUENCERS // per_fb):
            text = chart_source(f + 1, f * per_fb, per_fb)
            cc = compile_chart(parse_chart(text, f"<bench FB{f + 1}>"))
            self.fbs.append(GraphFB(cc))
        install_all(self.cpu, self.fbs)
        self.cpu.start("warm")  # OB100 calls each FB once: initial steps, their rows run
        self.switches = 0
        self.profile: cProfile.Profile | None = None

    def scan(self) -> int:
        """One scan; returns its wall time in ns."""
        self.clock.advance(CYCLE_MS)
        prof = self.profile
        if prof is not None:
            prof.enable()
        t0 = time.perf_counter_ns()
        rec = self.cpu.scan()
        dt = time.perf_counter_ns() - t0
        if prof is not None:
            prof.disable()
        self.switches += sum(1 for e in rec.events if getattr(e, "event", "") == "S1")
        return dt

    def active(self) -> int:
        return sum(len(g.state.active) for g in self.fbs)

    def positions(self) -> list[int]:
        """The step (0..24) each sequencer is in, in global sequencer order."""
        out = []
        for g in self.fbs:
            cc = g.cc
            by_seq = {cc.step_seq[i]: (cc.step_numbers[i] - 1) % STEPS for i in g.state.active}
            out += [by_seq[k] for k in range(len(cc.seq_numbers))]
        return out

    def markers(self) -> bytes:
        return bytes(self.cpu.mem.markers[: N_SEQUENCERS // 4])


# ---------------------------------------------------------------------------- transitions


class _Seq:
    """One ``transitions`` model: ``c`` and the step's start time; D/L bits go to ``mem``."""

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


class TransitionsWorkload:
    """One ``transitions.Machine`` per sequencer, one ``scan`` trigger each per scan."""

    name = "transitions"

    def __init__(self) -> None:
        from transitions import Machine

        states = [f"s{k}" for k in range(STEPS)]
        table = [
            {"trigger": "scan", "source": states[k], "dest": states[(k + 1) % STEPS],
             "conditions": "ready"}
            for k in range(STEPS)
        ]  # fmt: skip
        self.mem = bytearray(64)
        self.seqs = []
        for g in range(N_SEQUENCERS):
            m = _Seq(g, self.mem)
            Machine(model=m, states=states, transitions=table, initial=states[0],
                    auto_transitions=False, after_state_change="entered")  # fmt: skip
            self.seqs.append(m)
        self.now = 0
        for m in self.seqs:  # as the engine's startup call: the initial steps' rows once
            m.act()

    def scan(self) -> int:
        self.now += CYCLE_MS
        now = self.now
        t0 = time.perf_counter_ns()
        for m in self.seqs:
            m.now = now
            m.scan()  # type: ignore[attr-defined]
            m.act()
        return time.perf_counter_ns() - t0

    def positions(self) -> list[int]:
        return [int(m.state[1:]) for m in self.seqs]  # type: ignore[attr-defined]

    def markers(self) -> bytes:
        return bytes(self.mem[: N_SEQUENCERS // 4])


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

    print(
        f"python {sys.version.split()[0]}, {N_SEQUENCERS} sequencers x {STEPS} steps, "
        f"{args.scans} scans of {CYCLE_MS} ms virtual time, in rounds of {BLOCK} scans per workload"
    )
    base = TransitionsWorkload()
    layouts = ("packed", "single") if args.layout == "both" else (args.layout,)
    engines = [EngineWorkload(layout) for layout in layouts]
    prof = cProfile.Profile() if args.profile else None
    for e in engines:
        e.profile = prof
    workloads: list[TransitionsWorkload | EngineWorkload] = [base, *engines]
    samples: dict[str, list[int]] = {w.name: [] for w in workloads}
    for w in workloads:
        for _ in range(args.warmup):
            w.scan()
    done = 0
    while done < args.scans:  # rounds of BLOCK scans each, so load drift hits all alike
        n = min(BLOCK, args.scans - done)
        for w in workloads:
            samples[w.name] += [w.scan() for _ in range(n)]
        done += n

    b = stats(samples[base.name])
    print(
        f"transitions   mean {b['mean']:.3f} ms  p50 {b['p50']:.3f}  p99 {b['p99']:.3f}  "
        f"max {b['max']:.3f}"
    )
    for e in engines:
        r = stats(samples[e.name])
        active = e.active()
        assert str(e.cpu.mode).endswith("RUN"), f"{e.name}: CPU left RUN ({e.cpu.mode})"
        assert active == N_SEQUENCERS, f"{e.name}: {active} active steps"
        same = (e.positions(), e.markers()) == (base.positions(), base.markers())
        print(
            f"{e.name:13} mean {r['mean']:.3f} ms  p50 {r['p50']:.3f}  p99 {r['p99']:.3f}  "
            f"max {r['max']:.3f}  ({len(e.fbs)} FBs, {active} active steps, "
            f"{e.switches / (args.warmup + args.scans):.1f} switches/scan)"
        )
        print(
            f"{'':13} {r['mean'] * 1e3 / active:.2f} us per active step; "
            f"transitions/engine {b['mean'] / r['mean']:.2f}x (p50 {b['p50'] / r['p50']:.2f}x); "
            f"final steps and D/L bits {'same as' if same else 'DIFFER FROM'} transitions"
        )
    print("targets: engine mean <= 2 ms, >= 10x faster than transitions")
    c = time_compile()
    print(
        f"250-step chart: parse {c['parse']:.1f} ms, compile {c['compile']:.1f} ms "
        f"(target: compile <= 100 ms)"
    )
    if prof is not None:
        buf = io.StringIO()
        pstats.Stats(prof, stream=buf).sort_stats("tottime").print_stats(25)
        print(buf.getvalue())
    return (
        0
        if all((e.positions(), e.markers()) == (base.positions(), base.markers()) for e in engines)
        else 1
    )


if __name__ == "__main__":
    sys.exit(main())
