"""Forcing: the CPU's force table, as STEP 7's "Force Values" keeps it (docs/runtime.md, "When a
scan hangs or fails").

A force job holds an input (I), output (Q) or flag (M) — a bit, byte, word or double word —
at a value until it is deleted (``unforce``), whatever the modules or the program say.
``FORCE_POINTS`` is the one table of where in the scan each area's forces are written:

- **I**: into the process-image input table right after it is read from the module side
  (``Cpu.update_pii``, every cycle, and SFC26 UPDAT_PI): the program reads the force value;
- **Q**: into the process-image output table right before it is written to the module side
  (``Cpu.update_piq``, and SFC27 UPDAT_PO): the modules get the force value whatever the
  program wrote;
- **M**: into the flags at the start of the cycle, before OB1 — as an S7-400 forces bit
  memory (an S7-300 cannot force M; S7-1500 forces only peripheral I/O).

Between two such points the program may overwrite a forced I or M and then reads its own
write until the next point (S7-300's "forcing is cyclic modifying"); an S7-400 would keep
the force value against every write. Outside RUN the modules' outputs stay 0, forced or not.

The table is pure data on the CPU (no clock, no threads): ``ForceTable.add``/``remove``/
``clear`` change it (at a scan boundary), ``plan(area)`` is what the scan applies, and
``snapshot``/``restore`` carry it through the state file — a force job outlives a restart
and a power cycle, as on S7; a memory reset deletes it. At most ``MAX_FORCES`` jobs (an
S7-400's 256); two jobs may not share a bit (``MW10`` and ``M10.1``): unforce one first.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from enum import StrEnum
from typing import TYPE_CHECKING, Any, Final

from s7graph.engine.address import Address, Area, Width, parse_address
from s7graph.engine.datatypes import encode, type_of
from s7graph.engine.errors import LiteralError, S7Error, SymbolError, TypeMismatch
from s7graph.engine.literals import format_literal, parse_literal
from s7graph.engine.symbols import default_type

if TYPE_CHECKING:
    from s7graph.engine.memory import Memory

__all__ = [
    "FORCE_POINTS",
    "MAX_FORCES",
    "Force",
    "ForceError",
    "ForcePoint",
    "ForceTable",
    "apply_plan",
    "bit_masks",
    "encode_value",
    "force_target",
    "make_force",
    "resolve_operand",
]

MAX_FORCES: Final = 256
"""Force jobs one CPU holds at most (S7-400; an S7-300 holds 10)."""


class ForcePoint(StrEnum):
    """Where in the scan a force value is written."""

    AFTER_PII = "after the process-image inputs are read from the modules"
    BEFORE_PIQ = "before the process-image outputs are written to the modules"
    CYCLE_START = "at the start of the cycle, before OB1"


FORCE_POINTS: Final[dict[Area, ForcePoint]] = {
    Area.I: ForcePoint.AFTER_PII,
    Area.Q: ForcePoint.BEFORE_PIQ,
    Area.M: ForcePoint.CYCLE_START,
}
"""The areas that can be forced, and where the scan writes their force values."""

_WIDTH_NAME: Final = {
    Width.BIT: "bit",
    Width.BYTE: "byte",
    Width.WORD: "word",
    Width.DWORD: "double word",
}
_UNSIGNED: Final = frozenset({"BOOL", "BYTE", "WORD", "DWORD"})
_PLAIN: Final = frozenset({"BOOL", "INT", "DINT", "REAL"})
"""Types of the literals that are plain numbers or TRUE/FALSE: they fit any width they fit."""
Plan = tuple[tuple[int, int, int], ...]
"""Per forced byte of an area: (byte, mask of the bits kept, the forced bits)."""


class ForceError(S7Error):
    """A force job refused: unknown address, an area that cannot be forced, a value that
    does not fit, an overlap, a full table; the message names the problem."""


@dataclass(frozen=True, slots=True)
class Force:
    """One force job: ``address`` held at ``value`` (its raw bits, unsigned; a bit 0/1).

    ``shown`` is the value as the engineer reads it (``TRUE``, ``-5``, ``W#16#00FF``,
    ``T#5S``), ``symbol`` the name it was given by ("" for an absolute address), ``user``
    who forced it."""

    address: Address
    value: int
    shown: str
    symbol: str = ""
    user: str = ""

    def __str__(self) -> str:
        name = f'"{self.symbol}" ({self.address})' if self.symbol else str(self.address)
        return f"{name} = {self.shown}"

    def masks(self) -> dict[int, tuple[int, int]]:
        """Byte → (mask of the forced bits, the forced bits) of this job."""
        return bit_masks(self.address, self.value)

    def to_json(self) -> dict[str, Any]:
        return {
            "address": str(self.address),
            "value": self.value,
            "shown": self.shown,
            "symbol": self.symbol,
            "user": self.user,
        }

    @classmethod
    def from_json(cls, data: object) -> Force:
        """A job as ``to_json`` wrote it; ValueError when it is not one."""
        if not isinstance(data, dict):
            raise ValueError(f"a force job is an object, not {type(data).__name__}")
        address = parse_address(str(data.get("address", "")))
        if address.area not in FORCE_POINTS:
            raise ValueError(f"{address} cannot be forced")
        value = data.get("value")
        if isinstance(value, bool) or not isinstance(value, int):
            raise ValueError(f"the value of {address} is {value!r}")
        if not 0 <= value < 1 << address.width:
            raise ValueError(f"{value} does not fit {address}")
        texts = [data.get(k, "") for k in ("shown", "symbol", "user")]
        if not all(isinstance(t, str) and len(t) <= 256 for t in texts):
            raise ValueError(f"the texts of the force job {address} are not short strings")
        return cls(address, value, *texts)


def bit_masks(address: Address, value: int) -> dict[int, tuple[int, int]]:
    """Byte → (mask of the bits ``address`` covers, those bits as ``value`` sets them;
    ``value`` the raw bits of ``address``)."""
    if address.width is Width.BIT:
        return {address.byte: (1 << address.bit, (value & 1) << address.bit)}
    data = value.to_bytes(address.size, "big")
    return {address.byte + k: (0xFF, b) for k, b in enumerate(data)}


def make_force(mem: Memory, target: str | Address, value: object, *, user: str = "") -> Force:
    """The force job of ``target`` (an address or a symbol of ``mem.symbols``) at
    ``value``: a bool for a bit; an int (unsigned, or negative as INT/DINT), a float (REAL,
    a double word) or an S7 literal text (``16#00FF``, ``T#5S``, ``TRUE``) otherwise; a
    symbol's value in its declared type. ForceError names what is wrong."""
    address, type_name, symbol = force_target(mem, target)
    name = f'"{symbol}" ({address})' if symbol else str(address)
    raw, shown = encode_value(address, type_name, name, value)
    return Force(address, raw, shown, symbol, user)


def force_target(mem: Memory, target: str | Address) -> tuple[Address, str, str]:
    """(address, type, symbol name or "") of a force target: an address or a symbol of
    ``mem.symbols`` in an area that can be forced, inside it; ForceError otherwise."""
    address, type_name, symbol = resolve_operand(mem, target)
    if address.area not in FORCE_POINTS:
        areas = ", ".join(str(a) for a in FORCE_POINTS)
        raise ForceError(f"{address} cannot be forced: only {areas} can (inputs, outputs, flags)")
    size = len(mem.area_bytes(address.area))
    if address.byte + address.size > size:
        raise ForceError(f"{address} is outside the {address.area} area ({size} bytes)")
    return address, type_name, symbol


def resolve_operand(
    mem: Memory, target: str | Address, error: type[S7Error] = ForceError
) -> tuple[Address, str, str]:
    """(address, type, symbol name or "") of an address or a symbol of ``mem.symbols``;
    ``error`` (ForceError) names what is not one."""
    if isinstance(target, Address):
        return target, default_type(target), ""
    text = target.strip()
    if not text or len(text) > 64:
        raise error(f"not an address or symbol: {text[:64]!r}")
    table = mem.symbols
    sym = table.lookup(text) if table is not None else None
    if sym is not None:
        return sym.address, sym.type, sym.name
    try:
        if text.startswith('"'):
            raise SymbolError(f"unknown symbol {text}")
        address = parse_address(text)
    except S7Error as exc:  # said once: "bad address 'Nope': not an S7 address or a symbol"
        said = exc.message.removesuffix(": not an S7 address").removesuffix("not an S7 address")
        raise error(f"{said}{': ' if said else ''}not an S7 address or a symbol") from None
    return address, default_type(address), ""


def encode_value(
    address: Address,
    type_name: str,
    name: str,
    value: object,
    verb: str = "force",
    error: type[S7Error] = ForceError,
) -> tuple[int, str]:
    """(raw bits, the value as shown) of ``value`` at ``address`` of type ``type_name``;
    ``error`` (ForceError) names what does not fit, for ``verb`` ("force", "modify")."""
    width = address.width
    what = f"the {_WIDTH_NAME[width] if type_name in _UNSIGNED else type_name} {name}"
    if value is None:
        raise error(f"no value to {verb} {name} to")
    if isinstance(value, str):
        try:
            literal_type, value = parse_literal(value)
        except LiteralError as exc:
            raise error(f"{exc.message} (to {verb} {what})") from None
        if literal_type == "STRING" and type_name == "CHAR" and len(str(value)) == 1:
            literal_type = "CHAR"  # 'a': one character in quotes is a CHAR literal in S7
        if literal_type not in _PLAIN:  # a typed literal: B#16#.., W#16#.., T#.., S5T#..
            bits = type_of(literal_type).size_bits
            fits = bits == width if type_name in _UNSIGNED else literal_type == type_name
            if not fits:
                raise error(
                    f"{format_literal(literal_type, value)} is a {literal_type} "
                    f"({bits} bits), not a value for {what}"
                )
            return _typed(address, literal_type, value, what, verb, error)
    if width is Width.BIT:
        if isinstance(value, bool) or (isinstance(value, int) and value in (0, 1)):
            return int(value), "TRUE" if value else "FALSE"
        raise error(f"{value!r} does not fit {what}: {verb} TRUE or FALSE")
    if isinstance(value, bool):
        raise error(f"{what} takes a number, not {'TRUE' if value else 'FALSE'}")
    if type_name not in _UNSIGNED:
        return _typed(address, type_name, value, what, verb, error)
    if isinstance(value, float):
        if width is not Width.DWORD:
            raise error(f"{value!r} is a REAL (32 bits), not a value for {what}")
        return _typed(address, "REAL", value, what, verb, error)
    if not isinstance(value, int):
        raise error(f"{value!r} is no value for {what}")
    lo, hi = -(1 << (width - 1)), (1 << width) - 1
    if not lo <= value <= hi:
        raise error(f"{value} does not fit {what} (0..{hi}, or {lo}..{-lo - 1})")
    return value & hi, str(value)


def _typed(
    address: Address,
    type_name: str,
    value: object,
    what: str,
    verb: str,
    error: type[S7Error],
) -> tuple[int, str]:
    try:
        data = encode(type_name, value)
        shown = format_literal(type_name, value)
    except TypeMismatch as exc:
        raise error(f"{exc.message} (to {verb} {what})") from None
    if len(data) != address.size:
        raise error(f"a {type_name} is no value for {what}")
    return int.from_bytes(data, "big"), shown


def apply_plan(buf: bytearray, plan: Plan) -> None:
    """Write the forced bits of ``plan`` into ``buf`` (an area's bytes)."""
    for byte, keep, bits in plan:
        buf[byte] = buf[byte] & keep | bits


class ForceTable:
    """The force jobs of one CPU by address, and per area the plan the scan applies."""

    __slots__ = ("_forces", "_plans", "version")

    def __init__(self) -> None:
        self._forces: dict[Address, Force] = {}
        self._plans: dict[Area, Plan] = {}
        self.version = 0
        """Counts the changes (a view lists the table again when it moved)."""

    def __len__(self) -> int:
        return len(self._forces)

    def __iter__(self) -> Iterator[Force]:
        """The jobs in area order (I, Q, M), then by byte and bit."""
        order = list(FORCE_POINTS)

        def key(f: Force) -> tuple[int, int, int, int]:
            a = f.address
            return order.index(a.area), a.byte, a.bit, a.width

        return iter(sorted(self._forces.values(), key=key))

    def get(self, address: Address) -> Force | None:
        return self._forces.get(address)

    def plan(self, area: Area) -> Plan:
        """What the scan writes into ``area`` (empty: nothing forced there)."""
        return self._plans.get(area, ())

    def add(self, force: Force) -> Force | None:
        """Add ``force`` (replacing a job of the same address, which it returns); a job
        sharing a bit with another one, or one more than ``MAX_FORCES``, is refused."""
        address = force.address
        old = self._forces.get(address)
        if old is None:
            if len(self._forces) >= MAX_FORCES:
                raise ForceError(f"the force table is full ({MAX_FORCES} jobs): unforce one first")
            other = self.holding(address)
            if other is not None:
                raise ForceError(
                    f"{address} overlaps the force job {other}: unforce {other.address} first"
                )
        self._forces[address] = force
        self._changed(address.area)
        return old

    def holding(self, address: Address) -> Force | None:
        """The job that holds a bit of ``address``, if any (an address of an area that
        cannot be forced: None)."""
        if address.area not in FORCE_POINTS:
            return None
        mine = bit_masks(address, 0)
        for other in self._forces.values():
            if other.address.area is address.area and any(
                byte in mine and mine[byte][0] & mask for byte, (mask, _) in other.masks().items()
            ):
                return other
        return None

    def remove(self, address: Address) -> Force:
        """Delete the job of ``address``; ForceError when there is none."""
        force = self._forces.pop(address, None)
        if force is None:
            raise ForceError(f"{address} is not forced")
        self._changed(address.area)
        return force

    def clear(self) -> list[Force]:
        """Delete every job; returns them."""
        gone = list(self)
        self._forces.clear()
        self._plans.clear()
        if gone:
            self.version += 1
        return gone

    def _changed(self, area: Area) -> None:
        self.version += 1
        merged: dict[int, tuple[int, int]] = {}
        for f in self._forces.values():
            if f.address.area is area:
                for byte, (mask, bits) in f.masks().items():
                    m, b = merged.get(byte, (0, 0))
                    merged[byte] = (m | mask, b | bits)
        plan = tuple((byte, ~mask & 0xFF, bits) for byte, (mask, bits) in sorted(merged.items()))
        if plan:
            self._plans[area] = plan
        else:
            self._plans.pop(area, None)

    def snapshot(self) -> list[dict[str, Any]]:
        """The jobs as JSON-able data, for the state file."""
        return [f.to_json() for f in self]

    def restore(self, data: object, mem: Memory) -> None:
        """Replace the table with a ``snapshot()``; ValueError for a malformed one (one that
        does not fit ``mem``'s areas included)."""
        if not isinstance(data, list):
            raise ValueError(f"the force table is a list, not {type(data).__name__}")
        forces = [Force.from_json(item) for item in data]
        self.clear()
        for force in forces:
            a = force.address
            if a.byte + a.size > len(mem.area_bytes(a.area)):
                raise ValueError(f"{a} is outside the {a.area} area")
            try:
                self.add(force)
            except ForceError as exc:
                raise ValueError(exc.message) from None
