"""A stand-in feed of scans for the view tests: moves steps on a timer, ignores conditions.

Test data only (the product's view is always fed by a real GraphFB)."""

from __future__ import annotations

import time
from collections.abc import Iterator

from s7graph.web.bus.protocol import ChartLayout, Command, StepStateUpdate


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
