"""What a part of the CPU (``cpu_errors``, ``cpu_interrupts``, ``cpu_stops``) reads and
calls of the ``Cpu`` it is mixed into: its mode, OBs and diagnostic buffer, the time of the
scan, and how it runs an OB or goes to STOP."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from s7graph.engine.blocks import OB
from s7graph.engine.diagnostics import DiagnosticBuffer
from s7graph.engine.modes import CpuMode

__all__ = ["CpuPart"]


class CpuPart:
    """The ``Cpu`` as its parts see it (declarations only: ``Cpu`` defines them)."""

    mode: CpuMode
    obs: dict[int, OB]
    diagnostics: DiagnosticBuffer
    _raw: int

    if TYPE_CHECKING:

        def priority_of(self, ob: int) -> int: ...

        def _run_ob(
            self, number: int, start_info: dict[str, Any], *, nested: bool = False
        ) -> None: ...

        def _go_stop(self, event: int, block: str, message: str) -> None: ...
