"""Simulated pair of belts for ``examples/conveyor/conveyor.s7g`` (STEP7 comprehensive guide vol. 2,
ch. 14).

Belt A drops material onto belt B, and belt B needs ``TRANSIT_MS`` (7 s) to carry a load off
its end. That is why the book starts B before A and stops A 7 s before B. The model keeps
the load on belt B as milliseconds of material: it grows while both belts run (up to a
full belt, ``TRANSIT_MS``) and shrinks while only B runs. Inputs written back:
"Spill" latches when A runs while B stands; "Belt_B_empty" is true when B carries nothing.
The buttons are the operator's and come from ``stimulus.jsonl``.
"""

from __future__ import annotations

from typing import Protocol


class IO(Protocol):
    def get(self, name: str) -> object: ...
    def set(self, name: str, value: object) -> None: ...


class Plant:
    """Material on belt B, and spillage when A feeds a belt that is not moving."""

    TRANSIT_MS: int = 7000

    def __init__(self) -> None:
        self.load_ms = 0
        self.spilled = False

    def cycle(self, io: IO, t_ms: int, dt_ms: int) -> None:
        a, b = bool(io.get("Belt_A")), bool(io.get("Belt_B"))
        if a and not b:
            self.spilled = True
        elif a and b:
            self.load_ms = min(self.TRANSIT_MS, self.load_ms + dt_ms)
        elif b:
            self.load_ms = max(0, self.load_ms - dt_ms)
        io.set("Spill", self.spilled)
        io.set("Belt_B_empty", self.load_ms == 0)
