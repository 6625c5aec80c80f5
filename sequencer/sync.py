"""Synchronization: where the process stands in the chart, to resume it there instead of
at the initial steps (docs/semantics.md, "Synchronization").

When a plant was stopped in mid-sequence, moved by hand, or the sequencer was switched off,
INIT_SQ would put the sequence back at its initial steps while the machine is somewhere
else. S7-GRAPH's debugger offers *Synchronization* for this (S7-GRAPH V5 manual,
C79000-G7076-C526-01, ch. 14.2 "Initialization": "the sequencer can be synchronized with
the process state using the synchronize function"): it looks at the current process
values and marks the steps at which the sequence could go on. A step fits when

- its interlock holds (a step without interlock: always) — its conditioned actions could
  run, the machine is in that step's state; and
- none of its leaving transitions holds — its work is not done yet, else the following
  step would be the one.

Beside these two, each step says whether a transition leading into it holds now
(``entered``: the step before it looks done; a step no transition leads to, such as an
initial step without a jump back, counts as entered) — a fitting step that was also entered
is the likeliest place (``likely``). The operator then activates the chosen steps in MAN
(S_ON), as in S7-GRAPH.

The judgement is a pure function of the compiled chart, its conditions bound to the CPU's
memory and the FB's state: every transition and interlock condition is evaluated once on
the values of the scan just ended, whatever the steps' activity; nothing is written — the
state, its criteria bits and the process image stay as they were. A condition that reads
a step's times (``S3.T``) reads the times the FB keeps for an inactive step (the last
activation's).
"""

from __future__ import annotations

from dataclasses import dataclass

from s7graph.sequencer.compiled import CompiledChart, Program
from s7graph.sequencer.state import GraphState

__all__ = ["SyncStep", "synchronization"]


@dataclass(frozen=True, slots=True)
class SyncStep:
    """One step judged against the process: its number and name, its sequence's number,
    whether it is active now, whether its interlock holds, whether a transition into it
    holds (``entered``) and the leaving transitions that hold (numbers, priority order)."""

    number: int
    name: str
    sequence: int
    active: bool
    interlock: bool
    entered: bool
    done: tuple[int, ...]

    @property
    def fits(self) -> bool:
        """The sequence could go on at this step: its interlock holds, no leaving
        transition does."""
        return self.interlock and not self.done

    @property
    def likely(self) -> bool:
        """It fits and the step before it looks done (a transition into it holds)."""
        return self.fits and self.entered


def synchronization(cc: CompiledChart, prog: Program, st: GraphState) -> tuple[SyncStep, ...]:
    """Every step of ``cc`` judged on the current values (``prog``: its conditions bound to
    the CPU's memory; ``st``: the FB's state, only read), in chart order."""
    holds = tuple(bool(cond(st)[0]) for cond in prog.tcond)
    into: list[list[int]] = [[] for _ in range(cc.n_steps)]
    for j, targets in enumerate(cc.tr_dst):
        for i in targets:
            into[i].append(j)
    seqs = cc.seq_numbers
    out = []
    for i in range(cc.n_steps):
        il = prog.ilc[i]
        out.append(
            SyncStep(
                number=cc.step_numbers[i],
                name=cc.step_names[i],
                sequence=seqs[cc.step_seq[i]],
                active=bool(st.x[i]),
                interlock=True if il is None else bool(il(st)[0]),
                entered=any(holds[j] for j in into[i]) or not into[i],
                done=tuple(cc.transition_numbers[j] for j in cc.leaving[i] if holds[j]),
            )
        )
    return tuple(out)
