"""The drill of ``plant.py`` as a live demo: it works piece after piece, and now and then
the clamp is slow, so the operator sees a supervision fault and acknowledges it.

Used by the README's first command (``s7graph run ... --plant examples/drill/demo_plant.py
--web``). The operator presses "Start_button" ``IDLE_MS`` after the drill is back in
"Ready", alternates "Coolant_sel" (the alternative branch S2 → S3 / S2 → S4), and every
``SLOW_EVERY``-th piece the clamping pressure takes ``SLOW_CLAMP_MS`` — longer than the
500 ms supervision of S2 — so S2 turns red with ERR_FLT until someone presses Acknowledge
in the browser (or sets ACK_EF).
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

_spec = importlib.util.spec_from_file_location(
    "s7graph_drill_plant", Path(__file__).with_name("plant.py")
)
assert _spec is not None and _spec.loader is not None
_base = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_base)


class Plant(_base.Plant):  # type: ignore[name-defined,misc]
    """The drill, an operator who starts every piece, and a clamp that is sometimes slow."""

    START_AT_MS = -(10**9)  # never: this operator presses Start by himself (below)
    IDLE_MS = 1500
    SLOW_EVERY = 3
    SLOW_CLAMP_MS = 900
    NORMAL_CLAMP_MS = 300

    def __init__(self) -> None:
        super().__init__()
        self.pieces = 0
        self.idle_ms = 0
        self.press_ms = 0

    def cycle(self, io: _base.IO, t_ms: int, dt_ms: int) -> None:  # type: ignore[name-defined]
        ready = (
            bool(io.get("Drill_up"))
            and bool(io.get("Dr_mot_stopped"))
            and not io.get("Clamp_workp")
        )
        self.idle_ms = self.idle_ms + dt_ms if ready else 0
        slow = self.SLOW_EVERY and self.pieces % self.SLOW_EVERY == self.SLOW_EVERY - 1
        self.CLAMP_RISE_MS = self.SLOW_CLAMP_MS if slow else self.NORMAL_CLAMP_MS
        # the operator: press Start for 200 ms once the machine has been idle a while
        self.START_AT_MS = -(10**9)  # the base plant's one-shot press is replaced below
        super().cycle(io, t_ms, dt_ms)
        if self.idle_ms >= self.IDLE_MS and self.press_ms == 0:
            self.press_ms = self.START_PRESS_MS
            io.set("Coolant_sel", self.pieces % 2 == 0)
            self.pieces += 1
        if self.press_ms > 0:
            self.press_ms = max(0, self.press_ms - dt_ms)
            io.set("Start_button", True)
            if self.press_ms == 0:
                self.idle_ms = 0
