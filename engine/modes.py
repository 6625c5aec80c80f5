"""CPU operating modes and mode requests (docs/runtime.md, "Restarts: warm, hot, cold"; Siemens'
Program Design for S7-300/400, ch. 9, Table 9-1).

Simultaneous requests resolve to the highest priority: STOP > HOLD > STARTUP > RUN . The key switch
gates every start: with the key on STOP a RUN request is refused.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from enum import StrEnum


class CpuMode(StrEnum):
    """The four operating modes of the CPU."""

    STOP = "STOP"
    STARTUP = "STARTUP"
    RUN = "RUN"
    HOLD = "HOLD"


class KeySwitch(StrEnum):
    """The (virtual) mode selector; only RUN and RUN_P allow a start."""

    STOP = "STOP"
    RUN = "RUN"
    RUN_P = "RUN-P"


REQUEST_PRIORITY: dict[CpuMode, int] = {
    CpuMode.STOP: 4,
    CpuMode.HOLD: 3,
    CpuMode.STARTUP: 2,
    CpuMode.RUN: 1,
}
"""Mode-request priority, highest wins (Siemens' Program Design for S7-300/400)."""

TRANSITIONS: frozenset[tuple[CpuMode, CpuMode]] = frozenset(
    {
        (CpuMode.STOP, CpuMode.STARTUP),  # 2
        (CpuMode.STARTUP, CpuMode.STOP),  # 3
        (CpuMode.STARTUP, CpuMode.HOLD),  # 4
        (CpuMode.HOLD, CpuMode.STARTUP),  # 5
        (CpuMode.HOLD, CpuMode.STOP),  # 6
        (CpuMode.STARTUP, CpuMode.RUN),  # 7
        (CpuMode.RUN, CpuMode.STOP),  # 8
        (CpuMode.RUN, CpuMode.HOLD),  # 9
        (CpuMode.HOLD, CpuMode.RUN),  # 10
    }
)
"""Allowed mode transitions, Siemens' Program Design for S7-300/400, table 9-1."""


def resolve_requests(requests: Iterable[CpuMode]) -> CpuMode | None:
    """The winning request of several made at once, or None if none."""
    best: CpuMode | None = None
    for mode in requests:
        if best is None or REQUEST_PRIORITY[mode] > REQUEST_PRIORITY[best]:
            best = mode
    return best


@dataclass(frozen=True, slots=True)
class ModeRequest:
    """A command asking for a mode (applied at a scan boundary); RUN from STOP uses ``restart``."""

    mode: CpuMode
    restart: str = "warm"
    reason: str = ""


@dataclass(frozen=True, slots=True)
class SetKeySwitch:
    """A command turning the key switch; turning it to STOP stops a running CPU."""

    position: KeySwitch
