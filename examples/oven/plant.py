"""Simulated electric oven for ``examples/oven/oven.s7g`` and ``examples/oven/oven.scl``.

A first-order thermal model: the oven's heat capacity ``CAPACITY_J_K`` is heated by the
heating element, ``HEATER_W`` while the contactor "Heater" is closed, and loses heat to the
room through its walls, ``LOSS_W_K`` per kelvin above ``AMBIENT_C``:

    CAPACITY_J_K * dT/dt = HEATER_W * heater - LOSS_W_K * (T - AMBIENT_C)

Over one cycle the heater is on or off, so each cycle steps the exact solution: T moves
towards ``AMBIENT_C + HEATER_W / LOSS_W_K * heater`` (320 C with the heater on, 20 C off)
with the time constant ``CAPACITY_J_K / LOSS_W_K`` (300 s). Holding 180 C takes
``LOSS_W_K * 160 / HEATER_W``, 53 % of the heater's power. The thermocouple module reports
degrees C x 10 in "Oven_temp_AI" (PIW256), rounded to the nearest tenth. Deterministic:
no noise, no clock read. Subclass and change the class attributes for another oven.
"""

from __future__ import annotations

import math
from typing import Protocol


class IO(Protocol):
    def get(self, name: str) -> object: ...
    def set(self, name: str, value: object) -> None: ...


class Plant:
    """The oven's temperature, its heater and its losses."""

    AMBIENT_C: float = 20.0
    HEATER_W: float = 3000.0
    LOSS_W_K: float = 10.0
    CAPACITY_J_K: float = 3000.0

    def __init__(self) -> None:
        self.temp_c = self.AMBIENT_C

    def cycle(self, io: IO, t_ms: float, dt_ms: float) -> None:
        heater = 1.0 if io.get("Heater") else 0.0
        target = self.AMBIENT_C + self.HEATER_W * heater / self.LOSS_W_K
        decay = math.exp(-self.LOSS_W_K * dt_ms / 1000.0 / self.CAPACITY_J_K)
        self.temp_c = target + (self.temp_c - target) * decay
        io.set("Oven_temp_AI", round(self.temp_c * 10.0))
