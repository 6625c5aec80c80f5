"""Start-up benchmark: how long ``s7graph`` takes to start, and how long a plant waits for
its CPU after the CPU's process died (run as ``python bench/startup.py``; see
bench/README.md).

Each figure is the wall time from ``Popen`` (or from the SIGKILL) to the line that says the
CPU is there, over ``--repeat`` runs, min/median/max, beside the interpreter's own start
(``python -c pass``, the floor every command pays) as a ratio:

* ``check``: ``s7graph check`` of the drill demo, to its exit;
* ``run``: ``s7graph run`` of the drill demo with its plant (no bus), to ``in RUN``;
* ``crash``: the same run on a bus (``--listen`` on loopback), its CPU's process SIGKILLed
  (a crash in C code, as the supervisor sees one), to the next CPU's ``in STOP (from its
  last durable state``: what the supervisor's restart costs the plant (``web/cli/supervisor.py``).

The load average is printed at the start and at the end.
"""

from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from subprocess import DEVNULL

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "bench"))

from figures import free_port, spread  # noqa: E402

DRILL = ROOT / "examples" / "drill"
CHART = [str(DRILL / "drill.s7g"), "--symbols", str(DRILL / "symbols.txt")]
S7GRAPH = [sys.executable, "-m", "s7graph"]


def _floor() -> float:
    t0 = time.monotonic()
    subprocess.run([sys.executable, "-c", "pass"], check=True)
    return time.monotonic() - t0


def _check() -> float:
    t0 = time.monotonic()
    subprocess.run([*S7GRAPH, "check", *CHART], check=True, capture_output=True)
    return time.monotonic() - t0


def _run_args(folder: Path) -> list[str]:
    plant = ["--plant", str(DRILL / "demo_plant.py")]
    return [*S7GRAPH, "run", *CHART, *plant, "--state", str(folder / "drill.sqlite")]


def _wait(proc: subprocess.Popen[str], text: str) -> None:
    assert proc.stderr is not None
    for line in proc.stderr:
        if text in line:
            return
    raise SystemExit(f"the run ended before {text!r}")


def _end(proc: subprocess.Popen[str]) -> None:
    proc.send_signal(signal.SIGTERM)
    proc.communicate(timeout=30)


def _run(folder: Path) -> float:
    t0 = time.monotonic()
    proc = subprocess.Popen(_run_args(folder), stderr=subprocess.PIPE, stdout=DEVNULL, text=True)
    _wait(proc, " in RUN (")
    took = time.monotonic() - t0
    _end(proc)
    return took


def _cpu_of(supervisor: int) -> int:
    """The supervised CPU's process: the supervisor's child running ``s7graph``."""
    for task in Path(f"/proc/{supervisor}/task").iterdir():
        for pid in (task / "children").read_text().split():
            if b"s7graph" in Path(f"/proc/{pid}/cmdline").read_bytes():
                return int(pid)
    raise SystemExit("no CPU process under the supervisor")


def _crash(folder: Path) -> float:
    bus = ["--listen", f"tcp/127.0.0.1:{free_port()}"]
    proc = subprocess.Popen(
        [*_run_args(folder), *bus], stderr=subprocess.PIPE, stdout=DEVNULL, text=True
    )
    try:
        _wait(proc, " in RUN (")
        time.sleep(0.5)  # a few scans: the supervisor restarts only a CPU that had scanned
        t0 = time.monotonic()
        os.kill(_cpu_of(proc.pid), signal.SIGKILL)
        _wait(proc, "in STOP (from its last durable state")
        return time.monotonic() - t0
    finally:
        _end(proc)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args()
    print(f"load average at the start: {os.getloadavg()[0]:.2f}")
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        floor = [_floor() for _ in range(args.repeat)]
        rows = {
            "check": [_check() for _ in range(args.repeat)],
            "run": [_run(folder) for _ in range(args.repeat)],
            "crash": [_crash(folder) for _ in range(args.repeat)],
        }
    base = sorted(floor)[len(floor) // 2]
    print(f"python -c pass: {spread([t * 1e3 for t in floor], '{:.0f}')} ms (min/median/max)")
    for name, times in rows.items():
        ms = spread([t * 1e3 for t in times], "{:.0f}")
        ratio = spread([t / base for t in times], "{:.1f}")
        print(f"{name:6} {ms} ms; × python -c pass (median): {ratio}")
    print(f"load average at the end: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
