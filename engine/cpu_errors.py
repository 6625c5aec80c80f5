"""Synchronous errors — a programming error (OB121), an I/O access error (OB122) — and the
priority class an OB runs in (docs/runtime.md, "When a scan hangs or fails"; Siemens' Program
Design for S7-300/400, ch. 3-4 and 10).

* An exception escaping a block is a programming error: the diagnostic buffer records it,
  then OB121 runs (the faulting block has ended) or, without OB121, the CPU stops.
* A direct access to a peripheral address no module answers (``IOAccessError``: PI/PQ
  beyond the modules) is an I/O access error, and synchronous: with OB122 loaded the CPU
  runs OB122 at once, inside the access, in the faulting OB's priority class. SFC44 REPL_VAL
  there sets the value the failed read returns (its low bytes; 0 without REPL_VAL), a failed
  write is not made, and the block goes on. Without OB122, or in OB122 itself, the error
  escapes the block and the CPU stops (16#4563).
* OB121 and OB122 run in the priority class of the OB that caused them; OB80–OB87 in 28
  during startup (26 in RUN); every other OB in its own (``Cpu.priority_of``). The
  diagnostic buffer stamps each entry with the running OB and its class.

``SyncErrors`` is a part of ``engine.cpu.Cpu``, which owns the attributes it declares.
"""

from __future__ import annotations

from typing import Any

from s7graph.engine.context import CallContext, NestingOverflow
from s7graph.engine.cpu_part import CpuPart
from s7graph.engine.diagnostics import EventId
from s7graph.engine.errors import AddressError, BlockError, S7Error, TypeMismatch
from s7graph.engine.interrupts import class_at_start
from s7graph.engine.memory import AreaLengthError, AreaWriteError, IOAccessError
from s7graph.engine.modes import CpuMode

__all__ = ["SyncErrors", "classify"]


class SyncErrors(CpuPart):
    """OB121, OB122 and the priority class of a running OB."""

    _ctx: CallContext

    def priority_class(self, ob: int) -> int:
        """The class OB ``ob`` runs in when it starts now (``interrupts.class_at_start``):
        the running OB's is the faulting one's."""
        return class_at_start(
            ob,
            faulting=self.diagnostics.priority,
            startup=self.mode is CpuMode.STARTUP,
            priority_of=self.priority_of,
        )

    def _program_error(self, ob: int, block: str, exc: BaseException) -> None:
        event = classify(exc)
        message = _program_words(exc)
        self.diagnostics.record(self._raw, event, block, message, getattr(exc, "address", ""))
        if isinstance(exc, NestingOverflow | RecursionError):
            self._go_stop(EventId.STACK_OVERFLOW, block, "block stack overflow")
        elif isinstance(exc, IOAccessError):  # OB122 would have run: missing, or this is it
            why = "in OB122" if ob == 122 else "OB122 not loaded"
            self._go_stop(EventId.STOP_OB122_MISSING, block, f"I/O access error, {why}")
        elif ob == 121 or 121 not in self.obs:
            why = "in OB121" if ob == 121 else "OB121 not loaded"
            self._go_stop(EventId.STOP_OB121_MISSING, block, f"programming error, {why}")
        else:
            info = {"SW_FLT": event & 0xFF, "BLOCK": block, "MESSAGE": message, "FAULT_OB": ob}
            info["EXCEPTION"] = exc
            self._run_ob(121, info)

    def _io_access_error(self, err: IOAccessError) -> int:
        """``Memory.io_error``: run OB122 for ``err`` inside the access and return the
        replacement value REPL_VAL set (0 without it); raise ``err`` outside every OB, in
        OB122 itself, or without OB122."""
        diag = self.diagnostics
        fault_ob = diag.ob
        if fault_ob in (0, 122) or 122 not in self.obs:
            raise err
        event = EventId.IO_ACCESS_WRITE if err.write else EventId.IO_ACCESS_READ
        diag.record(self._raw, event, f"OB{fault_ob}", str(err), err.address)
        info: dict[str, Any] = {
            "SW_FLT": err.sw_flt,
            "ADDRESS": err.address,
            "MESSAGE": str(err),
            "FAULT_OB": fault_ob,
            "REPL_VAL": 0,
        }
        ctx = self._ctx
        saved = ctx.ob, ctx.depth, ctx.start_info
        try:
            self._run_ob(122, info, nested=True)
        finally:
            ctx.ob, ctx.depth, ctx.start_info = saved
        value = info["REPL_VAL"]
        return value if isinstance(value, int) else 0


def classify(exc: BaseException) -> int:
    """Event id of a synchronous error: 16#25xx a programming error (Siemens' Program Design
    for S7-300/400, ch. 3-4, OB121 SW_FLT), 16#2942/16#2943 an I/O access error (OB122)."""
    if isinstance(exc, IOAccessError):
        return 0x2900 | exc.sw_flt
    if isinstance(exc, AreaLengthError | AreaWriteError):
        return 0x2500 | exc.sw_flt
    if isinstance(exc, AddressError):
        return EventId.AREA_ERROR
    if isinstance(exc, TypeMismatch):
        return EventId.TYPE_ERROR
    if isinstance(exc, BlockError):
        text = str(exc)
        for kind, event in (
            ("FC", EventId.FC_NOT_LOADED),
            ("FB", EventId.FB_NOT_LOADED),
            ("DB", EventId.DB_NOT_LOADED),
        ):
            if f"block {kind}" in text or f"instance {kind}" in text:
                return event
        return EventId.PYTHON_EXCEPTION
    return EventId.PYTHON_EXCEPTION


def _program_words(exc: BaseException) -> str:
    """What a scan's error says: the runtime's own errors what went wrong; Python's own
    limits in words (nesting, memory); any other Python error of a block's body keeps its
    class, which its author knows (``ZeroDivisionError: division by zero``)."""
    if isinstance(exc, S7Error):
        return str(exc)
    if isinstance(exc, RecursionError):
        return f"calls nested too deeply ({exc})"
    if isinstance(exc, MemoryError):
        return "the blocks need more memory than there is"
    return f"{type(exc).__name__}: {exc}"
