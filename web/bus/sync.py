"""Synchronization over the bus: ``fb/<fb>/sync`` judges every step of the FB against the
process values at the next scan boundary (docs/bus.md, "Synchronization: sync";
``sequencer.sync``).

The zenoh thread only checks the key and queues the query; the scan thread judges at the
next boundary — the values of one scan, never torn by the next — once for every query
waiting and at most once every ``EVERY_NS``, and hands the :class:`SyncReport` to the
publisher's outbox. Reading it changes nothing, so any user may ask; resuming at the steps
it finds is the ``set_steps`` command in MAN (or ``step_on`` one at a time), with its role
and audit.
"""

from __future__ import annotations

import queue
import time
from collections.abc import Callable
from typing import Final, cast

import zenoh

from s7graph.engine.cpu import Cpu
from s7graph.engine.errors import S7Error, internal_error
from s7graph.sequencer.fb import GraphFB
from s7graph.web.bus.protocol import MODES, CpuState, SyncReport, SyncStepInfo, encode
from s7graph.web.bus.publisher import BusPublisher, QueryReply

__all__ = ["EVERY_NS", "QUEUE", "Synchronizing", "sync_report"]

QUEUE: Final = 16
"""Queries waiting at most; beyond, a query is refused at once as busy."""
EVERY_NS: Final = 200_000_000
"""At most one judgement in this time: a chart of 1,000 steps takes a few ms to judge, so
that a flood of queries costs the scan thread at most that every 0.2 s."""


def sync_report(graph: GraphFB, fb: str, cpu: Cpu) -> SyncReport:
    """The FB's steps judged on the values the scan just ended left, as a message; a
    report with its ``error`` when the FB cannot be judged (never an exception: this runs
    in the scan thread)."""
    state = cast(CpuState, str(cpu.mode))
    cycle, t_ms = max(cpu.cycle, 0), max(cpu.clock.now_ns() // 1_000_000, 0)
    try:
        steps = graph.synchronization()
        mode = graph.state.mode
    except S7Error as exc:
        return SyncReport(fb=fb, cycle=cycle, t_ms=t_ms, state=state, error=str(exc)[:4096])
    except Exception as exc:  # the scan thread's edge: never raise
        why = f"{fb}: cannot judge the steps: {internal_error('in the CPU', exc)}"
        return SyncReport(fb=fb, cycle=cycle, t_ms=t_ms, state=state, error=why[:4096])
    return SyncReport(
        fb=fb,
        cycle=cycle,
        t_ms=t_ms,
        state=state,
        mode=mode if mode in MODES else "AUTO",
        steps=[
            SyncStepInfo(
                number=s.number,
                name=s.name[:80],
                sequence=s.sequence,
                active=s.active,
                interlock=s.interlock,
                entered=s.entered,
                done=list(s.done),
                fits=s.fits,
                likely=s.likely,
            )
            for s in steps
        ],
    )


class Synchronizing:
    """The ``fb/<fb>/sync`` queryable of ``graph`` on ``publisher``'s bus; call
    :meth:`at_boundary` in the scan thread after each scan."""

    def __init__(
        self,
        graph: GraphFB,
        fb: str,
        cpu: Cpu,
        publisher: BusPublisher,
        *,
        clock: Callable[[], int] = time.perf_counter_ns,
    ) -> None:
        self.graph, self.fb, self.cpu = graph, fb, cpu
        self.clock = clock
        """The time in ns between judgements is measured on (``time.perf_counter_ns``)."""
        self._publisher = publisher
        leaf = f"fb/{fb}/sync"
        self._key = publisher.key(leaf)
        self._queue: queue.Queue[QueryReply] = queue.Queue(QUEUE)
        self._last_ns = -EVERY_NS  # when the last judgement was made
        self.judged = 0
        """Judgements made so far."""
        publisher.declare_queryable(leaf, self._on_query)

    def at_boundary(self) -> int:
        """Answer the queries waiting with one judgement of the scan just ended, unless
        the last was less than ``EVERY_NS`` ago (then at a later boundary); how many were
        answered."""
        now = self.clock()
        if self._queue.empty() or now - self._last_ns < EVERY_NS:
            return 0
        self._last_ns = now
        self.judged += 1
        replies = []
        while True:
            try:
                replies.append(self._queue.get_nowait())
            except queue.Empty:
                break
        if replies:
            report = sync_report(self.graph, self.fb, self.cpu)
            for reply in replies:
                self._publisher.post(reply, report)
        return len(replies)

    @property
    def waiting(self) -> int:
        """Queries waiting for a judgement."""
        return self._queue.qsize()

    def _on_query(self, query: zenoh.Query) -> None:
        # a zenoh thread: only the exact key, queue; never raise
        if str(query.key_expr) != self._key:
            return
        reply = QueryReply(query, self._key)
        try:
            self._queue.put_nowait(reply)
        except queue.Full:
            _refuse(reply, f"busy: {QUEUE} synchronization queries are waiting; ask again")


def _refuse(reply: QueryReply, reason: str) -> None:
    try:
        reply.put(encode(SyncReport(error=reason)))
    except Exception:
        return
