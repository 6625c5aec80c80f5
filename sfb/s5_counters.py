"""S5 counters on the C area cells (docs/runtime.md, "The block runtime"; El-Shahat's S7-300/400
course, timers and counters).

A counter C n (``engine.memory.S5Counter``) holds 0..999 and never wraps: CU stays at 999,
CD stays at 0. CU, CD and S act on the **rising edge** of their condition (the cell keeps
one edge memory each); S loads a BCD preset (``C#26`` = ``W#16#0026``; a non-BCD preset is
a programming error); R = 1 clears the value. Status Q = (value > 0). ``L C n`` reads the
value binary, ``LC C n`` reads it BCD. In S_CUD a simultaneous CU and CD edge leaves the
value unchanged and R dominates (``[K]``).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

from s7graph.engine.datatypes import bcd_to_int
from s7graph.engine.errors import ProgramError, TypeMismatch
from s7graph.engine.instructions import add_instruction
from s7graph.engine.memory import S5Counter

COUNT_MAX = 999


class CounterBox(NamedTuple):
    """S_CU / S_CD / S_CUD result: Q, CV (binary) and the function value (BCD)."""

    q: bool
    cv: int
    bcd: int


def cell_of(counters: Sequence[S5Counter], number: int) -> S5Counter:
    """Counter ``C number``; a number beyond the area is a programming error (8x27)."""
    if not 0 <= number < len(counters):
        why = "too high" if number >= 0 else "negative"
        raise ProgramError(f"C{number}: counter number {why} (the CPU has {len(counters)})")
    return counters[number]


def count_up(cell: S5Counter, rlo: bool) -> bool:
    """``CU C n``: +1 on a rising RLO, saturating at 999; returns Q."""
    rising = rlo and not cell.cu_edge
    cell.cu_edge = bool(rlo)
    if rising:
        cell.set_value(min(COUNT_MAX, cell.value + 1))
    return cell.q


def count_down(cell: S5Counter, rlo: bool) -> bool:
    """``CD C n``: -1 on a rising RLO, saturating at 0; returns Q."""
    rising = rlo and not cell.cd_edge
    cell.cd_edge = bool(rlo)
    if rising:
        cell.set_value(max(0, cell.value - 1))
    return cell.q


def set_preset(cell: S5Counter, rlo: bool, preset_bcd: int) -> bool:
    """``S C n``: load the BCD preset (``C#``, ACCU1-L) on a rising RLO; non-BCD raises."""
    rising = rlo and not cell.s_edge
    cell.s_edge = bool(rlo)
    if rising:
        try:
            cell.set_value(bcd_to_int(preset_bcd & 0x0FFF))
        except TypeMismatch as exc:
            raise ProgramError(f"counter preset: {exc.message}") from exc
    return cell.q


def reset(cell: S5Counter, rlo: bool = True) -> bool:
    """``R C n``: value 0 while the RLO is 1."""
    cell.r_edge = bool(rlo)
    if rlo:
        cell.set_value(0)
    return cell.q


def enable(cell: S5Counter, rlo: bool) -> None:
    """``FR C n``: a rising RLO clears the edge memories so a held condition acts again."""
    if rlo and not cell.fr_edge:
        cell.cu_edge = cell.cd_edge = cell.s_edge = False
    cell.fr_edge = bool(rlo)


def s_cud(
    cell: S5Counter,
    *,
    cu: bool = False,
    cd: bool = False,
    s: bool = False,
    pv: int = 0,
    r: bool = False,
) -> CounterBox:
    """S_CUD box (S_CU / S_CD: the other input FALSE): count, then set, then reset."""
    if cu and not cell.cu_edge and cd and not cell.cd_edge:
        cell.cu_edge = cell.cd_edge = True  # both edges at once: unchanged
    else:
        count_up(cell, cu)
        count_down(cell, cd)
    set_preset(cell, s, pv)
    reset(cell, r)
    return CounterBox(cell.q, cell.value, cell.bcd())


def box(
    counters: Sequence[S5Counter], number: int, cu: bool, cd: bool, s: bool, pv: int, r: bool
) -> CounterBox:
    """An S5 counter box called as a function (S_CU, S_CD, S_CUD of S7-SCL) on counter
    ``number``: Q, CV binary and the function value BCD."""
    return s_cud(cell_of(counters, number), cu=cu, cd=cd, s=s, pv=pv, r=r)


add_instruction("S5_COUNTER", box)
