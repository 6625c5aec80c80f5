"""S5 timers SP SE SD SS SF on the T area, and the S5TIME codec (docs/runtime.md, "The block
runtime"; El-Shahat's S7-300/400 course, timers and counters).

S5TIME (16 bit): bits 0-11 three BCD digits 0..999, bits 12-13 the time base (10 ms, 100 ms, 1 s, 10
s); a preset in ms is encoded with the smallest base that fits (``S5T#2S`` = ``W#16#0200``). A timer
cell counts its value down **at its time base on the CPU's tick grid** (``now_ns // base``),
asynchronously to the program, so a started timer expires between TV - 1 base and TV after the
start. ``L T n`` reads the count binary, ``LC T n`` reads it BCD with the time base. The five
functions:

* SP pulse: rising S starts; Q = 1 while S = 1 and time runs; S = 0 stops it (Q = 0).
* SE extended pulse: rising S starts; Q = 1 for the full time; a rising S retriggers.
* SD on-delay: rising S starts; Q = 1 after TV while S = 1; S = 0 stops it (Q = 0).
* SS retentive on-delay: rising S starts (restarts while running); Q = 1 after TV until R.
* SF off-delay: S = 1 gives Q = 1; the falling S starts; Q = 0 after TV; rising S stops it.

A timer *stopped* keeps its time value (``L T n`` reads the time left when it stopped), as the
STEP 7 Statement List manual (timer instructions) words it: "the time is stopped"; only R
clears it. R = 1 clears value and Q for all five (R dominates, as a level: a reset timer whose
S stays 1 starts again only on a new rising edge). A rising FR with S = 1 restarts.

The OS updates the T area once per scan: importing this module registers ``scan_hook`` with
``engine.cpu.add_os_scan_hook``, so every CPU ticks its timers at the start of each cycle on the
process time (frozen in HOLD, running in STARTUP) without any further timer instruction.
"""

from __future__ import annotations

from collections.abc import Sequence
from enum import StrEnum

from s7graph.engine.cpu import Cpu, add_os_scan_hook
from s7graph.engine.datatypes import S5_BASES_MS as TIME_BASES_MS
from s7graph.engine.datatypes import bcd_to_int, int_to_bcd, ms_to_s5time, s5time_to_ms
from s7graph.engine.errors import ProgramError
from s7graph.engine.instructions import add_instruction
from s7graph.engine.memory import S5Timer

NS_PER_MS = 1_000_000

# The S5TIME codec lives in engine.datatypes; these names are the sfb spelling of it.
s5time_encode = ms_to_s5time
s5time_decode = s5time_to_ms
to_bcd = int_to_bcd
from_bcd = bcd_to_int


def s5time_split(word: int) -> tuple[int, int]:
    """S5TIME word to ``(count, base_ms)``; bits 14-15 are ignored."""
    return from_bcd(word & 0x0FFF), TIME_BASES_MS[(word >> 12) & 0x3]


class TimerFunction(StrEnum):
    """The five S5 timer functions (English STL mnemonic; German/box names in comments)."""

    SP = "SP"  # SI, S_PULSE
    SE = "SE"  # SV, S_PEXT
    SD = "SD"  # SE, S_ODT
    SS = "SS"  # SS, S_ODTS
    SF = "SF"  # SA, S_OFFDT


# German STL and SCL/LAD box names for the same functions (El-Shahat's S7-300/400 course, timers and
# counters table).
FUNCTION_ALIASES: dict[str, TimerFunction] = {
    "S_PULSE": TimerFunction.SP,
    "SI": TimerFunction.SP,
    "S_PEXT": TimerFunction.SE,
    "SV": TimerFunction.SE,
    "S_ODT": TimerFunction.SD,
    "S_ODTS": TimerFunction.SS,
    "S_OFFDT": TimerFunction.SF,
    "SA": TimerFunction.SF,
}


def _function(name: TimerFunction | str) -> TimerFunction:
    key = str(name).upper()
    try:
        return FUNCTION_ALIASES.get(key) or TimerFunction(key)
    except ValueError:
        raise ProgramError(f"unknown S5 timer function {name!r} (SP SE SD SS SF)") from None


def _remaining_count(cell: S5Timer, now_ns: int) -> int:
    """Ticks left: the preset count minus the time-base boundaries passed since the start."""
    base_ns = cell.time_base_ms * NS_PER_MS
    passed = max(0, now_ns // base_ns - cell.start_ns // base_ns)
    return max(0, cell.preset_ms // cell.time_base_ms - passed)


def tick(cell: S5Timer, now_ns: int) -> None:
    """The OS update of one cell: count down on the time-base grid; handle expiry."""
    if not cell.running:
        return
    if cell.resume:  # restored from a state file (its start was on another process's clock),
        # or an off delay whose start input fell after its pulse: the time left runs from now
        cell.resume = False
        cell.start_ns = now_ns - (cell.preset_ms - cell.value_ms) * NS_PER_MS
    count = _remaining_count(cell, now_ns)
    cell.value_ms = count * cell.time_base_ms
    if count == 0:
        cell.running = False
        cell.q = {TimerFunction.SD: cell.s_edge, TimerFunction.SS: True}.get(
            _function(cell.mode), False
        )


def tick_all(timers: Sequence[S5Timer], now_ns: int) -> None:
    """The OS update of the T area (call once per scan, and before reading a timer)."""
    for cell in timers:
        if cell.running:
            tick(cell, now_ns)


def scan_hook(cpu: Cpu, now_ns: int) -> None:
    """The per-scan OS task: tick every running timer cell of ``cpu``."""
    tick_all(cpu.mem.timers, now_ns)


add_os_scan_hook(scan_hook)


def shift(timers: Sequence[S5Timer], delta_ns: int) -> None:
    """Freeze running timers for ``delta_ns`` (HOLD: timers stop, the RTC runs)."""
    for cell in timers:
        if cell.running:
            cell.start_ns += delta_ns


def cell_of(timers: Sequence[S5Timer], number: int) -> S5Timer:
    """Timer ``T number``; a number beyond the area is a programming error (8x26)."""
    if not 0 <= number < len(timers):
        why = "too high" if number >= 0 else "negative"
        raise ProgramError(f"T{number}: timer number {why} (the CPU has {len(timers)})")
    return timers[number]


def _load(cell: S5Timer, tv_ms: int, now_ns: int, base_ms: int | None = None) -> None:
    """Load the time ``tv_ms`` (in units of ``base_ms``, else of the finest base that holds
    it) and start counting at ``now_ns``."""
    if base_ms is None:
        count, base = s5time_split(s5time_encode(tv_ms))
    else:
        count, base = tv_ms // base_ms, base_ms
    cell.time_base_ms, cell.preset_ms, cell.value_ms = base, count * base, count * base
    cell.start_ns = now_ns
    cell.running = count > 0


def reset(cell: S5Timer) -> None:
    """``R T n``: value 0, status 0, stopped (edge memories are kept)."""
    cell.value_ms, cell.running, cell.q = 0, False, False


def start(cell: S5Timer, function: TimerFunction | str, word: int, now_ns: int) -> bool:
    """Start ``cell`` in ``function`` with the S5TIME ``word`` (its count in its own time
    base), as a rising edge of S does whatever the edge memory held (a GRAPH event row: each
    occurrence of the event starts the timer); returns Q."""
    count, base = s5time_split(word)
    cell.s_edge = False
    return run(cell, function, True, count * base, now_ns, base_ms=base)


def start_off_delay_at_next_update(cell: S5Timer, word: int, now_ns: int) -> None:
    """SF with S = 1 now and S = 0 from the next call: Q = 1 at once (a running off delay
    stops), the S5TIME ``word`` loaded and counted from the next OS update of the T area (the
    start of the next scan), as an S5 off delay whose start input is a one-call pulse."""
    count, base = s5time_split(word)
    start(cell, TimerFunction.SF, word, now_ns)
    cell.s_edge = False  # the falling edge of the pulse, seen by the next update
    _load(cell, count * base, now_ns, base)
    # ``tick`` sets the start from the time left at the next update (a zero time ends there)
    cell.q = cell.running = cell.resume = True


def run(
    cell: S5Timer,
    function: TimerFunction | str,
    s: bool,
    tv_ms: int,
    now_ns: int,
    *,
    r: bool = False,
    fr: bool = False,
    base_ms: int | None = None,
) -> bool:
    """One timer instruction or box call on ``cell``: start/stop per function, then R; Q.

    ``tv_ms`` is the S5TIME preset in ms, counted in ``base_ms`` (the time base of the
    S5TIME word loaded), else in the finest base that holds it.
    """
    fn = _function(function)
    tick(cell, now_ns)
    s, r, fr = bool(s), bool(r), bool(fr)
    start = (s and not cell.s_edge) or (fr and not cell.fr_edge and s)
    falling = cell.s_edge and not s
    cell.mode, cell.s_edge, cell.fr_edge = fn.value, s, fr
    if fn is TimerFunction.SP:
        if start:
            _load(cell, tv_ms, now_ns, base_ms)
            cell.q = cell.running
        elif not s:
            cell.running, cell.q = False, False
    elif fn is TimerFunction.SE:
        if start:
            _load(cell, tv_ms, now_ns, base_ms)
            cell.q = cell.running
    elif fn is TimerFunction.SD:
        if not s:
            cell.running, cell.q = False, False
        elif start:
            _load(cell, tv_ms, now_ns, base_ms)
            cell.q = not cell.running
    elif fn is TimerFunction.SS:
        if start and not cell.q:
            _load(cell, tv_ms, now_ns, base_ms)
            cell.q = not cell.running
    elif s:
        cell.running, cell.q = False, True
    elif falling:
        _load(cell, tv_ms, now_ns, base_ms)
        cell.q = cell.running
    if r:
        reset(cell)
    return cell.q


def box(
    timers: Sequence[S5Timer],
    number: int,
    function: str,
    s: bool,
    tv_ms: int,
    r: bool,
    now_ns: int,
    *,
    base_ms: int | None = None,
) -> tuple[int, int, bool]:
    """An S5 timer box called as a function (S_PULSE … S_OFFDT of S7-SCL): timer ``number``
    run with S, TV and R; returns the remaining time in ms (the function value, an S5TIME),
    the remaining count binary (BI) and the status (Q). ``base_ms`` is the time base of the
    S5TIME word given as TV (its count runs in it, as after ``L`` and ``SD``), else the
    finest base that holds ``tv_ms``."""
    cell = cell_of(timers, number)
    q = run(cell, function, s, tv_ms, now_ns, r=r, base_ms=base_ms)
    return cell.value_ms, cell.binary(), q


add_instruction("S5_TIMER", box)
