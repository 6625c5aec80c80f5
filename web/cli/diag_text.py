"""A diagnostic entry as one line of text (``s7graph diag``, ``s7graph status``): when it
happened and what it says, as STEP 7's diagnostic buffer shows it."""

from __future__ import annotations

import time

from s7graph.web.bus.protocol import DiagEvent

__all__ = ["event_line", "when"]


def when(event: DiagEvent) -> str:
    """The entry's time: local date and time to the ms, or the CPU clock's seconds."""
    if event.wall_ms:
        seconds, ms = divmod(event.wall_ms, 1000)
        return time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(seconds)) + f".{ms:03d}"
    return f"CPU clock {event.t_ms / 1000:.3f} s"


def event_line(event: DiagEvent) -> str:
    """``16#4562  OB121 PK 1  text: block @address: message`` (no number, no time)."""
    ob = f"OB{event.ob} PK{event.priority}" if event.ob else "-"
    said = " ".join(
        part
        for part in (
            event.block,
            f"@{event.address}" if event.address else "",
        )
        if part
    )
    info = f"{said}: {event.info}" if said and event.info else said or event.info
    text = f"{event.text}: {info}" if info else event.text
    return f"16#{event.event_id:04X}  {ob:<12}  {_one_line(text)}"


def _one_line(text: str) -> str:
    return " ".join(text.split())
