"""Online change: a changed chart swapped into a running GRAPH FB (docs/online-change.md;
the state lives in the instance DB, docs/architecture.md, "The core is a function").

:func:`preview` says what a download of ``new`` over the running chart changes (the change
summary of ``sequencer.change.diff``, with the active steps it removes). :func:`swap`, called at a
scan boundary, carries the FB's state over to ``new`` by step number with the one function
that does so (``sequencer.change.carry.carry_over``: active steps stay active with T and U, faults
and criteria, variables keep their values by name) and makes the FB run ``new`` from its
next call (``GraphFB.replace_chart``), the instance DBs of the system blocks it calls
created first (``sequencer.calls``; a DB that is something else, or a new call of a block
the CPU lacks, refuses the swap). Active steps the new chart does not have are never
dropped silently: without a choice the swap is refused naming them; ``keep`` lets the
other steps go on, ``init`` initializes the sequencer (INIT_SQ in the next call). A
sequencer the running chart did not have gets its initial steps active at the swap
(``carry.new_sequencers``), their S1 event in the next call, as the first call after a start
activates them. The way back — *Undo download* — is the same swap with the charts the other
way round.

:func:`refusal` is why the swap would refuse a chart now — an operand beyond the CPU's
memory, a call of a block the CPU lacks, an instance DB that is something else — read off
the chart's :class:`Needs` (small: a preview made in another process carries them), so that
a download's preview refuses with the very reason the swap would give.

Pure: no threads, no clock, no files; the caller (``web.bus.online``) compiles off the scan
thread and calls :func:`swap` between two scans.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Final, Literal

from s7graph.engine.errors import S7Error
from s7graph.sequencer.calls import CallPlan, CallSite, call_sites, missing_blocks, plan_calls
from s7graph.sequencer.change.carry import CarryReport, ChartShape, carry_over
from s7graph.sequencer.change.diff import ChangeSummary, active_steps, summarize
from s7graph.sequencer.compiled import CompiledChart, Reach, reach_problem
from s7graph.sequencer.fb import GraphFB
from s7graph.sequencer.text.model import Chart
from s7graph.steps.qualifiers import EV_S0

__all__ = [
    "REMOVED",
    "Needs",
    "Removed",
    "SwapRefused",
    "SwapReport",
    "preview",
    "refusal",
    "swap",
]

Removed = Literal["keep", "init"]
REMOVED: Final = ("keep", "init")


class SwapRefused(S7Error):
    """A swap that would drop active steps without the user's choice (or a bad choice)."""


@dataclass(frozen=True, slots=True)
class SwapReport:
    """What a swap did: the carry-over's report, the active steps that went, and whether
    the sequencer was initialized."""

    carry: CarryReport
    removed_active: tuple[int, ...]
    initialized: bool

    def lines(self) -> list[str]:
        out = list(self.carry.lines())
        if self.removed_active:
            shown = ", ".join(f"S{n}" for n in self.removed_active)
            what = (
                "the sequencer is initialized in its next call (the kept steps leave, the "
                "initial steps become the active ones)"
                if self.initialized
                else "the other steps go on"
            )
            out.append(f"active steps removed: {shown}; {what}")
        return out


@dataclass(frozen=True, slots=True)
class Needs:
    """What a compiled chart needs of the CPU it runs in: the areas and DBs its operands
    use (``buffers``) and how far they reach (``reach``), and its block calls."""

    buffers: tuple[tuple[str, int | None], ...]
    reach: tuple[Reach, ...]
    calls: tuple[CallSite, ...]

    @classmethod
    def of(cls, cc: CompiledChart) -> Needs:
        return cls(cc.buffers, cc.reach, tuple(call_sites(cc.chart)))


def refusal(
    cpu: Any,
    running: Chart,
    needs: Needs,
    *,
    find: Callable[[str], Any] | None = None,
    mem: Any = None,
) -> str | None:
    """Why :func:`swap` would refuse a chart that needs ``needs`` in ``cpu`` (running the
    chart ``running``) now, or None: an operand beyond the CPU's memory (bound, it would stop
    the CPU), a new call of a block the CPU lacks, an instance DB that is something else.
    ``find`` and ``mem``: the blocks and the memory as a download's S7-SCL sources leave
    them, for its preview (default: the CPU's now)."""
    return _checked(cpu, running, needs, find=find, mem=mem)[0]


def _checked(
    cpu: Any,
    running: Chart,
    needs: Needs,
    *,
    find: Callable[[str], Any] | None = None,
    mem: Any = None,
) -> tuple[str | None, CallPlan]:
    """:func:`refusal`, and the plan of the chart's calls (the instance DBs to create)."""
    beyond = reach_problem(needs.buffers, needs.reach, mem if mem is not None else cpu.mem)
    if beyond is not None:
        return f"{beyond}: reached, the new chart would stop the CPU", CallPlan()
    lacking = missing_blocks(cpu, running)
    plan = plan_calls(cpu, needs.calls, allowed_missing=lacking, find=find)
    return ("; ".join(plan.problems) if plan.problems else None), plan


def preview(graph: GraphFB, new: CompiledChart) -> ChangeSummary:
    """What swapping ``new`` into ``graph`` would change, for its state now."""
    running = graph.cc
    return summarize(running.chart, new.chart, active_steps(running, graph.state))


def _final_scans(graph: GraphFB, steps: list[int]) -> None:
    """The final scan of each active step the new chart lacks, as if it were left: its
    N, D and L operands back to 0 and its S0 rows run — a step that is gone leaves no
    output on (docs/online-change.md). A row that fails there (a block it calls is gone)
    leaves the rest of that step's scan undone, not the download."""
    rt = graph.loaded.runtime
    if rt is None:
        return
    st, fin = rt.st, rt.prog.fin
    for i in steps:
        try:
            fin[i](st, rt, st.ev[i] | EV_S0)
        except Exception:  # the swap must not fail half done
            continue


def swap(
    graph: GraphFB,
    new: CompiledChart,
    cpu: Any,
    *,
    removed: str | None = None,
    user: str | None = None,
) -> SwapReport:
    """Run ``new`` in ``graph`` from its next call, its state carried over by step number
    (call at a scan boundary). Active steps ``new`` does not have: refused unless
    ``removed`` is ``keep`` (the other steps go on) or ``init`` (INIT_SQ in the next call,
    as ``user``); either way each of those steps gets its final scan first (its N
    operands back to 0)."""
    if removed is not None and removed not in REMOVED:
        raise SwapRefused(f"removed must be keep or init, not {removed!r}")
    old = graph.cc
    state = graph.state
    gone = tuple(n for n in active_steps(old, state) if n not in new.step_index)
    if gone and removed is None:
        shown = ", ".join(f"S{n}" for n in gone)
        raise SwapRefused(
            f"active steps {shown} are not in the new chart: choose keep (the other steps "
            "go on) or init (initialize the sequencer)"
        )
    # nothing the new chart reaches beyond the CPU's memory (bound, it would stop the CPU);
    # no new call of a block the CPU lacks; then the instance DBs of its new SFB calls
    why, plan = _checked(cpu, old.chart, Needs.of(new))
    if why is not None:
        raise SwapRefused(why)
    for number, block in plan.wanted.items():
        cpu.create_instance_db(number, block)
    if gone:
        _final_scans(graph, [old.step_index[n] for n in gone])
    carried, report = carry_over(ChartShape.of(old), state, new)
    graph.replace_chart(new, carried, cpu)
    graph.enter([n for q in report.sequencers for n in q.started])
    initialize = removed == "init" and bool(gone)
    if initialize:
        graph.command("INIT_SQ", user=user)
    return SwapReport(report, gone, initialize)
