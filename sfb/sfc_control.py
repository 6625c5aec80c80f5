"""SFC46 STP, SFC47 WAIT, SFC43 RE_TRIGR, SFC44 REPL_VAL (docs/runtime.md, "The block runtime";
STEP7 comprehensive guide vol. 2, ch. 12).

* STP puts the CPU into STOP from any OB, OB100 included: ``cpu.stop``.
* WAIT(WT) busy-waits WT µs (INT, max 32767) on a real CPU and has no RET_VAL. Here time is
  the injected clock, so nothing advances: the wait is recorded as a ``Waited`` event in
  the scan's record; a negative WT waits 0 µs (``[K]``).
* RE_TRIGR restarts the cycle-time monitoring of the current cycle: ``cpu.retrigger``.
* REPL_VAL(VAL) in OB122 sets the value the failed peripheral read returns to the block
  that made it: its low bytes (a PIW read the low word); without REPL_VAL the read returns
  0 (``engine/cpu_errors.py``). It may be called in OB121 too, where no read waits for it
  (a block's exception has ended the block); anywhere else RET_VAL is ``W#16#8080``
  (``[K]``: not called from a synchronous error OB).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol, cast

from s7graph.engine import blocks
from s7graph.sfb.catalogue import OK, engine_sections, lookup, specific_error

if TYPE_CHECKING:
    from s7graph.engine.context import CallContext

WT_MAX_US = 32767
RET_NOT_IN_ERROR_OB = specific_error(0x8080)


class CpuControl(Protocol):
    """What the control SFCs need from the CPU (``engine.cpu.Cpu`` satisfies it)."""

    def stop(self, reason: str = "") -> None: ...

    def retrigger(self) -> None: ...


@dataclass(frozen=True, slots=True)
class Waited:
    """SFC47 WAIT was called for ``us`` microseconds (recorded; the clock is not advanced)."""

    us: int
    block: str = "SFC47"


def stp(cpu: CpuControl) -> None:
    """SFC46 STP: go to STOP now."""
    cpu.stop("SFC46 STP")


def wait(wt_us: int) -> Waited:
    """SFC47 WAIT(WT): the record of a wait of WT µs (clamped to 0..32767)."""
    return Waited(max(0, min(int(wt_us), WT_MAX_US)))


def re_trigr(cpu: CpuControl) -> None:
    """SFC43 RE_TRIGR: restart cycle-time monitoring for this cycle."""
    cpu.retrigger()


def repl_val(ob: int, start_info: dict[str, object], val: int) -> int:
    """SFC44 REPL_VAL(VAL) in OB ``ob`` with its start information: the replacement value
    of the failed read (``start_info["REPL_VAL"]``), ``W#16#8080`` outside OB121/OB122."""
    if ob not in (121, 122):
        return RET_NOT_IN_ERROR_OB
    start_info["REPL_VAL"] = int(val) & 0xFFFF_FFFF
    return OK


# --- Engine adapters --------------------------------------------------------------------


def _declare(name: str, body: blocks.FCBody) -> blocks.FC:
    entry = lookup(name)
    sections, ret = engine_sections(entry)
    return blocks.sfc(entry.number, entry.name, RET=ret, **sections)(body)


def _stp(ctx: CallContext, params: dict[str, object]) -> None:
    stp(ctx.cpu)


def _wait(ctx: CallContext, params: dict[str, object]) -> None:
    ctx.emit(wait(cast(int, params["WT"])))


def _re_trigr(ctx: CallContext, params: dict[str, object]) -> None:
    re_trigr(ctx.cpu)


def _repl_val(ctx: CallContext, params: dict[str, object]) -> int:
    return repl_val(ctx.ob, ctx.start_info, cast(int, params["VAL"]))


SFC46 = _declare("STP", _stp)
SFC47 = _declare("WAIT", _wait)
SFC43 = _declare("RE_TRIGR", _re_trigr)
SFC44 = _declare("REPL_VAL", _repl_val)
BLOCKS = (SFC43, SFC44, SFC46, SFC47)
