"""Simulated mixing tank for ``examples/mixing/mixing.s7g`` (Siemens' Program Design for S7-300/400,
ch. 1 and appendix A, Siemens' Program Design for S7-300/400, appendix A).

Each feed pump delivers ``PUMP_L_S`` litres a second (400 l/min, seed 002 Table 1-2) into
the tank while the pump runs and both its inlet and feed valve are open; its flow sensor
then reports flow (``FLOW_A_BROKEN_UNTIL_MS`` models a sensor that stays silent). The
agitator reaches rated speed ``AGITATOR_RUNUP_MS`` after its contactor closes and stands
still ``AGITATOR_RUNDOWN_MS`` after it opens. The drain valve empties the tank at
``DRAIN_L_S``. Level switches: "below max" (NC) opens at ``MAX_L``, "above min" (NO) closes
at ``MIN_L``, "not empty" closes above ``EMPTY_L``. EMERGENCY STOP and "Batch_start" are
the operator's and come from ``stimulus.jsonl``.
"""

from __future__ import annotations

from typing import Protocol


class IO(Protocol):
    def get(self, name: str) -> object: ...
    def set(self, name: str, value: object) -> None: ...


class Plant:
    """Tank level, the two feeds with their flow sensors, agitator and drain."""

    PUMP_L_S: float = 400.0 / 60.0
    DRAIN_L_S: float = 10.0
    MAX_L: float = 400.0
    MIN_L: float = 50.0
    EMPTY_L: float = 0.5
    AGITATOR_RUNUP_MS: int = 2000
    AGITATOR_RUNDOWN_MS: int = 1000
    FLOW_A_BROKEN_UNTIL_MS: int = 0

    def __init__(self) -> None:
        self.level_l = 0.0
        self.agitator_on_ms = 0
        self.agitator_off_ms = 0
        self.at_speed = False

    def cycle(self, io: IO, t_ms: int, dt_ms: int) -> None:
        dt_s = dt_ms / 1000.0
        flow_a = bool(
            io.get("Speisepumpe_A") and io.get("Einlassventil_A") and io.get("Speiseventil_A")
        )
        flow_b = bool(
            io.get("Speisepumpe_B") and io.get("Einlassventil_B") and io.get("Speiseventil_B")
        )
        self.level_l += (flow_a + flow_b) * self.PUMP_L_S * dt_s
        if io.get("Abfluss"):
            self.level_l = max(0.0, self.level_l - self.DRAIN_L_S * dt_s)

        if io.get("Ruehrwerk"):
            self.agitator_on_ms += dt_ms
            self.agitator_off_ms = 0
        else:
            self.agitator_off_ms += dt_ms
            self.agitator_on_ms = 0
        if self.agitator_on_ms >= self.AGITATOR_RUNUP_MS:
            self.at_speed = True
        elif self.agitator_off_ms >= self.AGITATOR_RUNDOWN_MS:
            self.at_speed = False

        io.set("Durchfluss_A", flow_a and t_ms >= self.FLOW_A_BROKEN_UNTIL_MS)
        io.set("Durchfluss_B", flow_b)
        io.set("Ruehrwerk_laeuft", self.at_speed)
        io.set("Behaelter_unter_Max", self.level_l < self.MAX_L)
        io.set("Behaelter_ueber_Min", self.level_l >= self.MIN_L)
        io.set("Behaelter_nicht_Leer", self.level_l > self.EMPTY_L)
