"""Compile and start-up benchmark (run as ``python bench/compile.py``; see bench/README.md).

Per-step cost (CPU time) of ``parse_chart`` (text → model) and ``compile_chart`` (model →
``CompiledChart``: validator, code generation, Python ``compile()``) for charts of 2,500
and 25,000 steps — the target: the large chart costs per step what the small one does —
and the start-up (wall) time of ``s7graph check`` on a chart. Each measurement runs in a
fresh Python process (a process that has built one chart keeps its objects, which the
garbage collector would then walk); the sizes are measured in turn, round by round, so
that load from other processes on the machine hits them alike; min/median/max over
``--repeat`` rounds.

The charts are those of ``bench/scan.py``: sequencers of 25-step loops, every step with an
assignment, an S1 assignment, a D and an L row, every transition a comparison (so 2,500
steps are 100 sequencers in one FB, 25,000 steps 1,000: beyond S7-GRAPH's limits, which
only warn).

``s7graph check`` reads one 250-step loop (S7-GRAPH's step limit); its peer is the
interpreter alone (``python -c pass``), the floor of any command.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

from figures import spread  # noqa: E402 (bench/ on the path first)
from scan import STEPS, chart_source  # noqa: E402

HEAVY = ("viser", "zenoh", "numpy")  # what ``s7graph check`` must not import


def chart_text(n_steps: int) -> str:
    """One FB of ``n_steps // 25`` sequencers of ``bench/scan.py``'s 25-step loops."""
    return chart_source(1, 0, n_steps // STEPS)


def check_text() -> str:
    """The chart ``s7graph check`` reads: one 250-step loop (S7-GRAPH's step limit)."""
    return chart_source(1, 0, 1, 250)


def child(n_steps: int) -> None:
    """Parse and compile one chart of ``n_steps`` steps in this (fresh) process; print the
    CPU seconds each took as JSON (CPU time: what other processes on a shared machine do
    not add to)."""
    from s7graph.sequencer.compile import compile_chart
    from s7graph.sequencer.text.parse import parse_chart

    text = chart_text(n_steps)
    t0 = time.process_time()
    chart = parse_chart(text, f"<bench {n_steps}>")
    t1 = time.process_time()
    cc = compile_chart(chart)
    t2 = time.process_time()
    assert cc.n_steps == n_steps
    print(json.dumps({"parse": t1 - t0, "compile": t2 - t1}))


def measure_compile(n_steps: int) -> dict[str, float]:
    out = subprocess.run(
        [sys.executable, __file__, "--child", str(n_steps)],
        check=True,
        capture_output=True,
        text=True,
    )
    return json.loads(out.stdout)  # type: ignore[no-any-return]


def measure_start(args: list[str]) -> float:
    """Wall time of one fresh process running ``args`` (seconds)."""
    t0 = time.perf_counter()
    subprocess.run(args, check=True, capture_output=True, cwd=ROOT)
    return time.perf_counter() - t0


def check_imports(chart: Path) -> list[str]:
    """The modules of ``HEAVY`` that ``s7graph check chart`` has loaded when it is done."""
    probe = (
        "import sys\n"
        "from s7graph.web.cli import main\n"
        f"sys.argv = ['s7graph', 'check', {str(chart)!r}]\n"
        "try:\n    main()\nexcept SystemExit:\n    pass\n"
        f"print('loaded:', *(m for m in {HEAVY!r} if m in sys.modules))\n"
    )
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, cwd=ROOT)
    last = out.stdout.splitlines()[-1].split()
    assert last[0] == "loaded:", out.stdout + out.stderr
    return last[1:]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeat", type=int, default=5, help="rounds; min/median/max (5)")
    ap.add_argument("--sizes", default="2500,25000", help="chart sizes in steps")
    ap.add_argument("--child", type=int, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child:
        child(args.child)
        return 0
    sizes = [int(s) for s in args.sizes.split(",")]
    per_step: dict[int, dict[str, list[float]]] = {n: {"parse": [], "compile": []} for n in sizes}
    start: dict[str, list[float]] = {"python -c pass": [], "s7graph check": []}
    with tempfile.TemporaryDirectory(prefix="s7graph-bench-") as tmp:
        chart = Path(tmp) / "bench.s7g"
        chart.write_text(check_text(), encoding="utf-8")
        commands = {
            "python -c pass": [sys.executable, "-c", "pass"],
            "s7graph check": [sys.executable, "-m", "s7graph", "check", str(chart)],
        }
        for _ in range(args.repeat):
            for n in sizes:
                r = measure_compile(n)
                for part in ("parse", "compile"):
                    per_step[n][part].append(r[part] / n * 1e6)
            for name, command in commands.items():
                start[name].append(measure_start(command) * 1e3)
        heavy = check_imports(chart)
    print(
        f"python {sys.version.split()[0]}, {args.repeat} rounds, each measurement in a fresh "
        "process (min/median/max)"
    )
    print(f"{'chart':>14} {'parse us/step':>20} {'compile us/step':>20}")
    for n in sizes:
        p, c = per_step[n]["parse"], per_step[n]["compile"]
        print(f"{n:>8} steps {spread(p, '{:.1f}'):>20} {spread(c, '{:.1f}'):>20}")
    if len(sizes) > 1:
        small, large = sizes[0], sizes[-1]
        for part in ("parse", "compile"):
            ratio = statistics.median(per_step[large][part]) / statistics.median(
                per_step[small][part]
            )
            print(f"{part}: {large} steps cost {ratio:.2f}x per step what {small} steps do")
    print("target: 1.0x (the per-step cost does not grow with the chart)")
    for name, ms in start.items():
        print(f"start-up {name:16} {spread(ms, '{:.0f}'):>16} ms")
    print(f"s7graph check imports {', '.join(heavy) if heavy else 'none of'} {'/'.join(HEAVY)}")
    return 1 if heavy else 0


if __name__ == "__main__":
    sys.exit(main())
