"""S7 literals both ways: text → (type, value) and canonical text (docs/runtime.md, "The block
runtime").

Forms follow Siemens' Program Design for S7-300/400, appendix C, table C-1 (SCL: STEP7 comprehensive
guide vol. 2, ch. 13). Prefixes and units are case-insensitive; ``_`` may separate digits. Values
follow docs/architecture.md, "Seams" (TIME/S5TIME/TOD in ms, DATE ``date``, DT ``datetime``).
"""

from __future__ import annotations

import math
import re
from datetime import date, datetime
from fractions import Fraction

from s7graph.engine.datatypes import (
    DATE_EPOCH,
    DATE_MAX,
    DT_MAX,
    DT_MIN,
    REAL_MAX,
    S5TIME_MAX_MS,
    TYPES,
    check_value,
    real32,
    real_shown,
    type_of,
)
from s7graph.engine.errors import LiteralError, SourceLocation, TypeMismatch

__all__ = ["format_literal", "parse_literal"]

_PREFIX = re.compile(r"([A-Za-z][A-Za-z0-9_]*)#(.*)", re.DOTALL)
_DEC = re.compile(r"[+-]?\d(?:_?\d)*")
_REAL = re.compile(r"[+-]?\d+(?:\.\d+(?:[eE][+-]?\d+)?|[eE][+-]?\d+)")
_RADIX = re.compile(r"(2|8|16)#([0-9A-Fa-f_]+)")
_UNIT = re.compile(r"(\d+(?:\.\d+)?)(MS|D|H|M|S)")
_DATE = re.compile(r"(\d{4})-(\d{1,2})-(\d{1,2})")
_TOD = re.compile(r"(\d{1,2}):(\d{1,2})(?::(\d{1,2})(?:\.(\d{1,3}))?)?")
_BYTES = re.compile(r"\(\s*(\d+)\s*,\s*(\d+)\s*(?:,\s*(\d+)\s*,\s*(\d+)\s*)?\)")

_UNIT_MS = {"D": 86_400_000, "H": 3_600_000, "M": 60_000, "S": 1000, "MS": 1}
_INT_PREFIX = {
    "B": "BYTE",
    "BYTE": "BYTE",
    "W": "WORD",
    "WORD": "WORD",
    "DW": "DWORD",
    "DWORD": "DWORD",
    "L": "DINT",
    "DINT": "DINT",
    "INT": "INT",
}
_ESCAPES = {"$": "$", "'": "'", "L": "\n", "N": "\n", "R": "\r", "T": "\t", "P": "\f"}
_UNESCAPES = {"$": "$$", "'": "$'", "\n": "$N", "\r": "$R", "\t": "$T", "\f": "$P"}


class _Bad(Exception):
    """Internal: why a literal body is rejected (turned into LiteralError)."""


def parse_literal(text: str, where: SourceLocation | None = None) -> tuple[str, object]:
    """Parse an S7 literal into ``(type name, value)``: ``'T#1s200ms'`` → ``('TIME', 1200)``.

    Bare integers are INT, or DINT beyond INT; bare ``16#``/``8#``/``2#`` are WORD (DWORD
    beyond 16 bits); ``C#26`` is the BCD counter value ``('WORD', 0x0026)``. Syntax errors and
    values outside the type's range raise LiteralError naming ``text`` (docs/runtime.md, "The block
    runtime").
    """
    s = text.strip()
    try:
        if not s.startswith("'") and (run := _LONG_DIGITS.search(s)):
            raise _Bad(f"a number of {len(run[0])} digits is beyond every type")
        return _parse(s)
    except (_Bad, TypeMismatch, ValueError, OverflowError) as exc:
        raise LiteralError(f"bad literal {clip(text)}: {exc}", where) from None


def shorten(text: str, limit: int = 40) -> str:
    """``text`` as it is, or cut to ``limit`` characters ending in "..." (for messages that
    quote what was written)."""
    return text if len(text) <= limit else text[: limit - 3] + "..."


def clip(text: str, limit: int = 40) -> str:
    """``repr(text)``, shortened to about ``limit`` characters with "…" (for messages)."""
    if len(text) <= limit:
        return repr(text)
    return repr(text[: limit - 10] + "…" + text[-5:]) + f" ({len(text)} characters)"


_LONG_DIGITS = re.compile(r"(?:[0-9A-Fa-f]_*){40,}")


def _parse(s: str) -> tuple[str, object]:
    up = s.upper()
    if up in ("TRUE", "FALSE"):
        return "BOOL", up == "TRUE"
    if s.startswith("'"):
        return "STRING", _string(s)
    if _DEC.fullmatch(s):
        n = int(s.replace("_", ""))
        return ("INT" if -32768 <= n <= 32767 else "DINT"), _fit("DINT", n)
    if _REAL.fullmatch(s):
        return "REAL", _real(s)
    if m := _RADIX.fullmatch(s):
        n = _radix(m[1], m[2])
        return ("WORD" if n <= 0xFFFF else "DWORD"), _fit("DWORD", n)
    m = _PREFIX.fullmatch(s)
    if m is None:
        raise _Bad("not a literal")
    prefix, body = m[1].upper(), m[2].strip()
    if prefix in _INT_PREFIX:
        if prefix == "B" and body.startswith("("):
            return _byte_list(body)
        tname = _INT_PREFIX[prefix]
        return tname, _fit(tname, _integer(body))
    if prefix == "C":
        n = _integer(body)
        if not 0 <= n <= 999:
            raise _Bad("counter value outside C#0..C#999")
        return "WORD", int(str(n), 16)
    if prefix == "BOOL":
        if body.upper() in ("TRUE", "1"):
            return "BOOL", True
        if body.upper() in ("FALSE", "0"):
            return "BOOL", False
        raise _Bad("BOOL is TRUE/FALSE/1/0")
    if prefix == "REAL":
        return "REAL", _real(body)
    if prefix == "CHAR":
        ch = _string(body) if body.startswith("'") else chr(_fit("BYTE", _integer(body)))
        if len(ch) != 1:
            raise _Bad("a CHAR is one character")
        return "CHAR", ch
    if prefix in ("T", "TIME"):
        return "TIME", _fit("TIME", _duration(body))
    if prefix in ("S5T", "S5TIME"):
        ms = _duration(body)
        if not 0 <= ms <= S5TIME_MAX_MS:
            raise _Bad("outside S5T#0MS..S5T#2H46M30S")
        return "S5TIME", ms
    if prefix in ("D", "DATE"):
        return "DATE", _date(body)
    if prefix in ("TOD", "TIME_OF_DAY"):
        return "TIME_OF_DAY", _tod(body)
    if prefix in ("DT", "DATE_AND_TIME"):
        return "DATE_AND_TIME", _dt(body)
    raise _Bad(f"unknown prefix {m[1]}#")


def _fit(type_name: str, n: int) -> int:
    spec = TYPES[type_name]
    assert spec.lo is not None and spec.hi is not None
    if not spec.lo <= n <= spec.hi:
        raise _Bad(f"{n} is outside {type_name} {spec.lo}..{spec.hi}")
    return n


def _radix(base: str, digits: str) -> int:
    clean = digits.replace("_", "")
    if not clean:
        raise _Bad("no digits")
    try:
        return int(clean, int(base))
    except ValueError:
        wrong = next(c for c in clean if not c.isdigit() or int(c, 36) >= int(base))
        raise _Bad(f"{wrong!r} is not a digit of base {base}") from None


def _integer(body: str) -> int:
    if m := _RADIX.fullmatch(body):
        return _radix(m[1], m[2])
    if _DEC.fullmatch(body):
        return int(body.replace("_", ""))
    raise _Bad("not an integer")


def _real(body: str) -> float:
    if not (_REAL.fullmatch(body) or _DEC.fullmatch(body)):
        raise _Bad("not a REAL")
    value = float(body.replace("_", ""))
    if not math.isfinite(value) or abs(value) > REAL_MAX:
        raise _Bad("outside the REAL range ±3.402823e+38")
    return real32(value)  # a REAL literal holds 32 bits, as the CPU loads it


def _byte_list(body: str) -> tuple[str, object]:
    m = _BYTES.fullmatch(body)
    if m is None:
        raise _Bad("B#(…) takes 2 or 4 bytes")
    parts = [int(g) for g in m.groups() if g is not None]
    if any(p > 255 for p in parts):
        raise _Bad("a byte is 0..255")
    return ("WORD" if len(parts) == 2 else "DWORD"), int.from_bytes(bytes(parts), "big")


def _string(body: str) -> str:
    if len(body) < 2 or not body.endswith("'"):
        raise _Bad("unterminated string")
    inner, out, i = body[1:-1], [], 0
    while i < len(inner):
        ch = inner[i]
        if ch == "'":
            raise _Bad("a quote inside a string is written $'")
        if ch != "$":
            out.append(ch)
            i += 1
            continue
        nxt = inner[i + 1 : i + 2].upper()
        if nxt == ">":  # a string break: what lies up to $< is layout, not text
            end = inner.find("$<", i + 2)
            if end < 0 or inner[i + 2 : end].strip():
                raise _Bad("a string break $> ends at $< with only spaces and lines between")
            i = end + 2
        elif nxt in _ESCAPES:
            out.append(_ESCAPES[nxt])
            i += 2
        elif re.fullmatch(r"[0-9A-Fa-f]{2}", inner[i + 1 : i + 3]):
            out.append(chr(int(inner[i + 1 : i + 3], 16)))
            i += 3
        else:
            raise _Bad("bad $ escape")
    value = "".join(out)
    if len(value) > 254:
        raise _Bad("a STRING holds at most 254 characters")
    return value


def _duration(body: str) -> int:
    """``[-]1D2H3M4S5MS`` (units in descending order, fractions allowed) → ms, truncated."""
    clean = body.replace("_", "").upper()
    sign = -1 if clean.startswith("-") else 1
    clean = clean.lstrip("+-")
    pos, total, last = 0, Fraction(0), 10**9
    for m in _UNIT.finditer(clean):
        if m.start() != pos:
            break
        unit_ms = _UNIT_MS[m[2]]
        if unit_ms >= last:
            raise _Bad("units must appear once, in the order D H M S MS")
        total += Fraction(m[1]) * unit_ms
        last, pos = unit_ms, m.end()
    if not clean or pos != len(clean):
        raise _Bad("a duration is like 1D2H3M4S5MS")
    return sign * int(total)


def _date(body: str) -> date:
    m = _DATE.fullmatch(body)
    if m is None:
        raise _Bad("a date is YYYY-MM-DD")
    year, month, day = int(m[1]), int(m[2]), int(m[3])
    if not 1 <= month <= 12:
        raise _Bad(f"there is no month {month}")
    try:
        value = date(year, month, day)
    except ValueError:
        raise _Bad(f"{year}-{month:02d} has no day {day}") from None
    if not DATE_EPOCH <= value <= DATE_MAX:
        raise _Bad("outside D#1990-01-01..D#2168-12-31")
    return value


def _tod_parts(body: str) -> tuple[int, int, int, int]:
    m = _TOD.fullmatch(body)
    if m is None:
        raise _Bad("a time of day is hh:mm:ss.mmm")
    h, mi, sec = int(m[1]), int(m[2]), int(m[3] or 0)
    ms = int((m[4] or "0").ljust(3, "0"))
    if h > 23 or mi > 59 or sec > 59:
        raise _Bad("outside 0:0:0.0..23:59:59.999")
    return h, mi, sec, ms


def _tod(body: str) -> int:
    h, mi, sec, ms = _tod_parts(body)
    return ((h * 60 + mi) * 60 + sec) * 1000 + ms


def _dt(body: str) -> datetime:
    m = re.fullmatch(r"(\d{4}-\d{1,2}-\d{1,2})-(.+)", body)
    if m is None:
        raise _Bad("a date and time is YYYY-MM-DD-hh:mm:ss.mmm")
    d = _date(m[1])
    h, mi, sec, ms = _tod_parts(m[2])
    value = datetime(d.year, d.month, d.day, h, mi, sec, ms * 1000)
    if not DT_MIN <= value <= DT_MAX:
        raise _Bad("outside DT#1990-01-01-0:0:0..DT#2089-12-31-23:59:59.999")
    return value


# ---- formatting -------------------------------------------------------------------------


def _fmt_duration(ms: int) -> str:
    sign, rest, parts = ("-" if ms < 0 else ""), abs(ms), []
    for unit, size in _UNIT_MS.items():
        count, rest = divmod(rest, size)
        if count:
            parts.append(f"{count}{unit}")
    return sign + ("".join(parts) or "0MS")


def _fmt_ms(ms: int) -> str:
    return f".{ms:03d}" if ms else ""


def _fmt_real(value: float) -> str:
    if not math.isfinite(value):
        raise TypeMismatch(f"{value!r} has no REAL literal")
    text = repr(float(value)).upper()
    mant, _, exp = text.partition("E")
    if "." not in mant:
        mant += ".0"
    return f"{mant}E{exp}" if exp else mant


def _fmt_string(value: str) -> str:
    out = []
    for ch in value:
        if ch in _UNESCAPES:
            out.append(_UNESCAPES[ch])
        elif ch.isprintable():
            out.append(ch)
        else:
            out.append(f"${ord(ch):02X}")
    return "'" + "".join(out) + "'"


def format_literal(type_name: str, value: object) -> str:
    """Canonical upper-case literal: ``('TIME', 1200)`` → ``'T#1S200MS'``, WORD → ``W#16#FFF0``.

    ``parse_literal(format_literal(t, v))`` gives back ``(t, v)`` (STRING[n] as STRING);
    a value outside the type raises TypeMismatch (Siemens' Program Design for S7-300/400, appendix
    C).
    """
    spec = type_of(type_name)
    v = check_value(spec.name, value)
    name = spec.name
    if name == "BOOL":
        return "TRUE" if v else "FALSE"
    if name == "REAL":
        assert isinstance(v, float)
        return _fmt_real(real_shown(v))
    if name == "CHAR":
        assert isinstance(v, str)
        return f"CHAR#{ord(v)}"
    if name == "DATE":
        assert isinstance(v, date)
        return f"D#{v.isoformat()}"
    if name == "DATE_AND_TIME":
        assert isinstance(v, datetime)
        ms = v.microsecond // 1000
        return f"DT#{v.date().isoformat()}-{v:%H:%M:%S}{_fmt_ms(ms)}"
    if name.startswith("STRING"):
        assert isinstance(v, str)
        return _fmt_string(v)
    assert isinstance(v, int)
    if name == "S5TIME":
        return "S5T#" + _fmt_duration(v)
    if name == "TIME":
        return "T#" + _fmt_duration(v)
    if name == "TIME_OF_DAY":
        sec, ms = divmod(v, 1000)
        return f"TOD#{sec // 3600:02d}:{sec // 60 % 60:02d}:{sec % 60:02d}{_fmt_ms(ms)}"
    if name == "BYTE":
        return f"B#16#{v:02X}"
    if name in ("WORD", "TIMER", "COUNTER"):
        return f"W#16#{v:04X}"
    if name == "DWORD":
        return f"DW#16#{v:08X}"
    if name == "DINT":
        return f"L#{v}"
    return str(v)  # INT
