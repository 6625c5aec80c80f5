"""Scan-time benchmark: 200 GRAPH sequencers on the soft CPU vs. the same workload in
``transitions`` (run as ``python bench/scan.py``; see bench/README.md).

Workload (docs/architecture.md, "The core is a function"): 200 sequencers, each a
loop of 25 steps (5000 steps, 200 active at any time). Every step holds

    S1 N c := 0;  N c := c + 1;      // an assignment every call (reset on activation)
    D Mb.d, T#20MS;  L Mb.l, T#20MS; // an on-delay and a pulse bit
    TRANSITION ... := c >= p;        // a comparison; p = 2, 3, 4 by sequencer

so a sequencer advances every ``p`` calls (phases drift, about 1/3 of the sequencers switch per
scan) and its D and L bits toggle inside every step at the 10 ms virtual cycle. Layout
(``--layout``): ``packed`` = 25 FBs of 8 sequencers each (S7-GRAPH allows 1..8 per FB,
docs/semantics.md, "Structure"; the default), ``single`` = 200 FBs of one sequencer each. The FBs
are called from OB1 of one ``engine.cpu.Cpu`` driven by a ``VirtualClock`` advanced 10 ms per scan;
the wall time of ``Cpu.scan()`` is measured with ``perf_counter_ns``.

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
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from figures import opcodes, spread

from s7graph.engine.clock import Clock, VirtualClock
from s7graph.engine.cpu import Cpu
from s7graph.sequencer.compile import compile_chart
from s7graph.sequencer.fb import GraphFB, install_all
from s7graph.sequencer.text.parse import parse_chart

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
    """The ``.s7g`` text (docs/chart-format.md) of FB ``fb`` holding sequencers ``first_g ..``."""
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

    def __init__(self, layout: str, clock: Clock | None = None) -> None:
        """``clock``: the virtual clock :meth:`scan` advances (default), or another one
        (``bench/bus.py`` runs the workload on the system clock)."""
        per_fb = 8 if layout == "packed" else 1
        self.name = f"engine {layout}"
        self.clock = VirtualClock()
        self.cpu = Cpu(clock if clock is not None else self.clock)
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
            {
                "trigger": "scan",
                "source": states[k],
                "dest": states[(k + 1) % STEPS],
                "conditions": "ready",
            }
            for k in range(STEPS)
        ]
        self.mem = bytearray(64)
        self.seqs = []
        for g in range(N_SEQUENCERS):
            m = _Seq(g, self.mem)
            Machine(
                model=m,
                states=states,
                transitions=table,
                initial=states[0],
                auto_transitions=False,
                after_state_change="entered",
            )
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


# ---------------------------------------------------------------------------- more peers


class StatemachineWorkload:
    """One ``python-statemachine`` machine per sequencer: a ``scan`` event per scan whose
    transitions are guarded by ``ready`` (``c >= p``); entering a state resets ``c``."""

    name = "python-statemachine"

    def __init__(self) -> None:
        from statemachine import State, StateMachine

        attrs: dict[str, object] = {f"s{k}": State(initial=k == 0) for k in range(STEPS)}
        scan = None
        for k in range(STEPS):
            edge = attrs[f"s{k}"].to(attrs[f"s{(k + 1) % STEPS}"], cond="ready")  # type: ignore[attr-defined]
            scan = edge if scan is None else scan | edge
        attrs |= {"scan": scan, "allow_event_without_transition": True}
        loop = type("Loop", (StateMachine,), attrs)
        self.mem = bytearray(64)
        self.seqs = [_Seq(g, self.mem) for g in range(N_SEQUENCERS)]
        for m in self.seqs:
            m.on_enter_state = m.entered  # type: ignore[attr-defined]
        self.machines = [loop(model=m) for m in self.seqs]
        self.now = 0
        for m in self.seqs:
            m.act()

    def scan(self) -> int:
        self.now += CYCLE_MS
        now = self.now
        t0 = time.perf_counter_ns()
        for m, sm in zip(self.seqs, self.machines, strict=True):
            m.now = now
            sm.scan()
            m.act()
        return time.perf_counter_ns() - t0

    def positions(self) -> list[int]:
        return [int(next(iter(sm.configuration)).id[1:]) for sm in self.machines]

    def markers(self) -> bytes:
        return bytes(self.mem[: N_SEQUENCERS // 4])


class SismicWorkload:
    """One ``sismic`` statechart interpreter per sequencer (YAML chart: 25 states, a ``scan``
    event guarded by ``c >= p``, ``on entry: c = 0``); the step's actions in plain Python."""

    name = "sismic"

    def __init__(self) -> None:
        from sismic.interpreter import Interpreter
        from sismic.io import import_from_yaml

        lines = [
            "statechart:",
            "  name: loop",
            "  root state:",
            "    name: root",
            "    initial: s0",
            "    states:",
        ]
        for k in range(STEPS):
            lines += [
                f"    - name: s{k}",
                "      on entry: c = 0",
                "      transitions:",
                f"      - target: s{(k + 1) % STEPS}",
                "        event: scan",
                "        guard: c >= p",
            ]
        chart = import_from_yaml("\n".join(lines))
        self.mem = bytearray(64)
        self.seqs = [_Seq(g, self.mem) for g in range(N_SEQUENCERS)]
        self.interpreters = []
        for m in self.seqs:
            it = Interpreter(chart, initial_context={"p": m.p, "c": 0})
            it.execute_once()
            self.interpreters.append(it)
        self.now = 0
        for m, it in zip(self.seqs, self.interpreters, strict=True):
            self._act(m, it)

    @staticmethod
    def _act(m: _Seq, it: Any) -> None:
        """The step's actions on the interpreter's ``c`` (its entry action reset it)."""
        m.c = it.context["c"]
        m.act()
        it.context["c"] = m.c

    def scan(self) -> int:
        self.now += CYCLE_MS
        now = self.now
        t0 = time.perf_counter_ns()
        for m, it in zip(self.seqs, self.interpreters, strict=True):
            m.now = now
            it.queue("scan")
            step = it.execute_once()
            if step is not None and step.transitions:
                m.since = now
            self._act(m, it)
        return time.perf_counter_ns() - t0

    def positions(self) -> list[int]:
        return [
            int(next(s for s in it.configuration if s != "root")[1:]) for it in self.interpreters
        ]

    def markers(self) -> bytes:
        return bytes(self.mem[: N_SEQUENCERS // 4])


class CReference:
    """``bench/scan_ref.c``: the workload in plain C, walking every step of every sequencer
    each scan as matiec-generated code does; built with the system's C compiler and called
    through ctypes so that its scans interleave with the others."""

    name = "C reference"

    def __init__(self, build_dir: Path) -> None:
        import ctypes

        lib = build_dir / "scan_ref.so"
        src = Path(__file__).with_name("scan_ref.c")
        cc = shutil.which("cc") or shutil.which("gcc")
        if cc is None:
            raise RuntimeError("no C compiler")
        subprocess.run([cc, "-O2", "-shared", "-fPIC", "-o", str(lib), str(src)], check=True)
        self.lib = ctypes.CDLL(str(lib))
        self.ctypes = ctypes
        self.lib.ref_start()

    def scans(self, n: int) -> list[int]:
        buf = (self.ctypes.c_int64 * n)()
        self.lib.ref_scan(n, buf)
        return list(buf)

    def scan(self) -> int:
        return self.scans(1)[0]

    def positions(self) -> list[int]:
        pos = (self.ctypes.c_int32 * N_SEQUENCERS)()
        mk = (self.ctypes.c_uint8 * (N_SEQUENCERS // 4))()
        self.lib.ref_positions(pos, mk)
        self._markers = bytes(mk)
        return list(pos)

    def markers(self) -> bytes:
        self.positions()
        return self._markers


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


def count_opcodes(layout: str, scans: int = 12) -> tuple[float, float]:
    """Python opcodes and Python-level calls per scan of an engine workload (``sys.settrace``
    with opcode events, after 100 unmeasured scans): deterministic, unlike the times."""
    e = EngineWorkload(layout)
    for _ in range(100):
        e.scan()
    ops = calls = 0
    for _ in range(scans):
        e.clock.advance(CYCLE_MS)
        o, c = opcodes(e.cpu.scan)
        ops, calls = ops + o, calls + c
    return ops / scans, calls / scans


Workload = EngineWorkload | TransitionsWorkload | StatemachineWorkload | SismicWorkload | CReference


def peers(build_dir: Path, names: set[str]) -> list[Workload]:
    """The peers that can run here (a missing library or compiler is reported, not fatal)."""
    out: list[Workload] = [TransitionsWorkload()]
    makers: dict[str, Any] = {
        "python-statemachine": StatemachineWorkload,
        "sismic": SismicWorkload,
        "C reference": lambda: CReference(build_dir),
    }
    for name, make in makers.items():
        if name not in names:
            continue
        try:
            out.append(make())
        except (ImportError, RuntimeError, OSError, subprocess.CalledProcessError) as exc:
            print(f"{name}: not measured ({exc})")
    return out


def measure(workloads: list[Workload], scans: int, warmup: int) -> dict[str, list[int]]:
    """``scans`` scans of each workload after ``warmup``, in rounds of BLOCK scans each, in
    turn, so that load from other processes hits them alike."""
    samples: dict[str, list[int]] = {w.name: [] for w in workloads}
    for w in workloads:
        for _ in range(warmup):
            w.scan()
    done = 0
    while done < scans:
        n = min(BLOCK, scans - done)
        for w in workloads:
            if isinstance(w, CReference):
                samples[w.name] += w.scans(n)
            else:
                samples[w.name] += [w.scan() for _ in range(n)]
        done += n
    return samples


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scans", type=int, default=1000, help="measured scans per run (1000)")
    ap.add_argument("--warmup", type=int, default=100, help="unmeasured scans first")
    ap.add_argument("--repeat", type=int, default=3, help="runs; min/median/max over them (3)")
    ap.add_argument("--layout", choices=("packed", "single", "both"), default="both")
    ap.add_argument(
        "--peers",
        default="python-statemachine,sismic,C reference",
        help="peers besides transitions (comma-separated; default all)",
    )
    ap.add_argument("--profile", action="store_true", help="cProfile the engine scans")
    ap.add_argument("--count", action="store_true", help="opcodes and calls per scan, too")
    args = ap.parse_args(argv)

    print(
        f"python {sys.version.split()[0]}, {N_SEQUENCERS} sequencers x {STEPS} steps, "
        f"{args.repeat} runs of {args.scans} scans of {CYCLE_MS} ms virtual time, in rounds "
        f"of {BLOCK} scans per workload"
    )
    layouts = ("packed", "single") if args.layout == "both" else (args.layout,)
    prof = cProfile.Profile() if args.profile else None
    means: dict[str, list[float]] = {}
    p50s: dict[str, list[float]] = {}
    agree = True
    with tempfile.TemporaryDirectory(prefix="s7graph-bench-") as tmp:
        names = {n.strip() for n in args.peers.split(",") if n.strip()}
        for _ in range(args.repeat):
            engines = [EngineWorkload(layout) for layout in layouts]
            for e in engines:
                e.profile = prof
            others = peers(Path(tmp), names)
            workloads: list[Workload] = [*others, *engines]
            samples = measure(workloads, args.scans, args.warmup)
            for w in workloads:
                st = stats(samples[w.name])
                means.setdefault(w.name, []).append(st["mean"])
                p50s.setdefault(w.name, []).append(st["p50"])
            base = others[0]
            for e in engines:
                assert str(e.cpu.mode).endswith("RUN"), f"{e.name}: CPU left RUN ({e.cpu.mode})"
                assert e.active() == N_SEQUENCERS, f"{e.name}: {e.active()} active steps"
            for w in workloads[1:]:
                if (w.positions(), w.markers()) != (base.positions(), base.markers()):
                    agree = False
                    print(f"{w.name}: final steps or D/L bits DIFFER FROM transitions")
    print(
        f"{'workload':22} {'mean ms':>20} {'p50 ms':>20} {'us/active step':>18}   "
        "time ÷ engine packed"
    )
    ref = "engine packed" if "engine packed" in means else f"engine {layouts[0]}"
    for name, ms in means.items():
        per_step = [m * 1e3 / N_SEQUENCERS for m in ms]
        ratio = [m / r for m, r in zip(ms, means[ref], strict=True)]
        print(
            f"{name:22} {spread(ms, '{:.3f}'):>20} {spread(p50s[name], '{:.3f}'):>20} "
            f"{spread(per_step, '{:.2f}'):>18}   {spread(ratio, '{:.2f}')}"
        )
    for e_name in (n for n in means if n.startswith("engine")):
        ratio = [b / e for b, e in zip(means["transitions"], means[e_name], strict=True)]
        print(f"transitions / {e_name}: {spread(ratio, '{:.2f}')}x (min/median/max)")
    print("targets: packed >= 4x transitions, single >= 3x")
    c = time_compile()
    print(
        f"250-step chart: parse {c['parse']:.1f} ms, compile {c['compile']:.1f} ms "
        f"(target: compile <= 100 ms)"
    )
    if args.count:
        for layout in layouts:
            ops, calls = count_opcodes(layout)
            print(f"engine {layout}: {ops:.0f} Python opcodes, {calls:.0f} Python calls per scan")
    if prof is not None:
        buf = io.StringIO()
        pstats.Stats(prof, stream=buf).sort_stats("tottime").print_stats(25)
        print(buf.getvalue())
    return 0 if agree else 1


if __name__ == "__main__":
    sys.exit(main())
