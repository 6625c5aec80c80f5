"""The functions S7-SCL knows by name: conversions, numeric and bit functions, and the IEC
functions of strings and selection (docs/scl.md, "Functions"; Siemens' S7-SCL V5.3 for
S7-300/400, "Standard functions"; the guide ch. 13 and ch. 12 for the IEC library).

A function takes its parameters by position or by name (``SHL(IN := w, N := 3)``). A
conversion ``A_TO_B`` takes exactly an ``A`` (or what widens to it). Where a result does not
fit — ``DINT_TO_INT(40000)``, ``REAL_TO_INT(1.0E9)``, ``LEFT(s, -1)`` — OK becomes FALSE.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from s7graph.engine.errors import SourceLocation
from s7graph.steps.scl import types as ty
from s7graph.steps.scl.diagnostics import Problem
from s7graph.steps.scl.gen import Block, X

Gen = Callable[[Block, list[X], SourceLocation], X]


@dataclass(frozen=True, slots=True)
class Builtin:
    """A function's parameter names in order (``*``: any number more) and its generator."""

    params: tuple[str, ...]
    gen: Gen


def _arg(b: Block, x: X, t: ty.SclType, loc: SourceLocation) -> str:
    return b.exprs.convert(x, t, loc, "pass")


# ---------------------------------------------------------------- conversions

_CONVERSIONS: dict[str, tuple[ty.SclType, ty.SclType, str]] = {
    "BOOL_TO_BYTE": (ty.BOOL, ty.BYTE, "int({})"),
    "BOOL_TO_WORD": (ty.BOOL, ty.WORD, "int({})"),
    "BOOL_TO_DWORD": (ty.BOOL, ty.DWORD, "int({})"),
    "BYTE_TO_BOOL": (ty.BYTE, ty.BOOL, "bool({} & 1)"),
    "BYTE_TO_WORD": (ty.BYTE, ty.WORD, "{}"),
    "BYTE_TO_DWORD": (ty.BYTE, ty.DWORD, "{}"),
    "BYTE_TO_CHAR": (ty.BYTE, ty.CHAR, "chr({})"),
    "WORD_TO_BOOL": (ty.WORD, ty.BOOL, "bool({} & 1)"),
    "WORD_TO_BYTE": (ty.WORD, ty.BYTE, "({} & 255)"),
    "WORD_TO_DWORD": (ty.WORD, ty.DWORD, "{}"),
    "WORD_TO_INT": (ty.WORD, ty.INT, "_signed({}, 16)"),
    "WORD_TO_DINT": (ty.WORD, ty.DINT, "{}"),
    "DWORD_TO_BOOL": (ty.DWORD, ty.BOOL, "bool({} & 1)"),
    "DWORD_TO_BYTE": (ty.DWORD, ty.BYTE, "({} & 255)"),
    "DWORD_TO_WORD": (ty.DWORD, ty.WORD, "({} & 65535)"),
    "DWORD_TO_DINT": (ty.DWORD, ty.DINT, "_signed({}, 32)"),
    # BCD: a WORD of 3 digits and a sign, a DWORD of 7 (S7-SCL's class B conversions)
    "WORD_BCD_TO_INT": (ty.WORD, ty.INT, "_from_bcd(_ok, {}, 16)"),
    "BCD_TO_INT": (ty.WORD, ty.INT, "_from_bcd(_ok, {}, 16)"),
    "INT_TO_BCD_WORD": (ty.INT, ty.WORD, "_to_bcd(_ok, {}, 16)"),
    "INT_TO_BCD": (ty.INT, ty.WORD, "_to_bcd(_ok, {}, 16)"),
    "DWORD_BCD_TO_DINT": (ty.DWORD, ty.DINT, "_from_bcd(_ok, {}, 32)"),
    "BCD_TO_DINT": (ty.DWORD, ty.DINT, "_from_bcd(_ok, {}, 32)"),
    "DINT_TO_BCD_DWORD": (ty.DINT, ty.DWORD, "_to_bcd(_ok, {}, 32)"),
    "DINT_TO_BCD": (ty.DINT, ty.DWORD, "_to_bcd(_ok, {}, 32)"),
    "DWORD_TO_REAL": (ty.DWORD, ty.REAL, "_dword_to_real({})"),
    "CHAR_TO_BYTE": (ty.CHAR, ty.BYTE, "ord({})"),
    "CHAR_TO_INT": (ty.CHAR, ty.INT, "ord({})"),
    "CHAR_TO_STRING": (ty.CHAR, ty.string(1), "{}"),
    "STRING_TO_CHAR": (ty.STRING, ty.CHAR, "({0}[:1] or '\\x00')"),
    "INT_TO_CHAR": (ty.INT, ty.CHAR, "_chr(_ok, {})"),
    "INT_TO_WORD": (ty.INT, ty.WORD, "({} & 65535)"),
    "INT_TO_DWORD": (ty.INT, ty.DWORD, "({} & 4294967295)"),
    "INT_TO_DINT": (ty.INT, ty.DINT, "{}"),
    "INT_TO_REAL": (ty.INT, ty.REAL, "float({})"),
    "DINT_TO_INT": (ty.DINT, ty.INT, "_narrow(_ok, {}, 16)"),
    "DINT_TO_WORD": (ty.DINT, ty.WORD, "({} & 65535)"),
    "DINT_TO_DWORD": (ty.DINT, ty.DWORD, "({} & 4294967295)"),
    "DINT_TO_REAL": (ty.DINT, ty.REAL, "_f32({})"),
    "DINT_TO_TIME": (ty.DINT, ty.TIME, "{}"),
    "DINT_TO_DATE": (ty.DINT, ty.DATE, "_dint_to_date(_ok, {})"),
    "DINT_TO_TOD": (ty.DINT, ty.TOD, "_tod({})"),
    "REAL_TO_INT": (ty.REAL, ty.INT, "_to_int(_ok, {}, 16, 'round')"),
    "REAL_TO_DINT": (ty.REAL, ty.DINT, "_to_int(_ok, {}, 32, 'round')"),
    "REAL_TO_DWORD": (ty.REAL, ty.DWORD, "_real_to_dword({})"),
    "ROUND": (ty.REAL, ty.DINT, "_to_int(_ok, {}, 32, 'round')"),
    "TRUNC": (ty.REAL, ty.DINT, "_to_int(_ok, {}, 32, 'trunc')"),
    "TIME_TO_DINT": (ty.TIME, ty.DINT, "{}"),
    "DATE_TO_DINT": (ty.DATE, ty.DINT, "_date_to_dint({})"),
    "TOD_TO_DINT": (ty.TOD, ty.DINT, "{}"),
    "TIME_OF_DAY_TO_DINT": (ty.TOD, ty.DINT, "{}"),
}


def _conversion(src: ty.SclType, dst: ty.SclType, template: str) -> Gen:
    def gen(b: Block, xs: list[X], loc: SourceLocation) -> X:
        return X(dst, "(" + template.format(_arg(b, xs[0], src, loc)) + ")")

    return gen


# ---------------------------------------------------------------- numeric and bit functions


def _abs(b: Block, xs: list[X], loc: SourceLocation) -> X:
    x = xs[0]
    if not ty.is_num(x.type):
        raise Problem("E220", f"ABS takes a number, not {x.type}", loc)
    bits = 32 if x.type.kind == "DINT" else 16
    return X(x.type, f"_abs(_ok, {x.src}, {bits})")


def _real_function(name: str) -> Gen:
    def gen(b: Block, xs: list[X], loc: SourceLocation) -> X:
        x = xs[0]
        if not ty.is_num(x.type):
            raise Problem("E220", f"{name} takes a number, not {x.type}", loc)
        return X(ty.REAL, f"_real_fn(_ok, {name!r}, {_arg(b, x, ty.REAL, loc)})")

    return gen


def _shift(name: str) -> Gen:
    def gen(b: Block, xs: list[X], loc: SourceLocation) -> X:
        x, n = xs
        if x.type.kind not in ty.MASK:
            raise Problem("E220", f"{name} shifts a BYTE, WORD or DWORD, not {x.type}", loc)
        bits = ty.WIDTH[x.type.kind]
        return X(x.type, f"_shift({name!r}, {x.src}, {_arg(b, n, ty.INT, loc)}, {bits})")

    return gen


def _same_type(
    b: Block, xs: list[X], loc: SourceLocation, name: str
) -> tuple[ty.SclType, list[str]]:
    t = xs[0].type
    for x in xs[1:]:
        wider = ty.common(t, x.type)
        if wider is None:
            raise Problem("E220", f"{name}: {t} and {x.type} are not of one type", loc)
        t = wider
    if t.aggregate or t.kind in ("TIMER", "COUNTER", "BLOCK_DB", "FB"):
        raise Problem("E220", f"{name} takes elementary values, not {t}", loc)
    return t, [_arg(b, x, t, loc) for x in xs]


def _limit(b: Block, xs: list[X], loc: SourceLocation) -> X:
    t, (mn, v, mx) = _same_type(b, xs, loc, "LIMIT")
    return X(t, f"_limit({mn}, {v}, {mx})")


def _minmax(name: str) -> Gen:
    def gen(b: Block, xs: list[X], loc: SourceLocation) -> X:
        if len(xs) < 2:
            raise Problem("E231", f"{name} takes two values or more", loc)
        t, srcs = _same_type(b, xs, loc, name)
        return X(t, f"{name.lower()}({', '.join(srcs)})")

    return gen


def _sel(b: Block, xs: list[X], loc: SourceLocation) -> X:
    g = _arg(b, xs[0], ty.BOOL, loc)
    t, (in0, in1) = _same_type(b, xs[1:], loc, "SEL")
    return X(t, f"({in1} if {g} else {in0})")


def _mux(b: Block, xs: list[X], loc: SourceLocation) -> X:
    if len(xs) < 3:
        raise Problem("E231", "MUX takes K and two values or more", loc)
    k = _arg(b, xs[0], ty.INT, loc)
    t, srcs = _same_type(b, xs[1:], loc, "MUX")
    return X(t, f"_mux(_ok, {k}, {', '.join(srcs)})")


# ---------------------------------------------------------------- strings


def _string_function(result: ty.SclType, template: str, kinds: str) -> Gen:
    """A string function: ``kinds`` says per parameter S (a STRING) or I (an INT)."""

    def gen(b: Block, xs: list[X], loc: SourceLocation) -> X:
        srcs = [
            _arg(b, x, ty.STRING if k == "S" else ty.INT, loc)
            for x, k in zip(xs, kinds, strict=True)
        ]
        return X(result, template.format(*srcs))

    return gen


def _concat(b: Block, xs: list[X], loc: SourceLocation) -> X:
    if len(xs) < 2:
        raise Problem("E231", "CONCAT takes two strings or more", loc)
    srcs = [_arg(b, x, ty.STRING, loc) for x in xs]
    return X(ty.STRING, f"_fit(_ok, {' + '.join(srcs)})")


def _to_string(src: ty.SclType, length: int, helper: str) -> Gen:
    def gen(b: Block, xs: list[X], loc: SourceLocation) -> X:
        return X(ty.string(length), f"{helper}({_arg(b, xs[0], src, loc)})")

    return gen


BUILTINS: dict[str, Builtin] = {
    name: Builtin(("IN",), _conversion(src, dst, template))
    for name, (src, dst, template) in _CONVERSIONS.items()
}
BUILTINS["ABS"] = Builtin(("IN",), _abs)
for _name in ("SQR", "SQRT", "EXP", "EXPD", "LN", "LOG", "SIN", "COS", "TAN"):
    BUILTINS[_name] = Builtin(("IN",), _real_function(_name))
for _name in ("ASIN", "ACOS", "ATAN"):
    BUILTINS[_name] = Builtin(("IN",), _real_function(_name))
for _name in ("SHL", "SHR", "ROL", "ROR"):
    BUILTINS[_name] = Builtin(("IN", "N"), _shift(_name))
BUILTINS["LIMIT"] = Builtin(("MN", "IN", "MX"), _limit)
BUILTINS["MIN"] = Builtin(("IN1", "IN2", "*"), _minmax("MIN"))
BUILTINS["MAX"] = Builtin(("IN1", "IN2", "*"), _minmax("MAX"))
BUILTINS["SEL"] = Builtin(("G", "IN0", "IN1"), _sel)
BUILTINS["MUX"] = Builtin(("K", "IN0", "IN1", "*"), _mux)
BUILTINS["CONCAT"] = Builtin(("IN1", "IN2", "*"), _concat)
BUILTINS["LEN"] = Builtin(("S",), _string_function(ty.INT, "len({})", "S"))
BUILTINS["LEFT"] = Builtin(("IN", "L"), _string_function(ty.STRING, "_left(_ok, {}, {})", "SI"))
BUILTINS["RIGHT"] = Builtin(("IN", "L"), _string_function(ty.STRING, "_right(_ok, {}, {})", "SI"))
BUILTINS["MID"] = Builtin(
    ("IN", "L", "P"), _string_function(ty.STRING, "_mid(_ok, {}, {}, {})", "SII")
)
BUILTINS["FIND"] = Builtin(("IN1", "IN2"), _string_function(ty.INT, "_find({}, {})", "SS"))
BUILTINS["INSERT"] = Builtin(
    ("IN1", "IN2", "P"), _string_function(ty.STRING, "_insert(_ok, {}, {}, {})", "SSI")
)
BUILTINS["DELETE"] = Builtin(
    ("IN", "L", "P"), _string_function(ty.STRING, "_delete(_ok, {}, {}, {})", "SII")
)
BUILTINS["REPLACE"] = Builtin(
    ("IN1", "IN2", "L", "P"), _string_function(ty.STRING, "_replace(_ok, {}, {}, {}, {})", "SSII")
)
BUILTINS["I_STRNG"] = Builtin(("I",), _to_string(ty.INT, 6, "_i_strng"))
BUILTINS["DI_STRNG"] = Builtin(("I",), _to_string(ty.DINT, 11, "_i_strng"))
BUILTINS["R_STRNG"] = Builtin(("IN",), _to_string(ty.REAL, 14, "_r_strng"))
BUILTINS["STRNG_I"] = Builtin(("S",), _string_function(ty.INT, "_strng_num(_ok, {}, 16)", "S"))
BUILTINS["STRNG_DI"] = Builtin(("S",), _string_function(ty.DINT, "_strng_num(_ok, {}, 32)", "S"))
BUILTINS["STRNG_R"] = Builtin(("S",), _string_function(ty.REAL, "_strng_r(_ok, {})", "S"))


def bind(
    name: str,
    params: tuple[str, ...],
    args: list[tuple[str, X, SourceLocation]],
    loc: SourceLocation,
) -> list[X]:
    """The actual values of a function's parameters in order (E230 unknown or twice,
    E231 missing): all by position, or all by name."""
    variadic = params[-1] == "*"
    fixed = params[:-1] if variadic else params
    if all(not n for n, _, _ in args):
        if len(args) < len(fixed) or (len(args) > len(fixed) and not variadic):
            raise Problem("E231", f"{name} takes {len(fixed)} parameter(s), not {len(args)}", loc)
        return [x for _, x, _ in args]
    got: dict[str, X] = {}
    for pname, x, where in args:
        key = pname.upper()
        known = key in fixed or (variadic and key.startswith("IN") and key[2:].isdigit())
        if not pname or not known or key in got:
            raise Problem(
                "E230", f"{name}: parameter {pname or '(unnamed)'} is unknown or twice", where
            )
        got[key] = x
    missing = [p for p in fixed if p not in got]
    if missing:
        raise Problem("E231", f"{name}: parameter {', '.join(missing)} missing", loc)
    extra = sorted((k for k in got if k not in fixed), key=lambda k: int(k[2:] or 0))
    return [got[p] for p in fixed] + [got[k] for k in extra]
