"""What a chart or program run keeps in its state file beside the CPU's own memory."""

from __future__ import annotations

from typing import Any

from s7graph.engine.cpu import Cpu
from s7graph.engine.persistence import StateStore
from s7graph.sfb.alarms import message_list

__all__ = ["persist_messages"]


def persist_messages(store: StateStore, cpu: Cpu) -> None:
    """Save the CPU's message list (``sfb.alarms``) with the state; call before ``load``."""
    messages = message_list(cpu)
    cached: list[Any] = [-1, None]  # (changes, snapshot): the same object while unchanged

    def snapshot() -> object:
        if cached[0] != messages.changes:
            cached[:] = [messages.changes, messages.snapshot()]
        return cached[1]

    store.add_part("messages", snapshot, messages.restore)
