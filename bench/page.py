"""Page benchmark: how fast the browser view of ``s7graph run CHART --web`` shows a step
change, and how long its first paint takes (run as ``python bench/page.py``; see
bench/README.md). A benchmark, not a test: it prints figures and the targets, met or not.

Each chart runs in a CPU process of its own — the real ``run_chart`` of ``s7graph run CHART
--web`` (state file, bus on a unix socket, the view in its own process) at a 10 ms cycle on
the system clock — whose ``LiveGraph._update`` (behind ``update`` and ``changed``, called
at the end of a scan, before it is published) is wrapped to stamp ``time.time()`` whenever
the active steps change. Headless Chromium (Playwright driving /usr/bin/chromium, software
WebGL) opens the page with an init script that hooks viser's websocket worker: the
worker's ``WebSocket`` notes the wall-clock arrival of every frame
(``performance.timeOrigin + performance.now()``, the machine clock the CPU stamps with), the
page notes when each decoded batch reaches the main
thread and the second ``requestAnimationFrame`` after it ("painted": the frame that drew
the batch has been presented — or, as viser applies a node's props through React, the one
drawing it has begun: up to a frame short; see bench/README.md).

Charts: ``loop8`` and ``loop250``, generated loops of 8 and 250 steps, each step leaving
on its own step time (150–249 ms, varied so the changes fall at every phase of the view's
render loop); ``drill``, the README's demo (``drill.s7g`` with ``demo_plant.py``).

- *colour*: from the scan where a step became active to the painted frame after the page
  received that step box's new colour (``/chart/step/S<n>`` in ACTIVE green), p50 / p99
  over ``--changes`` changes (100: the p99 of a round is its largest); also the parts up
  to the websocket frame's arrival in viser's worker (*ws*) and to the decoded batch in the
  page's main thread (*main*), the length of the frame that drew it (first to second
  animation frame after the batch), and the status line's "active: S<n>" painted
  (*status*). A change the page never shows is counted as missed. The changes are
  watched once the page has settled (``settle``: viser's adaptive resolution steps down
  in the first seconds of a slow page, each step a stall). Targets (at load
  average ≤ 2): colour p99 ≤ 100 ms for ``loop8``, ≤ 150 ms for ``loop250``.
- *bareN*, the peer of each loop chart, measured right after it in the same browser: a
  bare viser page (nothing of s7graph, ``Boxes``) of N boxes and a status line showing
  the same step changes at the same times — the least any viser page costs to show them
  on this machine at this load; printed beside the chart, with the ratio of the two.
- *frames*: while each page runs, its animation frames a second and the CPU time the
  browser spent per frame (all its processes, from ``/proc``) — what a frame costs
  software WebGL, which the load changes less than how long a frame takes.
- *first paint*: from ``page.goto`` (a fresh browser context: no cache) to the painted
  frame after the batch that created the chart's last scene node (no new one for 2 s
  after; *chart*), and to the later of that and the painted frame after the panel's first
  status line (*with panel*: the page as an operator needs it); beside it an empty
  ``viser.ViserServer`` (nothing added): to the painted frame after its first batch (the
  second of two pages opened in turn: the first pays for the browser's warm-up). Target: at
  most twice the empty page, both figures.

Min / median / max over ``--repeat`` rounds; the load average of the machine is printed.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import statistics
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

from figures import free_port, pct, serves, spread  # noqa: E402

DRILL = ROOT / "examples" / "drill"
CYCLE_MS = 10.0
CHARTS = ("loop8", "loop250", "drill")
COLOUR_CHARTS = ("loop8", "loop250")
MEASURES = (
    ("ws", "the websocket frame in the worker"),
    ("main", "the batch in the page's main thread"),
    ("frame", "(a frame: 1st to 2nd rAF after it)"),
    ("colour", "the colour painted (2nd rAF)"),
    ("status", "the status line painted"),
)
CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = [
    "--no-sandbox",
    "--headless",
    "--enable-unsafe-swiftshader",
    "--use-angle=swiftshader",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
]
ACTIVE = "40,170,60"  # web.view.drawing.ACTIVE as the page receives it
QUIET_S = 2.0  # no new chart node for this long: the chart is drawn
RESULT = "PAGE "
COLOUR_TARGET_MS = {"loop8": 100.0, "loop250": 150.0}  # p99, at load average <= 2
PAINT_TARGET = 2.0

# The init script: in the worker viser opens its websocket from, note every frame's
# arrival; in the page, each batch the worker posts, what it carries that we watch, and
# the second animation frame after it.
HOOK = r"""
(() => {
  const now = () => performance.timeOrigin + performance.now();
  const B = window.__bench = {raw: [], batches: 0, recs: [], first: null, last: null,
                              nodes: 0, error: null};
  const prelude = `(() => { const WS = self.WebSocket;
    self.WebSocket = class extends WS { constructor(...a) { super(...a);
      this.addEventListener('message', () => self.postMessage(
        {type: '__bench_raw', t: performance.timeOrigin + performance.now()})); } };
  })();\n`;
  const painted = (fill) => requestAnimationFrame(() => {
    const f1 = now();
    requestAnimationFrame(() => fill(now(), f1));
  });
  const onBatch = (e) => {
    const d = e.data;
    if (!d) return;
    if (d.type === '__bench_raw') { B.raw.push(d.t); return; }
    if (d.type !== 'message_batch') return;
    const arr = now();
    const raw = B.raw[B.batches++] ?? 0;
    const recs = [];
    let nodes = 0;
    for (const m of d.messages) {
      const name = m.name || '';
      if (m.type === 'SceneNodeUpdateMessage') {
        if (name.startsWith('/chart/step/S') && m.updates && m.updates.color) {
          const rgb = Array.from(m.updates.color).join(',');
          recs.push({kind: 'colour', key: name.slice(13) + '=' + rgb, raw, arr, paint: 0});
        }
      } else if (name.startsWith('/chart/') && !/^(Set|Remove)/.test(m.type)) {
        nodes += 1;
      } else if ((m.type === 'GuiUpdateMessage' && m.updates) || m.type === 'GuiHtmlMessage') {
        const found = /active: ((?:S\d+(?:, )?)+|none)/.exec(JSON.stringify(m.updates || m.props));
        if (found) recs.push({kind: 'status', key: found[1], raw, arr, paint: 0});
      }
    }
    const batch = {raw, arr, paint: 0};
    if (B.first === null) { B.first = batch; painted((t) => { batch.paint = t; }); }
    if (nodes) { B.nodes += nodes; B.last = batch; painted((t) => { batch.paint = t; }); }
    if (recs.length) {
      B.recs.push(...recs);
      painted((t, f1) => { for (const r of recs) { r.paint = t; r.f1 = f1; } });
    }
  };
  const W = window.Worker;
  window.Worker = function (url, opts) {
    let target = url;
    try {  // the inline worker's code, with the prelude before it
      const x = new XMLHttpRequest();
      x.open('GET', url, false);
      x.send();
      target = URL.createObjectURL(new Blob([prelude + x.responseText],
                                            {type: 'text/javascript'}));
    } catch (err) { B.error = String(err); }
    const w = new W(target, opts);
    w.addEventListener('message', onBatch);
    return w;
  };
  window.Worker.prototype = W.prototype;
})();
"""


# ---------------------------------------------------------------------------- the charts


def loop_source(steps: int) -> str:
    """The ``.s7g`` text of one sequence of ``steps`` steps in a loop, each leaving on its
    own step time of 150–249 ms (varied: the changes fall at every phase of the view)."""
    out = [
        'FUNCTION_BLOCK "Bench_loop" FB 1 DB 1',
        "  PARAMETERS := STANDARD;",
        'SEQUENCE 1 "Loop"',
    ]
    for k in range(1, steps + 1):
        kw = "INITIAL_STEP" if k == 1 else "STEP"
        out += [f'  {kw} S{k} "Step {k}":', "  END_STEP"]
    for k in range(1, steps + 1):
        ms = 150 + (k * 37) % 100
        out.append(f"  TRANSITION T{k} FROM S{k} TO S{k % steps + 1} := S{k}.T >= T#{ms}MS;")
    out += ["END_SEQUENCE", "END_FUNCTION_BLOCK"]
    return "\n".join(out) + "\n"


# ---------------------------------------------------------------------------- the CPU process


def stamp_changes() -> None:
    """Stamp every change of the active steps of the chart this process runs next (at the
    end of its scan, before it is published); a ``dump`` line on stdin prints the changes so
    far as one ``PAGE {json}`` line, ``end`` stops the run."""
    from s7graph.engine.runner import Runner
    from s7graph.web.bus.live import LiveGraph

    changes: list[tuple[float, list[int]]] = []
    runners: list[Runner] = []
    update = LiveGraph._update  # behind update() and changed(): every state built
    run = Runner.run
    last: list[list[int]] = [[]]

    def stamped_update(self: LiveGraph, record: Any, *args: Any, **kw: Any) -> Any:
        t = time.time()  # the end of the scan, before it is published
        result = update(self, record, *args, **kw)
        if result.active != last[0]:
            last[0] = list(result.active)
            changes.append((t, last[0]))
        return result

    def kept_run(self: Runner, **kw: Any) -> None:
        runners.append(self)
        run(self, **kw)

    LiveGraph._update = stamped_update  # type: ignore[method-assign]
    Runner.run = kept_run  # type: ignore[method-assign]

    def control() -> None:
        for line in sys.stdin:
            word = line.strip()
            if word == "dump":
                print(RESULT + json.dumps(changes[:]), flush=True)
            elif word == "end" and runners:
                runners[0].request_stop()

    threading.Thread(target=control, daemon=True).start()


def worker(chart: str, path: Path, endpoint: str, port: int, state: Path) -> int:
    """Run ``chart`` as ``s7graph run --web`` does, its changes stamped (``stamp_changes``)."""
    from s7graph.engine.runner import RT_PRIORITY
    from s7graph.web.cli.net import NetOptions
    from s7graph.web.cli.run_chart import run_chart

    stamp_changes()
    common: dict[str, Any] = {
        "state": state,
        "cycle_ms": CYCLE_MS,
        "web": True,
        "port": port,
        "net": NetOptions(listen=[endpoint]),
        "rt_priority": RT_PRIORITY,
    }
    if chart == "drill":
        common.update(plant=DRILL / "demo_plant.py", symbols=DRILL / "symbols.txt")
    return int(run_chart(path, **common))


class Cpu:
    """The CPU process of one chart, its view served at ``url``."""

    def __init__(self, proc: subprocess.Popen[str], url: str, path: Path) -> None:
        self.proc = proc
        self.url = url
        self.path = path

    def changes(self) -> list[tuple[float, list[int]]]:
        assert self.proc.stdin is not None and self.proc.stdout is not None
        self.proc.stdin.write("dump\n")
        self.proc.stdin.flush()
        for line in self.proc.stdout:
            if line.startswith(RESULT):
                return [(t, active) for t, active in json.loads(line[len(RESULT) :])]
        raise RuntimeError("the CPU process ended")


@contextmanager
def cpu(chart: str) -> Iterator[Cpu]:
    with tempfile.TemporaryDirectory(prefix="s7graph-page-") as tmp:
        if chart == "drill":
            path = DRILL / "drill.s7g"
        else:
            path = Path(tmp) / f"{chart}.s7g"
            path.write_text(loop_source(int(chart[4:])), encoding="utf-8")
        errors = Path(tmp) / "stderr.txt"
        with errors.open("w") as err:
            proc = subprocess.Popen(
                [
                    sys.executable,
                    __file__,
                    "--worker",
                    chart,
                    str(path),
                    f"unixsock-stream/{tmp}/bus.sock",
                    str(free_port()),
                    str(Path(tmp) / "state.sqlite"),
                ],
                cwd=ROOT,
                stdin=subprocess.PIPE,
                stdout=subprocess.PIPE,
                stderr=err,
                text=True,
            )
            try:
                url = ""
                assert proc.stdout is not None and proc.stdin is not None
                for line in proc.stdout:
                    found = re.search(r"view (\S+) \(bus ", line)
                    if found:
                        url = found[1]
                        break
                if not url:
                    raise RuntimeError(f"the CPU process of {chart} ended before its view")
                deadline = time.monotonic() + 60
                while not serves(url) and time.monotonic() < deadline:
                    time.sleep(0.2)
                time.sleep(1.0)  # let the start settle
                yield Cpu(proc, url, path)
                proc.stdin.write("end\n")
                proc.stdin.flush()
                proc.wait(30)
            except BaseException:
                proc.kill()
                raise
            finally:
                if proc.poll() is None:
                    proc.kill()
                proc.wait(30)
                said = errors.read_text()
                if "Traceback" in said:
                    print(said, file=sys.stderr)


class Boxes:
    """The peer of a loop chart: a bare viser page (nothing of s7graph) of ``steps`` boxes
    in a column and a status line, one box green at a time, moved on as the loop charts'
    steps are (after 150–249 ms, the same sequence of times), each change sent at once
    (``flush``) — the least any viser page must do to show the same changes. ``changes``
    as ``Cpu``'s; ``url`` its page."""

    def __init__(self, server: Any, steps: int) -> None:
        from s7graph.web.view.drawing import ACTIVE as GREEN
        from s7graph.web.view.drawing import FLAT_LIGHT, INACTIVE, PANEL_W

        self.url = f"http://127.0.0.1:{server.get_port()}/"
        self._server, self._steps = server, steps
        self._green, self._grey = GREEN, INACTIVE
        self._changes: list[tuple[float, list[int]]] = []
        self._stop = threading.Event()
        sc = server.scene
        sc.set_up_direction("+y")
        sc.world_axes.visible = False
        sc.configure_default_lights(enabled=False, cast_shadow=False)
        sc.configure_environment_map(None)
        sc.add_light_ambient("/light", intensity=FLAT_LIGHT)
        self._boxes = [
            sc.add_box(
                f"/chart/step/S{k}",
                color=GREEN if k == 1 else INACTIVE,
                dimensions=(1.2, 0.6, 0.04),
                position=(0.0, -1.5 * (k - 1), 0.0),
                cast_shadow=False,
                receive_shadow=False,
            )
            for k in range(1, steps + 1)
        ]
        shown = min(steps, 8)
        server.initial_camera.position = (0.0, -0.75 * (shown - 1), 1.5 * shown + 4.0)
        server.initial_camera.look_at = (0.0, -0.75 * (shown - 1), 0.0)
        server.gui.main_panel.dock_right()
        server.gui.main_panel.set_width(PANEL_W)
        self._status = server.gui.add_markdown("active: S1")
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        k = 1
        while not self._stop.wait((150 + (k * 37) % 100) / 1000):
            nxt = k % self._steps + 1
            t = time.time()
            self._boxes[k - 1].color = self._grey
            self._boxes[nxt - 1].color = self._green
            self._server.flush()
            self._status.content = f"active: S{nxt}"
            self._changes.append((t, [nxt]))
            k = nxt

    def changes(self) -> list[tuple[float, list[int]]]:
        return self._changes[:]

    def close(self) -> None:
        self._stop.set()
        self._thread.join(5)


@contextmanager
def bare_boxes(steps: int) -> Iterator[Boxes]:
    """``Boxes`` of ``steps`` on 127.0.0.1, served until the block ends."""
    import io
    from contextlib import redirect_stdout

    import viser

    with redirect_stdout(io.StringIO()):  # its banner
        server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    boxes = Boxes(server, steps)
    try:
        while not serves(boxes.url):
            time.sleep(0.1)
        yield boxes
    finally:
        boxes.close()
        with redirect_stdout(io.StringIO()):
            server.stop()


@contextmanager
def empty_viser() -> Iterator[str]:
    """An empty viser page (nothing added) on 127.0.0.1."""
    import io
    from contextlib import redirect_stdout

    import viser

    with redirect_stdout(io.StringIO()):  # its banner
        server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    try:
        url = f"http://127.0.0.1:{server.get_port()}/"
        while not serves(url):
            time.sleep(0.1)
        yield url
    finally:
        with redirect_stdout(io.StringIO()):
            server.stop()


# ---------------------------------------------------------------------------- in the page


def _poll(page: Any, script: str, timeout: float) -> Any:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = page.evaluate(script)
        if value:
            return value
        time.sleep(0.1)
    return None


STATUS_PAINTED = """(() => { const r = window.__bench.recs.find(r => r.kind === 'status');
  return r ? r.paint : 0; })()"""


def first_paint(page: Any, url: str, empty: bool) -> tuple[float, float]:
    """Open ``url`` in ``page``; ms from ``goto`` to the painted frame after the first batch
    (``empty``: both figures), else after the batch with the chart's last scene node, and
    after the later of that one and the first status line (the chart with its panel)."""
    nan = float("nan")
    t0 = time.time() * 1000
    page.goto(url, timeout=120_000)
    if empty:
        paint = _poll(page, "window.__bench.first && window.__bench.first.paint", 120)
        return (float(paint) - t0,) * 2 if paint else (nan, nan)
    seen: tuple[int, float] = (-1, 0.0)
    deadline = time.monotonic() + 180
    while time.monotonic() < deadline:
        nodes, paint = page.evaluate(
            "[window.__bench.nodes, window.__bench.last ? window.__bench.last.paint : 0]"
        )
        if nodes and paint and nodes == seen[0]:
            if time.monotonic() - seen[1] >= QUIET_S:
                status = _poll(page, STATUS_PAINTED, max(1.0, deadline - time.monotonic()))
                whole = max(float(paint), float(status)) - t0 if status else nan
                return float(paint) - t0, whole
        else:
            seen = (nodes, time.monotonic())
        time.sleep(0.1)
    return nan, nan


def _watch(machine: Cpu | Boxes, changes: int, start: float) -> list[tuple[float, list[int]]]:
    deadline = time.monotonic() + changes * 0.4 + 30
    got: list[tuple[float, list[int]]] = []
    while time.monotonic() < deadline:
        time.sleep(1.0)
        got = [c for c in machine.changes() if c[0] > start + 0.5]
        if len(got) > changes:
            break
    time.sleep(1.5)  # the last change on its way to the page
    return got[:changes]


CANVAS_SIZES = """Array.from(document.querySelectorAll('canvas'))
  .map((c) => c.width + 'x' + c.height).join(' ')"""
SETTLED_S = 4.0  # the canvas unchanged this long: the page has chosen its resolution
SETTLE_MAX_S = 30.0


def settle(page: Any) -> float:
    """Wait until the page's canvas kept its size for ``SETTLED_S`` (at most
    ``SETTLE_MAX_S``); the seconds waited. viser lowers the canvas's resolution in steps
    while frames are slow (its adaptive DPR): each step reallocates the drawing buffer and
    holds the page up for about 0.1 s in software WebGL, a few times in the first seconds
    of a page; the figures are of the page as it then stays."""
    t0 = time.monotonic()
    last, since = page.evaluate(CANVAS_SIZES), t0
    while time.monotonic() - since < SETTLED_S and time.monotonic() - t0 < SETTLE_MAX_S:
        time.sleep(0.1)
        now = page.evaluate(CANVAS_SIZES)
        if now != last:
            last, since = now, time.monotonic()
    return time.monotonic() - t0


def colour_latency(page: Any, machine: Cpu | Boxes, changes: int) -> dict[str, list[float]]:
    """Watch ``changes`` step changes, the page settled first (``settle``); per change the
    ms from the CPU's scan to the page."""
    settled = settle(page)
    page.evaluate("window.__bench.recs = []")
    start = time.time()
    got = _watch(machine, changes, start)
    recs = page.evaluate("window.__bench.recs")
    colour: dict[int, list[dict[str, float]]] = {}
    status: dict[str, list[dict[str, float]]] = {}
    for r in recs:
        if r["kind"] == "colour":
            step, _, rgb = r["key"].partition("=")
            if rgb == ACTIVE:
                colour.setdefault(int(step), []).append(r)
        else:
            status.setdefault(r["key"], []).append(r)
    out: dict[str, list[float]] = {
        "colour": [],
        "ws": [],
        "main": [],
        "frame": [],
        "status": [],
        "missed": [],
        "settled": [settled],
    }
    prev: set[int] = set()
    before = [c for c in machine.changes() if c[0] <= start + 0.5]
    if before:
        prev = set(before[-1][1])
    for t, active in got:
        t_ms = t * 1000
        for n in sorted(set(active) - prev):
            hit = next((r for r in colour.get(n, []) if r["arr"] >= t_ms and r["paint"]), None)
            if hit is None:
                out["missed"].append(n)
                continue
            out["colour"].append(hit["paint"] - t_ms)
            out["main"].append(hit["arr"] - t_ms)
            if hit["raw"]:
                out["ws"].append(hit["raw"] - t_ms)
            out["frame"].append(hit["paint"] - hit["f1"])
        key = ", ".join(f"S{n}" for n in active) or "none"
        line = next((r for r in status.get(key, []) if r["arr"] >= t_ms and r["paint"]), None)
        if line is not None:
            out["status"].append(line["paint"] - t_ms)
        prev = set(active)
    return out


# ---------------------------------------------------------------------------- frame cost

FRAME_S = 5.0  # seconds of frames counted per page
COUNT_FRAMES = """(ms) => new Promise((done) => { let n = 0; const t0 = performance.now();
  const tick = () => { n++; if (performance.now() - t0 < ms) requestAnimationFrame(tick);
  else done(n); }; requestAnimationFrame(tick); })"""


def _browser_cpu_ms() -> float:
    """CPU time (ms) so far of every Chromium process this benchmark started (the
    descendants of this process whose command line names chromium)."""
    children: dict[int, list[int]] = {}
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                with open(f"/proc/{entry}/stat") as f:
                    parent = int(f.read().rsplit(")", 1)[1].split()[1])
            except (OSError, IndexError, ValueError):
                continue
            children.setdefault(parent, []).append(int(entry))
    total, todo = 0, list(children.get(os.getpid(), []))
    while todo:
        pid = todo.pop()
        todo += children.get(pid, [])
        try:
            with open(f"/proc/{pid}/cmdline", "rb") as f:
                if b"chrom" not in f.read():
                    continue
            with open(f"/proc/{pid}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
            total += int(fields[11]) + int(fields[12])  # utime + stime, in ticks
        except (OSError, IndexError, ValueError):
            continue
    return total * 1000 / os.sysconf("SC_CLK_TCK")


def frame_cost(page: Any) -> tuple[float, float]:
    """While the page runs for ``FRAME_S``: its animation frames a second and the CPU time
    (ms) the browser spent per frame — what one frame costs software WebGL, which the
    machine's load changes less than the frame's length."""
    before, t0 = _browser_cpu_ms(), time.monotonic()
    frames = int(page.evaluate(COUNT_FRAMES, FRAME_S * 1000))
    spent, took = _browser_cpu_ms() - before, time.monotonic() - t0
    return frames / took, spent / max(frames, 1)


# ---------------------------------------------------------------------------- figures


def one_round(browser: Any, charts: list[str], changes: int) -> dict[str, Any]:
    result: dict[str, Any] = {"paint": {}, "colour": {}, "frame": {}}

    def page_of() -> Any:
        context = browser.new_context(viewport={"width": 1280, "height": 800})
        page = context.new_page()
        page.add_init_script(HOOK)
        return context, page

    with empty_viser() as url:
        for _ in range(2):  # the first page of a browser pays for its start: not counted
            context, page = page_of()
            result["paint"]["empty"] = first_paint(page, url, empty=True)
            context.close()
    for chart in charts:
        with cpu(chart) as machine:
            context, page = page_of()
            try:
                result["paint"][chart] = first_paint(page, machine.url, empty=False)
                error = page.evaluate("window.__bench.error")
                if error:
                    print(f"  {chart}: the websocket hook failed: {error}")
                if chart in COLOUR_CHARTS:
                    result["colour"][chart] = colour_latency(page, machine, changes)
                    result["frame"][chart] = frame_cost(page)
            finally:
                context.close()
        if chart in COLOUR_CHARTS:  # its peer, right after it
            with bare_boxes(int(chart[4:])) as boxes:
                context, page = page_of()
                try:
                    page.goto(boxes.url, timeout=120_000)
                    time.sleep(QUIET_S)
                    result["colour"][peer_of(chart)] = colour_latency(page, boxes, changes)
                    result["frame"][peer_of(chart)] = frame_cost(page)
                finally:
                    context.close()
    return result


def peer_of(chart: str) -> str:
    """The name of a loop chart's peer (``Boxes``): ``bare8`` for ``loop8``."""
    return "bare" + chart[4:]


def colour_table(rounds: list[dict[str, Any]], charts: list[str]) -> None:
    """Print the colour figures of ``charts`` and of their peers, and the ratio of each
    round's p99 to its peer's (measured right after it, in the same browser)."""
    print("\ncolour: from the CPU's scan of the change (bareN: the peer's set) to ... (ms)")
    print(f"{'chart':8} {'to':34} {'n':>9} {'p50':>17} {'p99':>17}  target p99")
    for chart in [name for c in charts for name in (c, peer_of(c))]:
        runs = [r["colour"][chart] for r in rounds if chart in r["colour"]]
        for key, what in MEASURES:
            if not any(key in r for r in runs):
                continue
            n = [len(r.get(key, [])) for r in runs]
            missed = [len(r["missed"]) if key == "colour" else 0 for r in runs]
            p50 = [pct(r.get(key, []), 0.5) for r in runs]
            p99 = [pct(r.get(key, []), 0.99) for r in runs]
            target = ""
            if key == "colour" and chart in COLOUR_TARGET_MS:
                goal = COLOUR_TARGET_MS[chart]
                met = "met" if all(v <= goal for v in p99) else "MISSED"
                target = f"<= {goal:.0f}: {met}"
            seen = f"{statistics.median(n):.0f}" + (f"-{max(missed)}" if max(missed) else "")
            p50s, p99s = spread(p50, "{:.0f}"), spread(p99, "{:.0f}")
            print(f"{chart:8} {what:34} {seen:>9} {p50s:>17} {p99s:>17}  {target}")
    print("\nthe page settled (its canvas's size unchanged for 4 s) after … s")
    for chart in [name for c in charts for name in (c, peer_of(c))]:
        waited = [r["colour"][chart]["settled"][0] for r in rounds if chart in r["colour"]]
        if waited:
            print(f"{chart:8} {spread(waited, '{:.1f}'):>17}")
    print("\nframes while it runs: per second, and the browser's CPU time per frame (ms)")
    for chart in [name for c in charts for name in (c, peer_of(c))]:
        got = [r["frame"][chart] for r in rounds if chart in r.get("frame", {})]
        if got:
            rate, cost = (
                spread([g[0] for g in got], "{:.1f}"),
                spread([g[1] for g in got], "{:.0f}"),
            )
            print(f"{chart:8} {rate:>17}/s {cost:>17} ms")
    for chart in charts:
        pairs = [
            (r["colour"][chart]["colour"], r["colour"][peer_of(chart)]["colour"])
            for r in rounds
            if chart in r["colour"] and peer_of(chart) in r["colour"]
        ]
        for q, name in ((0.5, "p50"), (0.99, "p99")):
            ratio = [pct(ours, q) / pct(bare, q) for ours, bare in pairs]
            print(f"{chart} colour {name} ÷ {peer_of(chart)}'s: {spread(ratio, '{:.2f}')}")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeat", type=int, default=1, help="rounds; min/median/max over them")
    ap.add_argument("--changes", type=int, default=100, help="step changes watched per chart")
    ap.add_argument("--charts", default=",".join(CHARTS))
    ap.add_argument(
        "--worker",
        nargs=5,
        metavar=("CHART", "PATH", "EP", "PORT", "STATE"),
        help=argparse.SUPPRESS,
    )
    args = ap.parse_args(argv)
    if args.worker:
        chart, path, endpoint, port, state = args.worker
        return worker(chart, Path(path), endpoint, int(port), Path(state))
    if not os.path.exists(CHROMIUM):
        print(f"no browser at {CHROMIUM}")
        return 1
    from playwright.sync_api import sync_playwright

    charts = [c for c in args.charts.split(",") if c]
    print(
        f"python {sys.version.split()[0]}, {os.cpu_count()} cores, cycle {CYCLE_MS:g} ms, "
        f"{args.changes} changes per chart, {args.repeat} round(s); ms, min/median/max "
        "over rounds"
    )
    rounds: list[dict[str, Any]] = []
    loads: list[float] = []
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, headless=True, args=CHROMIUM_ARGS)
        try:
            for i in range(args.repeat):
                before = os.getloadavg()[0]
                r = one_round(browser, charts, args.changes)
                loads.append((before + os.getloadavg()[0]) / 2)
                rounds.append(r)
                paints = ", ".join(f"{k} {v[0]:.0f}/{v[1]:.0f}" for k, v in r["paint"].items())
                colours = ", ".join(
                    f"{k} p50 {pct(v['colour'], 0.5):.0f} p99 {pct(v['colour'], 0.99):.0f} "
                    f"({len(v['colour'])} seen, {len(v['missed'])} missed)"
                    for k, v in r["colour"].items()
                )
                print(
                    f"  round {i + 1}: first paint {paints}; colour {colours}; "
                    f"load {loads[-1]:.1f}",
                    flush=True,
                )
        finally:
            browser.close()

    colour_table(rounds, [c for c in charts if c in COLOUR_CHARTS])
    print(
        "\nfirst paint: page.goto -> painted frame with the whole chart, and with its panel's "
        "status line too (ms)"
    )
    empty = [r["paint"]["empty"][0] for r in rounds]
    print(
        f"{'page':8} {'chart':>17} {'÷ empty':>14} {'with panel':>17} {'÷ empty':>14}  "
        f"target <= {PAINT_TARGET:g}x empty"
    )
    print(f"{'empty':8} {spread(empty, '{:.0f}'):>17}")
    for chart in charts:
        cells = []
        met = True
        for i in (0, 1):
            paint = [r["paint"][chart][i] for r in rounds]
            ratio = [r["paint"][chart][i] / r["paint"]["empty"][0] for r in rounds]
            met = met and all(v <= PAINT_TARGET for v in ratio)
            cells += [f"{spread(paint, '{:.0f}'):>17}", f"{spread(ratio, '{:.1f}'):>14}"]
        print(f"{chart:8} {' '.join(cells)}  {'met' if met else 'MISSED'}")
    print(f"\nload average during the rounds: {spread(loads, '{:.1f}')}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
