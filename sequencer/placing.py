"""Placing the sequence: the operator names the steps the sequence stands at, and they
become the active ones in one call (docs/semantics.md, "Synchronization").

S7-GRAPH's Control Sequencer moves a sequence in MAN one step per call: S_OFF on a step,
S_ON on another (manual 14-8; docs/semantics.md §8). Between those calls the plant runs a
position nobody chose — the old step's N actions beside the new one's, or none at all. A
placement does the whole move in one call, in step 2 of the call (where S_ON and S_OFF
act), in MAN only:

- every sequence holding at least one of the named steps ends with exactly the named steps
  of it active; its other active steps leave first, each with its final scan and event S0
  as S_OFF does, then the named steps not active enter with S1 as S_ON does (their S1 rows
  run in this call, and a step entered so stays for the call);
- a sequence holding none of the named steps keeps its steps, their times and errors.

:func:`moves` says what a placement does to a state, for the runtime and for the page or
the bus that checks a request before queuing it.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Any

__all__ = ["moves", "place"]


def moves(
    step_seq: Sequence[int], active: Iterable[int], steps: Iterable[int]
) -> tuple[list[int], list[int]]:
    """(the steps that leave, the steps that enter) when ``steps`` (indices) are placed on
    a state whose active steps are ``active``; ``step_seq`` gives each step's sequence."""
    wanted = list(dict.fromkeys(steps))
    sequences = {step_seq[i] for i in wanted}
    now = list(active)
    leave = [i for i in now if step_seq[i] in sequences and i not in wanted]
    held = set(now)
    return leave, [i for i in wanted if i not in held]


def place(rt: Any, steps: Sequence[int]) -> None:
    """Place ``steps`` (indices) on the runtime ``rt`` (``GraphRuntime``) in step 2 of its
    call: nothing outside MAN."""
    st = rt.st
    if st.mode != "MAN":
        return
    leave, enter = moves(rt.cc.step_seq, st.active, steps)
    for i in leave:
        rt.off(i)
    for i in enter:
        rt.on(i)
