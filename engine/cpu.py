"""The soft CPU: modes, startup, the scan cycle and error handling (docs/runtime.md, "Restarts:
warm, hot, cold"; docs/architecture.md, "The core is a function").

``scan()`` reads the clock once and runs one cycle in S7 order: commands queued since the
last scan are applied, scan hooks run (``add_os_scan_hook``; the S5 timer update of ``sfb``),
cycle monitoring judges the previous cycle, PII is read from the module side, OB1 runs,
due interrupt OBs run — time-of-day OB10–17, delay OB20–23, cyclic OB30–38 — highest
priority first and, within one priority, in the order of their start events (behaviour
17), PIQ is written to the modules. Force jobs (``force``/``unforce``, ``engine/force.py``)
are written into PII right after it is read, into the flags at the start of the cycle and
into PIQ right before it is written; a change of the table goes to the diagnostic buffer at
the start of the next scan, the one it acts in. Outside RUN the module outputs are 0. A Python
exception in a user block is a programming error: OB121 if loaded, else STOP — the process
never dies; a direct access to a missing peripheral address runs OB122 inside the access
(``engine/cpu_errors.py``). All timing uses *process time*: the clock minus the time spent
in HOLD, so HOLD freezes timers, interrupts and monitoring while the diagnostic time stamps
and the real-time clock keep the real clock. What a block body sees (``CallContext``, block calls)
lives in ``engine/context.py``.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from s7graph.engine.address import Area
from s7graph.engine.blocks import DB, FB, FC, OB, InstanceDB
from s7graph.engine.clock import Clock
from s7graph.engine.context import CallContext, NestingOverflow, _Fault
from s7graph.engine.cpu_errors import SyncErrors
from s7graph.engine.cpu_forcing import Forcing, jobs_text, listed
from s7graph.engine.cpu_interrupts import MISSING_STOP, InterruptDispatch
from s7graph.engine.cpu_program import ProgramBlocks
from s7graph.engine.cpu_stops import ErrorStops
from s7graph.engine.diagnostics import DiagnosticBuffer, EventId
from s7graph.engine.errors import BlockError, S7Error, ScanAborted, internal_error
from s7graph.engine.force import ForceTable, apply_plan
from s7graph.engine.interrupts import CYCLIC_DEFAULT_MS, CyclicScheduler, priority
from s7graph.engine.marks import ScanMarks
from s7graph.engine.memory import Memory
from s7graph.engine.modes import CpuMode, KeySwitch, ModeRequest, SetKeySwitch, resolve_requests
from s7graph.engine.record import DiagEntry, ScanRecord
from s7graph.engine.restart import (
    NO_HOT_AFTER_STOP,
    RESTART,
    RestartType,
    error_blocker,
    parse_restart,
)
from s7graph.engine.rtc import RealTimeClock
from s7graph.engine.rtm import RuntimeMeters
from s7graph.engine.timed import DelayInterrupts, TodInterrupts
from s7graph.engine.watchdog import CycleStatistics, Verdict, Watchdog

__all__ = [
    "CLOCK_MEMORY_HALF_MS",
    "OS_SCAN_HOOKS",
    "CallContext",
    "CommandFn",
    "Cpu",
    "NestingOverflow",
    "Pending",
    "ScanHook",
    "StartupHook",
    "add_os_scan_hook",
]

CLOCK_MEMORY_HALF_MS = (50, 100, 200, 250, 400, 500, 800, 1000)
"""Half periods of clock-memory bits 0..7 (periods 0.1 … 2.0 s)."""


ScanHook = Callable[["Cpu", int], None]
"""``hook(cpu, process_ns)``: an operating-system task run at the start of every cycle."""

StartupHook = Callable[["Cpu", RestartType], None]
"""``hook(cpu, restart)``: run when a startup begins, before anything is cleared."""

OS_SCAN_HOOKS: list[ScanHook] = []
"""Scan hooks every CPU runs (registered by ``sfb`` at import, see ``add_os_scan_hook``)."""


def add_os_scan_hook(hook: ScanHook) -> None:
    """Register ``hook`` for every CPU (idempotent): how ``sfb`` makes the S5 timers tick
    once per scan without the engine importing it (El-Shahat's S7-300/400 course, timers and
    counters)."""
    if hook not in OS_SCAN_HOOKS:
        OS_SCAN_HOOKS.append(hook)


@dataclass(slots=True)
class Pending:
    """A submitted command: ``done`` once applied at a scan boundary, with result or error."""

    command: object
    done: bool = False
    result: object = None
    error: str = ""


class Cpu(ProgramBlocks, Forcing, InterruptDispatch, SyncErrors, ErrorStops):
    """One soft CPU (docs/architecture.md, "Seams"). Power-on leaves it in STOP."""

    def __init__(
        self,
        clock: Clock,
        *,
        memory: Memory | None = None,
        key: KeySwitch = KeySwitch.RUN_P,
        max_cycle_ms: float = 150.0,
        min_cycle_ms: float = 0.0,
        diag_capacity: int = 100,
        clock_memory: int | None = None,
        max_nesting: int = 16,
        hot_restart_enabled: bool = True,
        keep_outputs_on_hot_restart: bool = False,
        name: str = "cpu",
    ) -> None:
        self.clock = clock
        self.mem = memory if memory is not None else Memory()
        self.mem.io_error = self._io_access_error  # OB122 (engine/cpu_errors.py)
        self.mem.no_db = self.no_db_bytes  # an instance DB by name only (cpu_program.py)
        self.name = name
        self.mode = CpuMode.STOP
        self.key = key
        self.diagnostics = DiagnosticBuffer(diag_capacity, wall=getattr(clock, "wall_ns", None))
        self.watchdog = Watchdog(max_cycle_ms, min_cycle_ms)
        self.stats = CycleStatistics()
        self.interrupts = CyclicScheduler()
        self.delays = DelayInterrupts()
        self.tod = TodInterrupts()
        self.rtc = RealTimeClock()
        """The CPU's date and time on the injected clock (SFC0/SFC1, TOD interrupts)."""
        self.meters = RuntimeMeters()
        self.ob_priority: dict[int, int] = {}
        """Parametrised OB priorities; others have the S7 defaults
        (``engine.interrupts.priority``)."""
        self._startup_hooks: list[StartupHook] = []
        self.stop_entry: DiagEntry | None = None
        """The diagnostic entry of the last transition to STOP (its cause is the entry
        before it when a block error or time error caused it)."""
        self.abort_reason = ""
        """Set by the real-time runner before it raises ``ScanAborted`` into the scan."""
        self._airt_disabled = 0
        self._tod_seen: tuple[int, object] | None = None
        self.clock_memory = clock_memory
        self.max_nesting = max_nesting
        self.hot_restart_enabled = hot_restart_enabled
        self.keep_outputs_on_hot_restart = keep_outputs_on_hot_restart
        self.blocks: dict[str, OB | FB | FC | DB] = {}
        self.obs: dict[int, OB] = {}
        self.instance_dbs: dict[int, InstanceDB] = {}
        self.cycle = 0
        self.last_restart: RestartType | None = None
        self.hot_blockers: set[str] = {"program download"}
        """Why only a warm restart is possible now; cleared by a warm restart."""
        self._commands: deque[Pending] = deque()
        self.forces = ForceTable()
        """The force jobs (``force``/``unforce``): kept until deleted, a memory reset included."""
        self._force_notes: list[tuple[int, str, str]] = []  # diagnostic entries, next scan
        self._ctx = CallContext(self)
        self.scan_events: list[object] = []
        self.scan_alarms: list[object] = []
        self._ran: list[int] = []
        self._held_ns = 0
        self._hold_since: int | None = None
        self._last_ob1: int | None = None
        self._now = 0
        self._raw = 0
        self._pq_seen = bytes(self.mem.periph_out)

    # ---- modes -----------------------------------------------------------------------------

    def submit(self, command: object) -> Pending:
        """Queue a command (ModeRequest, SetKeySwitch, callable ``f(cpu)`` or ``.apply(cpu)``);
        it is applied at the next scan boundary, never in the caller's thread."""
        pending = Pending(command)
        self._commands.append(pending)
        return pending

    def set_key(self, position: KeySwitch) -> None:
        """Turn the key switch; to STOP stops the CPU (transition 8)."""
        self.key = KeySwitch(position)
        if self.key is KeySwitch.STOP and self.mode is not CpuMode.STOP:
            self._go_stop(EventId.STOP_BY_SWITCH, "", "key switch turned to STOP")

    def start(self, restart: str | RestartType = "warm") -> ScanRecord:
        """STOP → STARTUP (OB100/101/102) → RUN; refused with the key in STOP."""
        self._begin(self.clock.now_ns())
        mark = self.diagnostics.total
        self._startup(parse_restart(restart))
        return self._record(mark, 0)

    def stop(self, reason: str = "") -> None:
        """Go to STOP now (PG STOP or SFC46 STP); module outputs go to 0."""
        if self.mode is not CpuMode.STOP:
            self._go_stop(EventId.STOP_BY_REQUEST, "", reason or "STOP requested")

    def hold(self) -> None:
        """RUN/STARTUP → HOLD (breakpoint): timers and monitoring freeze, outputs disabled."""
        if self.mode in (CpuMode.RUN, CpuMode.STARTUP):
            raw = self.clock.now_ns()
            self._hold_since = raw
            self.mode = CpuMode.HOLD
            self.mem.clear_outputs(image=False)
            self.diagnostics.record(raw, EventId.HOLD_ENTERED, "", "RUN → HOLD")

    def resume(self) -> None:
        """HOLD → RUN: the frozen process time continues where it stopped."""
        if self.mode is CpuMode.HOLD and self._hold_since is not None:
            raw = self.clock.now_ns()
            self._held_ns += raw - self._hold_since
            self._hold_since = None
            self.mode = CpuMode.RUN
            self.diagnostics.record(raw, EventId.HOLD_LEFT, "", "HOLD → RUN")

    def memory_reset(self, *, keep_program: bool = False) -> None:
        """MRES (STOP only): program and operand areas cleared; diagnostics and key kept.

        ``keep_program``: as an S7-300 with its program on a memory card, the program is
        copied back from load memory: the blocks stay loaded, every DB and instance DB goes
        back to its initial values, DBs created at run time (SFC22) are deleted
        (docs/runtime.md, "Memory reset (MRES)")."""
        if self.mode is not CpuMode.STOP:
            raise BlockError("memory reset is possible only in STOP")
        if keep_program:
            for idb in self.instance_dbs.values():
                idb.reset()
        else:
            self.blocks.clear()
            self.obs.clear()
            self.instance_dbs.clear()
            self.mem.dbs.clear()
        self.mem.reset_to_initial()
        self.hot_blockers.add("memory reset")
        self.cycle = 0
        now = self.clock.now_ns()
        what = "memory reset, the program copied from load memory" if keep_program else ""
        self.diagnostics.record(now, EventId.MEMORY_RESET, "", what or "memory reset")
        gone = self.forces.clear()
        if gone:
            self._force_notes.clear()
            text = f"memory reset deletes {jobs_text(len(gone))}: {listed(gone)}"
            self.diagnostics.record(now, EventId.FORCE_ENDED, "", text)

    def process_ns(self) -> int:
        """The clock minus time spent in HOLD: what timers, interrupts and monitoring see."""
        raw = self.clock.now_ns()
        since = self._hold_since
        return (since if since is not None else raw) - self._held_ns

    def retrigger(self) -> None:
        """SFC43 RE_TRIGR: restart cycle-time monitoring for this cycle."""
        self.watchdog.retrigger()

    def add_startup_hook(self, hook: StartupHook) -> None:
        """Run ``hook(cpu, restart)`` at the beginning of every startup, once the restart
        type is settled and before memory or instance DBs are cleared (idempotent): how a
        GRAPH FB writes its position to the diagnostic buffer before a warm or cold
        restart initializes it."""
        if hook not in self._startup_hooks:
            self._startup_hooks.append(hook)

    def mark_blocks(self, marks: ScanMarks | None) -> None:
        """Mark each OB, FB and FC as it runs in ``marks`` (``engine.marks``; None: stop)."""
        self._ctx.marks = marks

    def _run_hooks(self, now: int) -> None:
        for hook in OS_SCAN_HOOKS:
            hook(self, now)

    def priority_of(self, ob: int) -> int:
        """The OB's priority class: parametrised in ``ob_priority`` or the default (18)."""
        got = self.ob_priority.get(ob)
        return got if got is not None else priority(ob)

    def dis_airt(self) -> int:
        """SFC41 DIS_AIRT: delay higher-priority interrupts until EN_AIRT or the end of the
        current OB — delayed, never lost; returns the number of delays."""
        self._airt_disabled += 1
        return self._airt_disabled

    def en_airt(self) -> int | None:
        """SFC42 EN_AIRT: undo one DIS_AIRT; the remaining count, None if none was active."""
        if self._airt_disabled == 0:
            return None
        self._airt_disabled -= 1
        return self._airt_disabled

    @property
    def airt_disabled(self) -> int:
        """How many DIS_AIRT calls of the running OB are still in force."""
        return self._airt_disabled

    def update_pii(self) -> None:
        """Read the module inputs into the process-image input table (also SFC26 UPDAT_PI),
        then write the forced inputs over them."""
        mem = self.mem
        n = len(mem.inputs)
        mem.inputs[:] = mem.periph_in[:n]
        plan = self.forces.plan(Area.I)
        if plan:
            apply_plan(mem.inputs, plan)

    def update_piq(self) -> None:
        """Write the forced outputs into the process-image output table, then the table to
        the modules (also SFC27 UPDAT_PO)."""
        mem = self.mem
        n = len(mem.outputs)
        if self.mode is CpuMode.RUN:
            plan = self.forces.plan(Area.Q)
            if plan:
                apply_plan(mem.outputs, plan)
            mem.periph_out[:n] = mem.outputs

    def raise_async_error(self, ob: int, info: dict[str, Any] | None = None) -> None:
        """An asynchronous error event for OB80..OB87 (module fault, rack failure ...).

        Runs the OB if loaded; without it the CPU stops, except OB81.
        """
        raw = self.clock.now_ns()
        self.diagnostics.record(
            raw, EventId.ASYNC_ERROR | (ob - 80), f"OB{ob}", "asynchronous error"
        )
        if self.mode is not CpuMode.RUN:
            return
        if ob in self.obs:
            self._ctx.now_ns = self.process_ns()
            self._run_ob(ob, dict(info or {}))
        elif ob != 81:
            stop = MISSING_STOP.get(ob, EventId.STOP_OB85_MISSING)
            self._go_stop(stop, f"OB{ob}", f"OB{ob} is not loaded")

    # ---- the scan --------------------------------------------------------------------------

    def scan(self) -> ScanRecord:
        """One cycle; reads the clock once and returns what happened."""
        raw = self.clock.now_ns()
        self._begin(raw)
        mark = self.diagnostics.total
        self._drain()
        if self._force_notes:
            for event, address, text in self._force_notes:
                self.diagnostics.record(raw, event, "", text, address)
            self._force_notes.clear()
        cycle_ns = 0
        if self.mode is CpuMode.RUN:
            cycle_ns = self._cycle(raw - self._held_ns)
        return self._record(mark, cycle_ns)

    def _begin(self, raw: int) -> None:
        self._raw = raw
        self.scan_events = []
        self.scan_alarms = []
        self._ran = []

    def _record(self, mark: int, cycle_ns: int) -> ScanRecord:
        pq = self.mem.periph_out
        outputs: dict[str, int] = {}
        if pq != self._pq_seen:
            seen = self._pq_seen
            outputs = {f"PQB{i}": b for i, b in enumerate(pq) if i >= len(seen) or seen[i] != b}
            self._pq_seen = bytes(pq)
        return ScanRecord(
            self.cycle,
            self._raw,
            cycle_ns,
            self.mode,
            tuple(self.scan_events),
            outputs,
            self.diagnostics.since(mark),
            tuple(self.scan_alarms),
            tuple(self._ran),
        )

    def _cycle(self, now: int) -> int:
        self._now = now
        ctx = self._ctx
        ctx.now_ns = now
        if OS_SCAN_HOOKS:
            self._run_hooks(now)
        last = self._last_ob1
        if last is not None and now - last < self.watchdog.min_cycle_ns:
            self._interrupts(now)  # interrupt OBs still run in the minimum-cycle wait
            return 0
        cycle_ns = 0
        if last is not None:
            cycle_ns = now - last
            self.stats.add(cycle_ns)
            verdict = self.watchdog.check(cycle_ns, has_ob80=80 in self.obs)
            if verdict is not Verdict.OK:
                limit = self.watchdog.max_cycle_ns // 1_000_000
                msg = f"cycle time {cycle_ns / 1e6:.1f} ms exceeds {limit} ms"
                self.diagnostics.record(self._raw, EventId.CYCLE_TIME_EXCEEDED, "OB1", msg)
                if verdict is Verdict.STOP:
                    if 80 in self.obs:
                        self._go_stop(EventId.STOP_CYCLE_TIME, "OB80", "twice the maximum")
                    else:
                        why = "no OB80 is loaded for a time error"
                        self._go_stop(EventId.STOP_OB80_MISSING, "OB80", why)
                    return cycle_ns
                self._run_ob(80, {"FLT_ID": 0x01, "CYCLE_MS": cycle_ns // 1_000_000})
                if self.mode is not CpuMode.RUN:
                    return cycle_ns
        self._last_ob1 = now
        self.cycle += 1
        ctx.cycle = self.cycle
        if self.clock_memory is not None:
            self._clock_memory(now)
        self.update_pii()
        plan = self.forces.plan(Area.M)
        if plan:
            apply_plan(self.mem.markers, plan)
        self._run_ob(1, self.stats.start_info_ms())
        if self.mode is CpuMode.RUN:
            self._interrupts(now)
        if self.mode is CpuMode.RUN:
            self.update_piq()
        return cycle_ns

    def _clock_memory(self, now: int) -> None:
        assert self.clock_memory is not None
        ms = now // 1_000_000
        value = 0
        for bit, half in enumerate(CLOCK_MEMORY_HALF_MS):
            value |= ((ms // half) & 1) << bit
        self.mem.markers[self.clock_memory] = value

    def _run_ob(self, number: int, start_info: dict[str, Any], *, nested: bool = False) -> None:
        """Run OB ``number`` in its priority class (``priority_class``); PI is read-only to
        it. ``nested``: inside a block of another OB (OB122), which an abort escapes to."""
        block = self.obs.get(number)
        if block is None:
            return
        ctx = self._ctx
        diag, mem = self.diagnostics, self.mem
        outer = diag.ob, diag.priority, mem.pi_locked
        diag.ob, diag.priority = number, self.priority_class(number)
        mem.pi_locked = True
        ctx.ob = number
        ctx.depth = 0
        ctx.start_info = start_info
        self._ran.append(number)
        airt = self._airt_disabled
        marks = ctx.marks
        before = marks.enter(block) if marks is not None else 0
        try:
            block.body(ctx)
        except _Fault as fault:
            self._program_error(number, fault.block, fault.exc)
        except ScanAborted as abort:
            if nested:
                raise
            self.abort(abort.block or block.label)
        except (Exception, SystemExit, KeyboardInterrupt) as exc:  # a block error, never an exit
            self._program_error(number, block.label, exc)
        finally:
            self._airt_disabled = airt  # DIS_AIRT ends with its OB
            diag.ob, diag.priority, mem.pi_locked = outer
            if marks is not None:
                marks.leave(before)

    def _go_stop(self, event: int, block: str, message: str) -> None:
        """STOP with an entry ``event``; after a STOP by an error (``NO_HOT_AFTER_STOP``)
        only a warm restart, in this process as after the state file is read back."""
        if event in NO_HOT_AFTER_STOP:
            self.hot_blockers.add(error_blocker(message))
        self.mode = CpuMode.STOP
        self._hold_since = None
        self.meters.stop_cpu(self.clock.now_ns())
        self.delays.clear()
        self.mem.clear_outputs(image=False)
        self.stop_entry = self.diagnostics.record(self.clock.now_ns(), event, block, message)

    # ---- commands and startup ---------------------------------------------------------------

    def _drain(self) -> None:
        requests: list[ModeRequest] = []
        while self._commands:
            pending = self._commands.popleft()
            command = pending.command
            try:
                if isinstance(command, ModeRequest):
                    requests.append(command)
                elif isinstance(command, SetKeySwitch):
                    self.set_key(command.position)
                elif hasattr(command, "apply"):
                    pending.result = command.apply(self)
                elif callable(command):
                    pending.result = command(self)
                else:
                    raise BlockError(f"unknown command {command!r}")
            except Exception as exc:
                pending.error = (
                    str(exc)
                    if isinstance(exc, S7Error)
                    else internal_error("in the CPU while applying a command", exc)
                )
                self.diagnostics.record(self._raw, EventId.COMMAND_FAILED, "", pending.error)
            pending.done = True
        if requests:
            self._apply_mode(requests)

    def _apply_mode(self, requests: list[ModeRequest]) -> None:
        """Several requests at one boundary: the highest priority wins."""
        winner = resolve_requests(r.mode for r in requests)
        request = next(r for r in requests if r.mode is winner)
        if winner is CpuMode.STOP:
            self.stop(request.reason)
        elif winner is CpuMode.HOLD:
            self.hold()
        elif self.mode is CpuMode.HOLD:
            self.resume()
        elif self.mode is CpuMode.STOP:
            self._startup(parse_restart(request.restart))

    def _startup(self, restart: RestartType) -> None:
        raw = self._raw
        if self.mode is not CpuMode.STOP:
            self._go_stop(EventId.STOP_BY_REQUEST, "", f"{restart} restart requested")
        if self.key is KeySwitch.STOP:
            self.diagnostics.record(raw, EventId.STARTUP_REFUSED, "", "key switch is in STOP")
            return
        deselected = sorted(self.interrupts.deselected() & self.obs.keys())
        if deselected:
            msg = f"OB{deselected[0]} is loaded but deselected: startup aborted"
            self.diagnostics.record(raw, EventId.STARTUP_REFUSED, f"OB{deselected[0]}", msg)
            return
        if restart is RestartType.HOT and (self.hot_blockers or not self.hot_restart_enabled):
            why = ", ".join(sorted(self.hot_blockers)) or "hot restart not enabled"
            self.diagnostics.record(
                raw, EventId.STARTUP_REFUSED, "", f"hot restart refused ({why}): warm restart"
            )
            restart = RestartType.WARM
        for hook in self._startup_hooks:
            hook(self, restart)
        rule = RESTART[restart]
        self.mode = CpuMode.STARTUP
        self.diagnostics.record(raw, EventId.STOP_TO_STARTUP, f"OB{rule.ob}", f"{restart} restart")
        mem = self.mem
        if rule.reload_dbs:
            mem.reset_to_initial()
            for idb in self.instance_dbs.values():
                idb.reset()
        elif rule.clear_nonretentive_mtc:
            mem.clear_non_retentive()
        mem.clear_outputs(image=rule.clear_piq and not rule.residual_cycle)
        if rule.clear_pii:
            mem.inputs[:] = bytes(len(mem.inputs))
        self._held_ns = 0
        self._hold_since = None
        self._last_ob1 = None
        self.stats.reset()
        if restart is not RestartType.HOT:
            self.cycle = 0
        ctx = self._ctx
        ctx.now_ns = raw
        ctx.cycle = self.cycle
        hot = restart is RestartType.HOT
        self.meters.start_cpu(raw, hot=hot)
        self.tod.startup(self.rtc.read(raw), hot=hot)
        self._tod_seen = None
        self._airt_disabled = 0
        if OS_SCAN_HOOKS:
            self._run_hooks(raw)  # S5 timers keep running in STARTUP
        self._run_ob(rule.ob, {"RESTART": str(restart)})
        if self.mode is not CpuMode.STARTUP:
            if restart is RestartType.WARM:
                self.hot_blockers.add("aborted warm restart")
            return
        if restart is RestartType.HOT and self.keep_outputs_on_hot_restart:
            pass
        elif restart is RestartType.HOT:
            mem.clear_outputs(modules=False)
        self.update_pii()
        t_run = self.clock.now_ns()  # STOP→RUN instant, after the (unmonitored) startup program
        self.mode = CpuMode.RUN
        self.last_restart = restart
        if restart is not RestartType.HOT:
            self.hot_blockers.clear()
        self.diagnostics.record(t_run, EventId.STARTUP_TO_RUN, "", f"STARTUP → RUN ({restart})")
        cyclic = {ob for ob in self.obs if ob in CYCLIC_DEFAULT_MS}
        cyclic |= {ob for ob in CYCLIC_DEFAULT_MS if self.interrupts.is_configured(ob)}
        self.interrupts.arm(cyclic, t_run)


CommandFn = Callable[[Cpu], object]
