"""What compiled SCL calls at run time: overflow and the OK flag, division, REAL rounding,
conversions, strings, indexed operands, block calls and the loop meter (docs/scl.md,
"Run time").

Every helper that can fail takes the block's OK flag ``ok`` (a one-element list) and clears
it rather than raising: an INT or DINT result out of range wraps to 16/32 bits, a division
by zero gives 0 (REAL: ±infinity), a REAL out of range becomes ±infinity — S7-SCL's rule
(Siemens' S7-SCL V5.3 for S7-300/400, "OK flag"). An array index out of bounds, a DB that is
not there or a block that is not loaded raises: a block error (OB121, else STOP).

**The loop meter.** Loops and jumps back run inside one scan. Each pass of a loop and each
GOTO counts as ``PASS_NS`` of CPU time on the CPU's cycle; when a cycle's passes reach
twice the maximum cycle time, the block is aborted as the real-time runner's monitor
aborts a hanging scan (``engine/runner.py``): a time error, then STOP — on a virtual clock
as on the system clock.
"""

from __future__ import annotations

import math
import struct
from datetime import date, datetime, timedelta
from functools import lru_cache
from typing import Any
from weakref import WeakKeyDictionary

from s7graph.engine.address import Address, Area, Width
from s7graph.engine.datatypes import (
    DATE_EPOCH,
    DATE_MAX,
    DT_MAX,
    DT_MIN,
    S5_BASES_MS,
    check_value,
    decode,
    encode,
    ms_to_s5time,
    real32,
    s5time_to_ms,
)
from s7graph.engine.errors import BlockError, ProgramError, ScanAborted, TypeMismatch
from s7graph.engine.instructions import instruction
from s7graph.steps.scl.types import (
    SclType,
    clone,
    element_stride,
    recast,
    size_of,
    struct_layout,
)

PASS_NS = 1_000
"""CPU time one pass of a loop (or one jump) counts for: 1 µs."""

Ok = list[bool]
_F32 = struct.Struct(">f")
_U32 = struct.Struct(">I")

# ---------------------------------------------------------------- arithmetic


def _ovf(ok: Ok, v: int, bits: int) -> int:
    """An INT (16) or DINT (32) result out of range: OK := FALSE, the low bits kept."""
    ok[0] = False
    half = 1 << (bits - 1)
    return (int(v) + half) % (half << 1) - half


def _idiv(ok: Ok, a: int, b: int, bits: int) -> int:
    """Integer division truncating toward zero (``/`` and ``DIV`` on INT and DINT)."""
    if b == 0:
        ok[0] = False
        return 0
    q = abs(a) // abs(b)
    q = q if (a >= 0) == (b >= 0) else -q
    half = 1 << (bits - 1)
    return q if -half <= q < half else _ovf(ok, q, bits)


def _imod(ok: Ok, a: int, b: int) -> int:
    """``MOD``: the remainder with the dividend's sign."""
    if b == 0:
        ok[0] = False
        return 0
    r = abs(a) % abs(b)
    return r if a >= 0 else -r


def _r32(ok: Ok, v: float) -> float:
    """A REAL result rounded to 32 bits (``real32``); beyond ±3.402823e+38 once rounded, an
    infinity, or NaN: OK := FALSE."""
    r = real32(v)
    if not math.isfinite(r):
        ok[0] = False
    return r


def _rdiv(ok: Ok, a: float, b: float) -> float:
    if b == 0:
        ok[0] = False
        return math.nan if a == 0 else math.copysign(math.inf, a) * math.copysign(1.0, b)
    return _r32(ok, a / b)


def _pow(ok: Ok, a: float, b: float) -> float:
    try:
        result = float(a) ** float(b)
    except (OverflowError, ZeroDivisionError):  # beyond the range, or 0.0 ** a negative
        ok[0] = False
        odd = float(b).is_integer() and int(b) % 2 == 1
        return -math.inf if a < 0 and odd else math.inf
    if isinstance(result, complex):
        ok[0] = False
        return math.nan
    return _r32(ok, result)


def _real_fn(ok: Ok, name: str, v: float) -> float:
    """ABS … ATAN of a REAL (``SQRT(-1)``: OK := FALSE, NaN; ``EXP(1000.0)``: +infinity,
    ``LN(0.0)``: -infinity, each with OK := FALSE, as the floating-point unit gives them)."""
    try:
        result = _REAL_FUNCTIONS[name](float(v))
    except OverflowError:  # EXP, EXPD of a large value: beyond the range, as the FPU gives
        ok[0] = False
        return math.inf
    except ValueError:  # LN, LOG of 0: minus infinity; of a negative, SQRT(-1): NaN
        ok[0] = False
        return -math.inf if v == 0 and name in ("LN", "LOG") else math.nan
    return _r32(ok, result)


_REAL_FUNCTIONS = {
    "SQR": lambda x: x * x,
    "SQRT": math.sqrt,
    "EXP": math.exp,
    "EXPD": lambda x: 10.0**x,
    "LN": math.log,
    "LOG": math.log10,
    "SIN": math.sin,
    "COS": math.cos,
    "TAN": math.tan,
    "ASIN": math.asin,
    "ACOS": math.acos,
    "ATAN": math.atan,
}


def _abs(ok: Ok, v: Any, bits: int) -> Any:
    if isinstance(v, float):
        return abs(v)
    r = abs(v)
    return r if r < 1 << (bits - 1) else _ovf(ok, r, bits)


def _shift(op: str, v: int, n: int, bits: int) -> int:
    """SHL, SHR, ROL, ROR of a BYTE, WORD or DWORD by ``n`` bits (``n`` < 0 counts as 0)."""
    mask = (1 << bits) - 1
    n = max(0, int(n))
    if op == "SHL":
        return (v << n) & mask if n < bits else 0
    if op == "SHR":
        return v >> n if n < bits else 0
    n %= bits
    if op == "ROL":
        return ((v << n) | (v >> (bits - n))) & mask
    return ((v >> n) | (v << (bits - n))) & mask


# ---------------------------------------------------------------- conversions


def _to_int(ok: Ok, v: float, bits: int, mode: str) -> int:
    """REAL → INT/DINT: ``round`` to the nearest (a half to the even number, as RND) or
    ``trunc``; NaN or out of range: OK := FALSE, 0."""
    if v != v or math.isinf(v):
        ok[0] = False
        return 0
    n = round(v) if mode == "round" else math.trunc(v)
    half = 1 << (bits - 1)
    if -half <= n < half:
        return int(n)
    ok[0] = False
    return 0


def _narrow(ok: Ok, v: int, bits: int) -> int:
    """DINT → INT: the value if it fits, else OK := FALSE and the low 16 bits."""
    half = 1 << (bits - 1)
    return v if -half <= v < half else _ovf(ok, v, bits)


def _signed(v: int, bits: int) -> int:
    """A bit pattern read as a signed number (WORD_TO_INT, DWORD_TO_DINT)."""
    return v - (1 << bits) if v >> (bits - 1) & 1 else v


def _from_bcd(ok: Ok, v: int, bits: int) -> int:
    """A BCD word (3 digits, the sign in bits 12-15) or double word (7 digits, bits 28-31)
    as a number (WORD_BCD_TO_INT, DWORD_BCD_TO_DINT); a digit A-F: OK := FALSE and 0."""
    digits = bits // 4 - 1
    n = 0
    for k in range(digits - 1, -1, -1):
        d = v >> (4 * k) & 15
        if d > 9:
            ok[0] = False
            return 0
        n = n * 10 + d
    return -n if v >> (bits - 1) & 1 else n


def _to_bcd(ok: Ok, v: int, bits: int) -> int:
    """A number as BCD (INT_TO_BCD_WORD: -999..999, DINT_TO_BCD_DWORD: ±9,999,999), the
    sign nibble all ones when negative; beyond the digits: OK := FALSE and 0."""
    digits = bits // 4 - 1
    a = abs(v)
    if a >= 10**digits:
        ok[0] = False
        return 0
    r = int(str(a), 16)  # each decimal digit one nibble
    return r | (15 << (bits - 4)) if v < 0 else r


def _dword_to_real(v: int) -> float:
    """The 32 bits of a DWORD taken as a REAL (the bit pattern, not the number)."""
    return float(_F32.unpack(_U32.pack(v & 0xFFFF_FFFF))[0])


def _real_to_dword(v: float) -> int:
    try:
        raw = _F32.pack(v)
    except OverflowError:
        raw = _F32.pack(math.copysign(math.inf, v))
    return int(_U32.unpack(raw)[0])


def _chr(ok: Ok, v: int) -> str:
    if 0 <= v <= 255:
        return chr(v)
    ok[0] = False
    return chr(v & 0xFF)


def _date_to_dint(v: date) -> int:
    return (v - DATE_EPOCH).days


def _dint_to_date(ok: Ok, v: int) -> date:
    """Days since 1990-01-01 as a DATE; beyond D#1990-01-01..D#2168-12-31 the nearest limit
    and OK false."""
    if v < 0:
        ok[0] = False
        return DATE_EPOCH
    if v > (DATE_MAX - DATE_EPOCH).days:
        ok[0] = False
        return DATE_MAX
    return DATE_EPOCH + timedelta(days=v)


def _tod(v: int) -> int:
    """A TIME_OF_DAY kept within one day."""
    return v % 86_400_000


def _dt_add(ok: Ok, dt: datetime, ms: int) -> datetime:
    """DT + TIME; beyond DT#1990-01-01-0:0:0..DT#2089-12-31-23:59:59.999 the nearest limit
    and OK false, as AD_DT_TM limits its result and clears BR."""
    try:
        out = dt + timedelta(milliseconds=ms)
    except OverflowError:
        out = DT_MAX if ms > 0 else DT_MIN
    if DT_MIN <= out <= DT_MAX:
        return out
    ok[0] = False
    return DT_MAX if out > DT_MAX else DT_MIN


def _dt_diff(ok: Ok, a: Any, b: Any) -> int:
    """DATE − DATE, DT − DT as TIME (ms)."""
    ms = int((a - b) // timedelta(milliseconds=1))
    return ms if -(2**31) <= ms < 2**31 else _ovf(ok, ms, 32)


# ---------------------------------------------------------------- strings (IEC functions)


def _fit(ok: Ok, s: str, n: int = 254) -> str:
    if len(s) <= n:
        return s
    ok[0] = False
    return s[:n]


def _left(ok: Ok, s: str, n: int) -> str:
    if n < 0:
        ok[0] = False
        return ""
    return s[:n]


def _right(ok: Ok, s: str, n: int) -> str:
    if n < 0:
        ok[0] = False
        return ""
    return s[max(len(s) - n, 0) :] if n else ""  # all of it when L is longer


def _mid(ok: Ok, s: str, n: int, p: int) -> str:
    """``MID(IN, L, P)``: ``L`` characters from position ``P`` (the first is 1)."""
    if n < 0 or p < 1 or p > len(s):
        ok[0] = False
        return ""
    return s[p - 1 : p - 1 + n]


def _find(s: str, part: str) -> int:
    """``FIND(IN1, IN2)``: where ``IN2`` starts in ``IN1`` (1-based), 0 if nowhere."""
    return s.find(part) + 1 if part else 0


def _insert(ok: Ok, s: str, part: str, p: int) -> str:
    """``INSERT(IN1, IN2, P)``: ``IN2`` after the ``P``-th character of ``IN1``."""
    if p < 0 or p > len(s):
        ok[0] = False
        return ""
    return _fit(ok, s[:p] + part + s[p:])


def _delete(ok: Ok, s: str, n: int, p: int) -> str:
    """``DELETE(IN, L, P)``: ``L`` characters removed from position ``P``."""
    if n < 0 or p < 1 or p > len(s):
        ok[0] = False
        return s
    return s[: p - 1] + s[p - 1 + n :]


def _replace(ok: Ok, s: str, part: str, n: int, p: int) -> str:
    """``REPLACE(IN1, IN2, L, P)``: ``L`` characters from position ``P`` replaced by ``IN2``."""
    if n < 0 or p < 1 or p > len(s) + 1:
        ok[0] = False
        return s
    return _fit(ok, s[: p - 1] + part + s[p - 1 + n :])


def _i_strng(v: int) -> str:
    """I_STRNG, DI_STRNG: the number with its sign in front (``'+12'``, ``'-7'``)."""
    return f"{v:+d}"


def _r_strng(v: float) -> str:
    """R_STRNG: ``±v.vvvvvvvE±xx``; an infinity ``+INF`` / ``-INF``, not a number ``NaN``."""
    if math.isinf(v):
        return "+INF" if v > 0 else "-INF"
    if math.isnan(v):
        return "NaN"
    text = f"{v:+.7E}"
    mant, _, exp = text.partition("E")
    return f"{mant}E{int(exp):+03d}"


def _strng_num(ok: Ok, s: str, bits: int) -> int:
    try:
        n = int(s.strip())
    except ValueError:
        ok[0] = False
        return 0
    half = 1 << (bits - 1)
    return n if -half <= n < half else _ovf(ok, n, bits)


def _strng_r(ok: Ok, s: str) -> float:
    try:
        return _r32(ok, float(s.strip()))
    except ValueError:
        ok[0] = False
        return 0.0


def _limit(mn: Any, v: Any, mx: Any) -> Any:
    return mn if v < mn else mx if v > mx else v


def _mux(ok: Ok, k: int, *values: Any) -> Any:
    if 0 <= k < len(values):
        return values[k]
    ok[0] = False
    return values[0]


# ---------------------------------------------------------------- indices and operands


def _ix(i: int, lo: int, hi: int, where: str) -> int:
    """``i - lo`` for an index within ``lo..hi``; outside it is a block error."""
    if lo <= i <= hi:
        return i - lo
    raise ProgramError(f"array index {i} outside {lo}..{hi}", where)


_WIDTHS = {1: Width.BIT, 8: Width.BYTE, 16: Width.WORD, 32: Width.DWORD}


@lru_cache(maxsize=4096)
def _ad(area: str, bits: int, byte: int, bit: int = 0, db: int | None = None) -> Address:
    """The address of an indexed operand (``MD[i]``, ``Q[i, 0]``, ``DB1.DW[i]``), made once
    for each place a program reaches (an Address is immutable)."""
    return Address(Area(area), _WIDTHS[bits], byte, bit, db)


def _anyp(addr: Address, type_name: str, count: int) -> str:
    """The ANY pointer text a system block reads (``P#DB5.DBX4.0 BYTE 20``, SFC 20 BLKMOV's
    SRCBLK) to ``count`` values of ``type_name`` from ``addr``."""
    return f"P#{addr} {type_name} {count}"


def _mget(mem: Any, area: str, db: int | None, byte: int, t: SclType) -> Any:
    """A whole STRUCT or ARRAY read from memory (a DB) as a dict or list."""
    buf = mem.area_bytes(area, db)
    return _decode(buf, byte, 0, t)


def _mset(mem: Any, area: str, db: int | None, byte: int, t: SclType, value: Any) -> None:
    buf = mem.area_bytes(area, db)
    _encode(buf, byte, 0, t, value)


def _span(buf: bytearray, byte: int, size: int) -> None:
    if byte < 0 or byte + size > len(buf):
        raise ProgramError(f"bytes {byte}..{byte + size - 1} are outside the DB ({len(buf)})")


def _decode(buf: bytearray, byte: int, bit: int, t: SclType) -> Any:
    if t.kind == "BOOL":
        _span(buf, byte, 1)
        return bool(buf[byte] >> bit & 1)
    if t.kind == "ARRAY":
        assert t.element is not None
        step = element_stride(t)
        if t.element.kind == "BOOL":
            return [_decode(buf, byte + k // 8, k % 8, t.element) for k in range(t.count)]
        return [_decode(buf, byte + k * step, 0, t.element) for k in range(t.count)]
    if t.kind == "STRUCT":
        offsets, _ = struct_layout(t)
        return {n: _decode(buf, byte + offsets[n][0], offsets[n][1], ft) for n, ft in t.fields}
    size = size_of(t)
    _span(buf, byte, size)
    return decode(_engine_name(t), buf[byte : byte + size])


def _encode(buf: bytearray, byte: int, bit: int, t: SclType, value: Any) -> None:
    if t.kind == "BOOL":
        _span(buf, byte, 1)
        buf[byte] = buf[byte] | (1 << bit) if value else buf[byte] & ~(1 << bit) & 0xFF
    elif t.kind == "ARRAY":
        assert t.element is not None
        step = element_stride(t)
        for k, item in enumerate(value):
            if t.element.kind == "BOOL":
                _encode(buf, byte + k // 8, k % 8, t.element, item)
            else:
                _encode(buf, byte + k * step, 0, t.element, item)
    elif t.kind == "STRUCT":
        offsets, _ = struct_layout(t)
        for n, ft in t.fields:
            _encode(buf, byte + offsets[n][0], offsets[n][1], ft, value[n])
    else:
        data = encode(_engine_name(t), value)
        _span(buf, byte, len(data))
        buf[byte : byte + len(data)] = data


def _engine_name(t: SclType) -> str:
    return f"STRING[{t.length}]" if t.kind == "STRING" else t.kind


# ---------------------------------------------------------------- blocks


def _block(ctx: Any, label: str) -> Any:
    """A loaded block by label (``FC41``, ``SFC46``): a CALL's look-up, at run time."""
    found = ctx.cpu.blocks.get(label)
    if found is None:
        raise BlockError(f"block {label} is not loaded")
    return found


def _idb(ctx: Any, number: int, fb: str) -> Any:
    """Instance DB ``number``, which must be one of FB ``fb``."""
    idb = ctx.cpu.instance_db(number)
    if idb.fb.label != fb:
        raise BlockError(f"DB{number} is an instance of {idb.fb.label}, not {fb}")
    return idb


def _fcall(ctx: Any, eno: Ok, blk: Any, args: dict[str, Any]) -> Any:
    """An FC called inside an expression: its value; ENO from its OK flag."""
    result = ctx._invoke(blk, args)
    eno[0] = args.pop("ENO", True) is not False
    return result


def _start_info(ctx: Any, key: str, default: Any, type_name: str) -> Any:
    """An OB's start information ``key`` (``FLT_ID`` for ``OB80_FLT_ID``) if it is a value
    of the variable's type, else ``default``."""
    info = ctx.start_info
    value = info.get(key, default) if info else default
    try:
        return check_value(type_name, value)
    except (TypeMismatch, ValueError):
        return default


def _s5_timer(
    ctx: Any, fn: str, number: int, s: bool, tv: int, r: bool
) -> tuple[int, int, bool, int]:
    """S_PULSE … S_OFFDT: the operating system's S5 timer on T ``number`` (registered by
    ``sfb``, ``engine.instructions``) given the S5TIME word ``tv``, whose BCD count runs in
    its own time base (as ``L`` then ``SD`` start a timer in STL): the remaining ms, the
    remaining count (BI), Q, and the time left as an S5TIME word in the timer's time base
    (as ``LC T`` reads it)."""
    try:
        ms = s5time_to_ms(tv)
    except TypeMismatch:  # the word given, time base bits and all
        raise ProgramError(f"TV: W#16#{tv & 0xFFFF:04X} is not valid BCD") from None
    base = S5_BASES_MS[(tv >> 12) & 0x3]
    box = instruction("S5_TIMER")
    left, count, q = box(ctx.mem.timers, number, fn, s, ms, r, ctx.now_ns, base_ms=base)
    return int(left), int(count), bool(q), ctx.mem.timers[number].bcd()


def _s5_counter(
    ctx: Any, number: int, cu: bool, cd: bool, s: bool, pv: int, r: bool
) -> tuple[int, int, bool]:
    """S_CU, S_CD, S_CUD on C ``number``: the count BCD (the function value), binary, Q."""
    q, cv, bcd = instruction("S5_COUNTER")(ctx.mem.counters, number, cu, cd, s, pv, r)
    return int(bcd), int(cv), bool(q)


def _s5w(ms: int) -> int:
    """An S5TIME held as a value (ms) as a word, in the finest time base that holds it (as
    ``S5T#`` encodes)."""
    try:
        return ms_to_s5time(ms)
    except TypeMismatch as exc:
        raise ProgramError(f"TV: {exc.message}") from None


class Meter:
    """Passes left in the current cycle for one CPU (``PASS_NS`` each)."""

    __slots__ = ("at", "cycle", "left")

    def __init__(self) -> None:
        self.cycle = -1
        self.at = -1
        self.left = 0

    def over(self, ctx: Any, block: str, where: str = "") -> None:
        """The passes are used up: abort the scan (a time error naming the loop's place, then
        STOP)."""
        cpu = ctx.cpu
        limit = 2 * _max_cycle_ns(cpu) // 1_000_000
        at = f", the loop at {where}" if where else ""
        cpu.abort_reason = f"a loop still running at twice the maximum cycle time ({limit} ms){at}"
        abort = ScanAborted()
        abort.block = block
        raise abort


_METERS: WeakKeyDictionary[Any, Meter] = WeakKeyDictionary()


def _max_cycle_ns(cpu: Any) -> int:
    watchdog = getattr(cpu, "watchdog", None)
    return int(getattr(watchdog, "max_cycle_ns", 150_000_000))


def _meter(ctx: Any) -> Meter:
    """The CPU's meter, refilled at the first block of each cycle."""
    cpu = ctx.cpu
    meter = _METERS.get(cpu)
    if meter is None:
        meter = _METERS[cpu] = Meter()
    if meter.cycle != ctx.cycle or meter.at != ctx.now_ns:
        meter.cycle, meter.at = ctx.cycle, ctx.now_ns
        meter.left = 2 * _max_cycle_ns(cpu) // PASS_NS
    return meter


RUNTIME: dict[str, Any] = {
    name: obj
    for name, obj in dict(globals()).items()
    if name.startswith("_") and not name.startswith("__") and callable(obj)
}
RUNTIME["_f32"] = real32
RUNTIME["_clone"] = clone
RUNTIME["_recast"] = recast
RUNTIME["_date"] = date
RUNTIME["_datetime"] = datetime
"""The names generated code finds in its module (each begins with ``_``)."""
