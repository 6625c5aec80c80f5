"""Wire a chart, a feed of scans, the bus and the browser view together (the README's demo).

``serve_view(chart, updates)`` opens two loopback zenoh sessions — the CPU's and the
view's — so the view reaches the CPU only over the bus, the same path a remote view takes.
``python -m web.demo`` runs a hand-made chart on :class:`ToySequencer`, a stand-in that
moves steps on a timer, until Ctrl-C.
"""

from __future__ import annotations

import argparse
import contextlib
import shutil
import tempfile
import threading
import time
from collections.abc import Callable, Iterable, Iterator

from sequencer.model import Chart, Operand, Sequence, Step, Transition
from web.bus import BusClient, BusPublisher, open_session
from web.protocol import ChartLayout, Command, StepStateUpdate
from web.view import ChartView, make_server

__all__ = ["ToySequencer", "WebEdge", "demo_chart", "main", "serve_view"]

Apply = Callable[[Command], tuple[bool, str]]


class WebEdge:
    """A running view: ``publisher`` is the CPU's side of the bus, ``url`` the page."""

    def __init__(
        self,
        chart: Chart | ChartLayout,
        *,
        host: str,
        port: int,
        cpu: str,
        fb: str | None,
        endpoint: str | None,
    ) -> None:
        layout = chart if isinstance(chart, ChartLayout) else ChartLayout.from_chart(chart, fb=fb)
        self.fb = layout.fb
        self._tmp = None if endpoint else tempfile.mkdtemp(prefix="s7graph-bus-")
        self.endpoint = endpoint or f"unixsock-stream/{self._tmp}/bus.sock"
        self._stop = threading.Event()
        self._pump: threading.Thread | None = None
        self._closers: list[Callable[[], object]] = []
        try:
            cpu_session = open_session(listen=[self.endpoint])
            self._closers.append(cpu_session.close)
            self.publisher = BusPublisher(cpu_session, cpu, {self.fb: layout})
            self._closers.append(self.publisher.close)
            view_session = open_session(connect=[self.endpoint])
            self._closers.append(view_session.close)
            self.client = BusClient(view_session, cpu)
            self._closers.append(self.client.close)
            seen = self._wait_for_chart()
            self.server = make_server(host, port)
            self._closers.append(self.server.stop)
            self.view = ChartView(self.server, seen, self.client.send)
            self._closers.append(self.view.close)
            self.follower = self.client.follow(self.fb, self.view.apply)
            self.client.on_status(self.view.apply_status)
            self.client.on_alarms(self.view.apply_alarms)
        except BaseException:
            self.close()
            raise
        self.url = f"http://{host}:{self.server.get_port()}/"

    def _wait_for_chart(self, timeout: float = 5.0) -> ChartLayout:
        deadline = time.monotonic() + timeout
        while True:
            layout = self.client.chart(self.fb)
            if layout is not None:
                return layout
            if time.monotonic() > deadline:
                raise TimeoutError(f"no chart for FB {self.fb!r} on the bus within {timeout:g} s")
            time.sleep(0.05)

    def pump(self, updates: Iterable[StepStateUpdate], apply: Apply | None) -> None:
        """Publish ``updates`` in a thread; between two of them, apply pending commands."""

        def refuse(command: Command) -> tuple[bool, str]:
            return False, "this CPU takes no commands"

        def run() -> None:
            for update in updates:
                if self._stop.is_set():
                    return
                self.publisher.publish(self.fb, update)
                self.publisher.apply_commands(apply or refuse, cycle=update.cycle)

        self._pump = threading.Thread(target=run, name="s7graph-feed", daemon=True)
        self._pump.start()

    def wait(self) -> None:
        """Block until the feed ends or Ctrl-C."""
        try:
            while self._pump is not None and self._pump.is_alive():
                self._pump.join(0.2)
            if self._pump is None:
                while True:
                    time.sleep(1.0)
        except KeyboardInterrupt:
            pass

    def close(self) -> None:
        """Stop the feed, the view, the bus and the server; close both sessions."""
        self._stop.set()
        if self._pump is not None:
            self._pump.join(timeout=2.0)
        while self._closers:
            with contextlib.suppress(Exception):  # keep closing the rest
                self._closers.pop()()
        if self._tmp:
            shutil.rmtree(self._tmp, ignore_errors=True)

    def __enter__(self) -> WebEdge:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def serve_view(
    chart: Chart | ChartLayout,
    updates_source: Iterable[StepStateUpdate] | None,
    *,
    host: str = "127.0.0.1",
    port: int = 8080,
    cpu: str = "cpu1",
    fb: str | None = None,
    apply_command: Apply | None = None,
    endpoint: str | None = None,
) -> WebEdge:
    """Serve the browser view of ``chart`` and return the running edge (close it when done).

    ``updates_source`` yields one :class:`StepStateUpdate` per scan (it may block to pace
    the scans); between two of them, ``apply_command(command) -> (applied, reason)`` runs
    for each command from the view — a scan boundary when the iterator runs the scan. With
    ``updates_source=None`` the caller drives ``edge.publisher`` itself. ``endpoint`` is the
    bus's listen endpoint (default: a unix socket in a temporary directory)."""
    edge = WebEdge(chart, host=host, port=port, cpu=cpu, fb=fb, endpoint=endpoint)
    if updates_source is not None:
        edge.pump(updates_source, apply_command)
    return edge


# ---------------------------------------------------------------- the demo's stand-in CPU


class ToySequencer:
    """A stand-in for the GraphFB: fires every ready transition after ``hold`` scans in AUTO
    (on T_PUSH in TAP/TOP), ignores conditions. A step with supervision waits ``3 * hold``
    scans and latches a supervision error after ``2 * hold``, held until Acknowledge."""

    def __init__(self, layout: ChartLayout, *, hold: int = 15) -> None:
        self.layout = layout
        self.hold = hold
        self.mode = "AUTO"
        self.cycle = 0
        self.active: dict[int, int] = {}  # step -> scans active
        self.latched: set[int] = set()
        self._events: list[tuple[str, int]] = []
        self._push = False
        self.init()

    def init(self) -> None:
        for step in list(self.active):
            self._off(step)
        for s in self.layout.steps:
            if s.initial:
                self._on(s.number)

    def _on(self, step: int) -> None:
        if step not in self.active:
            self.active[step] = 0
            self._events.append(("S1", step))

    def _off(self, step: int) -> None:
        if self.active.pop(step, None) is not None:
            self._events.append(("S0", step))
        self.latched.discard(step)

    def apply(self, command: Command) -> tuple[bool, str]:
        """Apply one command at the scan boundary; (applied, reason)."""
        match command.op:
            case "ack":
                if not self.latched:
                    return False, "no error to acknowledge"
                for step in sorted(self.latched):
                    self._events.append(("A1", step))
                    self.active[step] = 0
                self.latched.clear()
            case "mode":
                self.mode = command.mode or self.mode
            case "init":
                self.init()
            case "off":
                for step in list(self.active):
                    self._off(step)
            case "t_push":
                if self.mode not in ("TAP", "TOP"):
                    return False, "T_PUSH works in TAP and TOP only"
                self._push = True
            case "step_on" | "step_off":
                step = command.step or 0
                if self.mode != "MAN":
                    return False, "activating or deactivating steps needs MAN mode"
                if self.layout.step(step) is None:
                    return False, f"no step S{step}"
                (self._on if command.op == "step_on" else self._off)(step)
        return True, ""

    def scan(self, t_ms: int) -> StepStateUpdate:
        self.cycle += 1
        for step in self.active:
            self.active[step] += 1
            info = self.layout.step(step)
            overdue = info is not None and info.supervision and self.active[step] > 2 * self.hold
            if overdue and step not in self.latched:
                self.latched.add(step)
                self._events.append(("V1", step))
        ready = self.mode == "AUTO" or (self.mode in ("TAP", "TOP") and self._push)
        if ready:
            for t in self.layout.transitions:
                sources = [self.active.get(s) for s in t.sources]
                supervised = any((i := self.layout.step(s)) and i.supervision for s in t.sources)
                need = 3 * self.hold if supervised else self.hold
                if any(n is None or n < need for n in sources):
                    continue
                if any(s in self.latched for s in t.sources):
                    continue
                for s in t.sources:
                    self._off(s)
                for s in t.targets:
                    self._on(s)
                self._push = False
        events, self._events = self._events, []
        return StepStateUpdate(
            cycle=self.cycle,
            t_ms=t_ms,
            mode=self.mode,  # type: ignore[arg-type]
            active=sorted(self.active),
            disturbed=sorted(self.latched),
            latched=sorted(self.latched),
            events=events,  # type: ignore[arg-type]
        )

    def run(self, cycle_ms: float = 100.0) -> Iterator[StepStateUpdate]:
        """Scan forever, paced by the wall clock."""
        start = time.monotonic()
        while True:
            yield self.scan(int((time.monotonic() - start) * 1000))
            time.sleep(cycle_ms / 1000)


def demo_chart() -> Chart:
    """A mixing tank: fill, then heat and stir side by side, drain or rinse, back to start."""

    def step(n: int, name: str, **kw: object) -> Step:
        return Step(n, name, **kw)  # type: ignore[arg-type]

    def trans(n: int, src: tuple[int, ...], dst: tuple[int, ...], cond: str | None) -> Transition:
        return Transition(n, f"T{n}", src, dst, Operand(cond, quoted=True) if cond else None)

    main_seq = Sequence(
        1,
        "Tank",
        (
            step(1, "Idle", initial=True),
            step(2, "Fill", interlock=Operand("Inlet_ok", quoted=True)),
            step(3, "Heat", supervision=Operand("Heat_timeout", quoted=True)),
            step(4, "Stir"),
            step(5, "Drain"),
            step(6, "Rinse"),
        ),
        (
            trans(1, (1,), (2,), "Start"),
            trans(2, (2,), (3, 4), "Level_high"),
            trans(3, (3, 4), (5,), "Temp_ok"),
            trans(4, (5,), (1,), "Level_low"),
            trans(5, (5,), (6,), "Dirty"),
            trans(6, (6,), (1,), None),
        ),
    )
    alarm_seq = Sequence(
        2,
        "Horn",
        (step(10, "Quiet", initial=True), step(11, "Horn")),
        (trans(10, (10,), (11,), "Alarm"), trans(11, (11,), (), None)),
    )
    return Chart(
        "TANK",
        sequences=(main_seq, alarm_seq),
    )


def main(argv: list[str] | None = None) -> int:
    """``python -m web.demo``: the demo chart on the toy sequencer, served on 127.0.0.1."""
    parser = argparse.ArgumentParser(description=main.__doc__)
    parser.add_argument("--host", default="127.0.0.1")
    parser.add_argument("--port", type=int, default=8080)
    parser.add_argument("--cycle-ms", type=float, default=100.0)
    args = parser.parse_args(argv)
    chart = demo_chart()
    toy = ToySequencer(ChartLayout.from_chart(chart))
    with serve_view(
        chart, toy.run(args.cycle_ms), host=args.host, port=args.port, apply_command=toy.apply
    ) as edge:
        print(f"s7graph demo: {edge.url} (Ctrl-C to stop)")
        edge.wait()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
