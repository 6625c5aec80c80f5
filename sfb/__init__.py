"""System blocks: SFB0-5, the process-control SFB41-43, S5 timers/counters, edges,
clock/memory/control SFCs, alarms, RDSYSST/WR_USMSG (docs/runtime.md, "The block runtime";
El-Shahat's S7-300/400 course, timers and counters).

The semantics are pure state machines over ``(inputs, now_ns)``; thin adapters declare them
as engine SFBs/SFCs from the one ``catalogue``. ``install(cpu)`` loads every system block so
``ctx.call("SFB4", 10, IN=..., PT=...)`` and ``ctx.call("SFC46")`` work.
"""

from __future__ import annotations

from typing import Protocol

from s7graph.engine.blocks import FB, FC
from s7graph.sfb import (
    alarms,
    cont_c,
    cont_s,
    diag_read,
    iec_counters,
    iec_timers,
    pulsegen,
    s5_counters,  # noqa: F401  (importing it registers the S5 counter instruction)
    s5_timers,  # noqa: F401  (importing it registers the S5 timer tick)
    sfc_clock,
    sfc_control,
    sfc_db,
    sfc_interrupts,
    sfc_memory,
    sfc_rtm,
)
from s7graph.sfb.alarms import Message, MessageEvent, MessageList, MessageState, message_list
from s7graph.sfb.catalogue import CATALOGUE, Direction, Entry, Kind, Pin, find, lookup
from s7graph.sfb.cont_c import ContC, ContCIn
from s7graph.sfb.cont_s import ContS, ContSIn
from s7graph.sfb.diag_read import rdsysst, wr_usmsg
from s7graph.sfb.edges import F_TRIG, R_TRIG, fn, fp
from s7graph.sfb.iec_counters import CTD, CTU, CTUD
from s7graph.sfb.iec_timers import TOF, TON, TP
from s7graph.sfb.pulsegen import PulseGen, PulseGenIn
from s7graph.sfb.sfc_clock import RealTimeClock, rtc_of
from s7graph.sfb.sfc_memory import AnyPointer, parse_any

__all__ = [
    "CATALOGUE",
    "CTD",
    "CTU",
    "CTUD",
    "F_TRIG",
    "R_TRIG",
    "SYSTEM_BLOCKS",
    "TOF",
    "TON",
    "TP",
    "AnyPointer",
    "ContC",
    "ContCIn",
    "ContS",
    "ContSIn",
    "Direction",
    "Entry",
    "Kind",
    "Message",
    "MessageEvent",
    "MessageList",
    "MessageState",
    "Pin",
    "PulseGen",
    "PulseGenIn",
    "RealTimeClock",
    "find",
    "fn",
    "fp",
    "install",
    "lookup",
    "message_list",
    "parse_any",
    "rdsysst",
    "rtc_of",
    "wr_usmsg",
]

SYSTEM_BLOCKS: tuple[FB | FC, ...] = (
    *iec_counters.BLOCKS,
    *iec_timers.BLOCKS,
    *cont_c.BLOCKS,
    *cont_s.BLOCKS,
    *pulsegen.BLOCKS,
    *sfc_clock.BLOCKS,
    *sfc_rtm.BLOCKS,
    *alarms.BLOCKS,
    *sfc_memory.BLOCKS,
    *sfc_db.BLOCKS,
    *sfc_interrupts.BLOCKS,
    *sfc_control.BLOCKS,
    *diag_read.BLOCKS,
)
"""Every system block with an engine adapter, in catalogue order of kind and number."""


class _Loader(Protocol):
    def load(self, *blocks: FB | FC) -> None: ...


def install(cpu: _Loader) -> None:
    """Load all system blocks into ``cpu`` (they belong to the OS: no download needed).

    The S5 timer update needs no install: importing ``sfb`` registers it as an OS scan hook
    of every CPU (``s5_timers.scan_hook``), so GraphFB timers tick too; the S5 timer and
    counter boxes S7-SCL calls are registered the same way (``engine.instructions``).
    """
    cpu.load(*SYSTEM_BLOCKS)
