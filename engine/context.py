"""What a block body sees during a scan, and how one block calls another (docs/runtime.md, "Programs
of blocks in Python" and "Restarts: warm, hot, cold").

``CallContext.call`` binds the actual parameters (a ``str`` for a non-string parameter is an
operand; a TIMER or COUNTER parameter takes the cell's number, ``T12`` → 12), runs the body
one nesting level deeper (B-stack overflow → ``NestingOverflow``) and tags an escaping
exception with the innermost block (``_Fault``), which the CPU turns into OB121 or STOP
— ``SystemExit`` and ``KeyboardInterrupt`` raised by a block included: a block error, never a
process exit. The runner's ``ScanAborted`` passes through, naming the innermost block.
"""

from __future__ import annotations

from collections.abc import Iterable
from functools import lru_cache
from typing import Any, Protocol

from s7graph.engine.address import Address, Area, parse_address
from s7graph.engine.blocks import DB, FB, FC, OB, Decl, InstanceDB, is_stringy
from s7graph.engine.clock import Clock
from s7graph.engine.datatypes import check_value, shown
from s7graph.engine.diagnostics import DiagnosticBuffer
from s7graph.engine.errors import BlockError, ScanAborted
from s7graph.engine.interrupts import CyclicScheduler
from s7graph.engine.marks import ScanMarks
from s7graph.engine.memory import Memory
from s7graph.engine.rtc import RealTimeClock
from s7graph.engine.rtm import RuntimeMeters
from s7graph.engine.timed import DelayInterrupts, TodInterrupts


class BlockHost(Protocol):
    """What a block may reach of its CPU through ``ctx.cpu`` (``engine.cpu.Cpu`` is one).

    Declared here, below the CPU, so that the CPU imports its call context and never the
    other way round."""

    mem: Memory
    clock: Clock
    rtc: RealTimeClock
    diagnostics: DiagnosticBuffer
    meters: RuntimeMeters
    interrupts: CyclicScheduler
    tod: TodInterrupts
    delays: DelayInterrupts
    blocks: dict[str, OB | FB | FC | DB]
    obs: dict[int, OB]
    instance_dbs: dict[int, InstanceDB]
    max_nesting: int
    scan_events: list[object]
    scan_alarms: list[object]

    def block(self, ref: str | int) -> OB | FB | FC | DB: ...

    def instance_db(self, number: int) -> InstanceDB: ...

    def stop(self, reason: str = "") -> None: ...

    def retrigger(self) -> None: ...

    def update_pii(self) -> None: ...

    def dis_airt(self) -> int: ...

    def en_airt(self) -> int | None: ...


class NestingOverflow(BlockError):
    """Block nesting deeper than the CPU allows (B-stack overflow → STOP)."""


class _Fault(Exception):
    """A user-block exception tagged with the innermost block it escaped from."""

    def __init__(self, block: str, exc: BaseException) -> None:
        super().__init__(block, exc)
        self.block = block
        self.exc = exc


_INT_RANGES: dict[str, tuple[int, int]] = {
    "INT": (-32768, 32767),
    "DINT": (-(2**31), 2**31 - 1),
    "TIME": (-(2**31), 2**31 - 1),
    "BYTE": (0, 0xFF),
    "WORD": (0, 0xFFFF),
    "DWORD": (0, 0xFFFF_FFFF),
}


def _fits(type_name: str, value: object) -> bool:
    """Fast path of ``check_value`` for the common cases (BOOL, in-range integers)."""
    cls = value.__class__
    if cls is bool:
        return type_name == "BOOL"
    if cls is int:
        bounds = _INT_RANGES.get(type_name)
        return bounds is not None and bounds[0] <= value <= bounds[1]  # type: ignore[operator]
    return type_name == "OBJECT"


@lru_cache(maxsize=4096)
def _addr(text: str) -> Address:
    return parse_address(text)


# Block parameter types that name an S5 cell (Siemens' Program Design for S7-300/400, ch. 2 and
# appendix C: the parameter types TIMER and COUNTER).
_CELL_PARAMS = {"TIMER": Area.T, "COUNTER": Area.C}


def _cell_number(where: str, type_name: str, actual: object) -> int:
    """The actual of a TIMER or COUNTER parameter: the cell's number, as S7 passes it — ``T12``
    arrives as 12, never as the timer's value, and the block runs that timer (``s5_timers``
    ``cell_of(ctx.mem.timers, n)``). An ``int`` actual is the number itself."""
    want = "a timer like T12" if type_name == "TIMER" else "a counter like C3"
    if isinstance(actual, str):
        addr = _addr(actual)
        if addr.area is not _CELL_PARAMS[type_name]:
            raise BlockError(f"{where}: a {type_name} parameter takes {want}, not {actual!r}")
        return addr.byte
    if isinstance(actual, bool) or not isinstance(actual, int):
        raise BlockError(f"{where}: a {type_name} parameter takes {want}, not {actual!r}")
    check_value(type_name, actual)
    return actual


class CallContext:
    """What a block body sees during a scan: the CPU, memory, process time, cycle number."""

    __slots__ = ("cpu", "cycle", "depth", "marks", "mem", "now_ns", "ob", "start_info")

    def __init__(self, cpu: BlockHost) -> None:
        self.cpu = cpu
        self.mem = cpu.mem
        self.now_ns = 0
        self.cycle = 0
        self.ob = 0
        self.depth = 0
        self.start_info: dict[str, Any] = {}
        self.marks: ScanMarks | None = None
        """Where the block being run is marked for a watchdog outside the process."""

    def emit(self, event: object) -> None:
        """Add ``event`` to this scan's ``ScanRecord.events``."""
        self.cpu.scan_events.append(event)

    def emit_all(self, events: Iterable[object]) -> None:
        """Add ``events`` to this scan's ``ScanRecord.events``, in order (``emit`` each)."""
        self.cpu.scan_events.extend(events)

    def alarm(self, alarm: object) -> None:
        """Add ``alarm`` to this scan's ``ScanRecord.alarms``."""
        self.cpu.scan_alarms.append(alarm)

    def call(
        self,
        block: FB | FC | InstanceDB | str | int,
        instance: InstanceDB | int | None = None,
        **params: object,
    ) -> dict[str, object]:
        """Call an FB/SFB (with its instance DB) or an FC/SFC; return its outputs by name.

        A ``str`` actual for a non-string parameter is an operand (``"MW10"``); OUT and IN_OUT
        operands receive the values after the call. ``None`` for an OUT gives it without an operand:
        its value is only returned (a GRAPH row's ``CDT => t`` writes it to an FB variable the
        engine does not address).
        """
        if isinstance(block, FB) and isinstance(instance, InstanceDB) and instance.fb is block:
            return self._call_fb(block, instance, params)  # the common case, checks below
        blk: OB | FB | FC | DB
        if isinstance(block, FB | FC):
            blk = block
        elif isinstance(block, InstanceDB):
            instance, blk = block, block.fb
        else:
            blk = self.cpu.block(block)
        if isinstance(blk, FB):
            if instance is None:
                raise BlockError(f"{blk.label} {blk.name!r} called without an instance DB")
            idb = instance if isinstance(instance, InstanceDB) else self.cpu.instance_db(instance)
            if idb.fb is not blk and idb.fb != blk:
                raise BlockError(f"{idb.name} is an instance of {idb.fb.label}, not {blk.label}")
            return self._call_fb(blk, idb, params)
        if isinstance(blk, FC):
            return self._call_fc(blk, params)
        raise BlockError(f"{blk.label} cannot be called")

    def run_fb(self, blk: FB, idb: InstanceDB) -> None:
        """Call FB ``blk`` with its instance DB ``idb`` and no parameters, for a caller that
        reads no outputs (``call`` without building the outputs dict; same checks)."""
        if idb.fb is not blk and idb.fb != blk:
            raise BlockError(f"{idb.name} is an instance of {idb.fb.label}, not {blk.label}")
        self._invoke(blk, idb)

    def tag_fault(self, block: str, exc: BaseException) -> BaseException:
        """What ``call`` lets escape when ``exc`` escapes the body of block ``block`` (the
        rule of ``_invoke``): an exception tagged with the innermost block, one tagged
        already or one ``_invoke`` lets pass unchanged — for a caller that runs a block's
        body inline one level deeper itself (the GRAPH FBs' quiet calls from OB1,
        ``sequencer.fb.startup_obs``) and raises what this returns."""
        if isinstance(exc, _Fault):
            return exc
        if isinstance(exc, ScanAborted):
            exc.block = exc.block or block
            return exc
        if isinstance(exc, Exception | SystemExit | KeyboardInterrupt):
            return _Fault(block, exc)
        return exc

    def _invoke(self, blk: FB | FC, arg: Any) -> Any:
        """``blk.body(self, arg)`` one nesting level deeper; an exception escaping it is
        tagged with the innermost block it escaped from (``_Fault``)."""
        if self.depth >= self.cpu.max_nesting:
            raise NestingOverflow(
                f"block nesting deeper than {self.cpu.max_nesting} at {blk.label}"
            )
        self.depth += 1
        marks = self.marks
        before = marks.enter(blk) if marks is not None else 0
        try:
            return blk.body(self, arg)
        except BaseException as exc:
            fault = self.tag_fault(blk.label, exc)
            if fault is exc:
                raise
            raise fault from exc
        finally:
            self.depth -= 1
            if marks is not None:
                marks.leave(before)

    def _write_back(
        self, refs: list[tuple[str, str, str]], values: dict[str, object]
    ) -> dict[str, object]:
        """Write OUT/IN_OUT ``values`` to their operands; an OUT the block left unassigned
        (absent from ``values``) leaves its operand alone. Returns what was written."""
        out: dict[str, object] = {}
        for name, operand, type_name in refs:
            if name in values:
                self.mem.write_as(_addr(operand), type_name, values[name])
                out[name] = values[name]
        return out

    def _call_fb(self, blk: FB, idb: InstanceDB, params: dict[str, object]) -> dict[str, object]:
        values = idb.values
        table = blk.params
        writes: list[tuple[str, str, str]] | None = None
        for name, actual in params.items() if params else ():
            spec = table.get(name)
            if spec is None or spec[0] is Decl.STAT:
                raise BlockError(f"{blk.label} has no parameter {name!r}")
            decl, type_name = spec
            if decl is Decl.OUT:
                if actual is None:  # only returned (a GRAPH row writes it): see _call_fc
                    continue
                if not isinstance(actual, str):
                    raise BlockError(f"{blk.label}.{name}: an OUT needs an operand, not {actual!r}")
                writes = writes or []
                writes.append((name, actual, type_name))
                continue
            if type_name in _CELL_PARAMS:
                actual = _cell_number(f"{blk.label}.{name}", type_name, actual)
            elif isinstance(actual, str) and not is_stringy(type_name):
                if decl is Decl.IN_OUT:
                    writes = writes or []
                    writes.append((name, actual, type_name))
                actual = self.mem.read_as(_addr(actual), type_name)
            elif not _fits(type_name, actual):
                actual = check_value(type_name, actual)
            values[name] = actual
        self._invoke(blk, idb)
        if writes:
            self._write_back(writes, values)
        return {name: values[name] for name in blk.out_names}

    def _call_fc(self, blk: FC, params: dict[str, object]) -> dict[str, object]:
        table = blk.params
        missing = [n for n in table if n not in params]
        if missing:
            raise BlockError(f"{blk.label} {blk.name!r}: parameter(s) {', '.join(missing)} missing")
        args: dict[str, object] = {}
        refs: list[tuple[str, str, str]] = []
        returned: list[str] = []
        for name, actual in params.items():
            spec = table.get(name)
            if spec is None:
                raise BlockError(f"{blk.label} has no parameter {name!r}")
            decl, type_name = spec
            if actual is None and decl is Decl.OUT:
                returned.append(name)  # given, its value only returned: the caller writes it
                continue
            if type_name in _CELL_PARAMS and decl is Decl.IN:
                args[name] = _cell_number(f"{blk.label}.{name}", type_name, actual)
            elif isinstance(actual, str) and not is_stringy(type_name):
                if decl is not Decl.OUT:  # an OUT is written, never read in
                    args[name] = self.mem.read_as(_addr(actual), type_name)
                if decl is not Decl.IN:
                    refs.append((name, actual, type_name))
            elif decl is not Decl.IN:
                raise BlockError(
                    f"{blk.label}.{name}: {decl} needs an operand, not {shown(actual)}"
                )
            else:
                args[name] = check_value(type_name, actual)
        ret = self._invoke(blk, args)
        out = self._write_back(refs, args)
        out.update((name, args[name]) for name in returned if name in args)
        if blk.ret_type is not None:
            out["RET_VAL"] = ret
        return out
