"""Simulated drilling machine for ``examples/drill/drill.s7g`` (STEP7 comprehensive guide vol. 2,
ch. 14).

Loaded by ``s7graph sim --plant``: ``Plant.cycle(io, t_ms, dt_ms)`` runs once per cycle after
the FB has written its outputs; it reads outputs with ``io.get`` and writes the module side
of inputs with ``io.set`` (names are the symbols of ``symbols.txt``).

The model: the drill motor reaches speed ``MOTOR_RUNUP_MS`` after "Dr_mot_on" and stands
still ``MOTOR_RUNDOWN_MS`` after it goes off; the clamping pressure builds up
``CLAMP_RISE_MS`` after "Clamp_workp" and drops at once on release; the coolant pressure
follows the pump after ``COOLANT_RISE_MS``; the drill travels ``TRAVEL_MM`` between its two
limit switches at ``SPEED_MM_S`` while "Lower_drill" or "Raise_drill" is on. The operator
presses "Start_button" once, at ``START_AT_MS`` for ``START_PRESS_MS``. Subclass and change
the class attributes to model faults (e.g. a clamp that never reaches pressure).
"""

from __future__ import annotations

from typing import Protocol


class IO(Protocol):
    def get(self, name: str) -> object: ...
    def set(self, name: str, value: object) -> None: ...


class Plant:
    """Drill motor, clamp, coolant pump, drill slide and the operator's start button."""

    START_AT_MS: int = 1000
    START_PRESS_MS: int = 200
    MOTOR_RUNUP_MS: int = 200
    MOTOR_RUNDOWN_MS: int = 300
    CLAMP_RISE_MS: int = 300
    COOLANT_RISE_MS: int = 150
    TRAVEL_MM: float = 100.0
    SPEED_MM_S: float = 50.0

    def __init__(self) -> None:
        self.position_mm = 0.0  # 0 = upper limit, TRAVEL_MM = lower limit
        self.motor_on_ms = 0  # how long the motor has been switched on / off
        self.motor_off_ms = self.MOTOR_RUNDOWN_MS
        self.clamp_ms = 0
        self.coolant_ms = 0

    def cycle(self, io: IO, t_ms: int, dt_ms: int) -> None:
        motor = bool(io.get("Dr_mot_on"))
        if motor:
            self.motor_on_ms += dt_ms
            self.motor_off_ms = 0
        else:
            self.motor_off_ms += dt_ms
            self.motor_on_ms = 0
        self.clamp_ms = self.clamp_ms + dt_ms if io.get("Clamp_workp") else 0
        self.coolant_ms = self.coolant_ms + dt_ms if io.get("Cool_pump_on") else 0

        step = self.SPEED_MM_S * dt_ms / 1000.0
        if io.get("Lower_drill") and not io.get("Raise_drill"):
            self.position_mm = min(self.TRAVEL_MM, self.position_mm + step)
        elif io.get("Raise_drill") and not io.get("Lower_drill"):
            self.position_mm = max(0.0, self.position_mm - step)

        io.set("Dr_mot_running", motor and self.motor_on_ms >= self.MOTOR_RUNUP_MS)
        io.set("Dr_mot_stopped", not motor and self.motor_off_ms >= self.MOTOR_RUNDOWN_MS)
        io.set("Cl_press_ok", self.clamp_ms >= self.CLAMP_RISE_MS)
        io.set("Cool_press_ok", self.coolant_ms >= self.COOLANT_RISE_MS)
        io.set("Drill_up", self.position_mm <= 0.0)
        io.set("Drill_down", self.position_mm >= self.TRAVEL_MM)
        pressed = self.START_AT_MS <= t_ms < self.START_AT_MS + self.START_PRESS_MS
        io.set("Start_button", pressed)
