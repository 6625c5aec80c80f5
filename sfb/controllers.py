"""What the process-control blocks SFB41 CONT_C, SFB42 CONT_S and SFB43 PULSEGEN share
(docs/runtime.md, "Process control: CONT_C, CONT_S, PULSEGEN"; Siemens, *System Software for
S7-300/400, System and Standard Functions*, chapters "SFB 41/FB 41 CONT_C", "SFB 42/FB 42
CONT_S" and "SFB 43/FB 43 PULSEGEN").

The blocks run on their CYCLE pin, never on a clock: a call is one sampling step of CYCLE
(TIME, ms). Each block is a state object holding the instance DB's static variables and a
step ``block(inputs) -> outputs``, where the inputs and outputs are records named and ordered
as the catalogue's pins (``sfb.catalogue``; a test keeps them equal). ``declare`` makes the
engine SFB: its instance DB holds the pins with Siemens' initial values and the state as
``STATE``, so an input a call leaves out keeps its last value, as in S7.

Shared rules:

- process value: ``PV_IN``, or with ``PVPER_ON`` the I/O word ``PV_PER`` (an INT,
  27648 = 100 %) as ``PV_PER * 100 / 27648 * PV_FAC + PV_OFF`` (the CRP_IN and PV_NORM
  functions of the manual: the factor and offset scale only the I/O value);
- error: ``SP_INT - PV`` through the dead band: inside ``±DEADB_W`` it is 0, outside it is
  moved towards 0 by ``DEADB_W`` (so it has no step at the band's edge). A negative width is
  taken as 0 (the manual only permits ``DEADB_W >= 0``).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import asdict, fields
from typing import TYPE_CHECKING, Any, NamedTuple, Protocol, Self, cast

from s7graph.engine import blocks
from s7graph.sfb.catalogue import engine_sections, lookup

if TYPE_CHECKING:
    from s7graph.engine.context import CallContext

PER_FULL = 27648
"""The I/O value of 100 % (an analog module's nominal range)."""

MS_MIN = 1
"""The smallest sampling time, ms: a CYCLE below it is taken as 1 ms (manual: CYCLE >= 1 ms)."""


def signed16(word: int) -> int:
    """A WORD read as the INT an analog value is (``W#16#9400`` -> -27648)."""
    word = int(word) & 0xFFFF
    return word - 0x10000 if word & 0x8000 else word


def as_word(value: int) -> int:
    """An INT as the WORD it is stored in (-27648 -> ``W#16#9400``)."""
    return int(value) & 0xFFFF


def process_value(pvper_on: bool, pv_in: float, pv_per: int, fac: float, off: float) -> float:
    """PV: ``PV_IN``, or the I/O word scaled to % and normalised by PV_FAC/PV_OFF."""
    if not pvper_on:
        return float(pv_in)
    return signed16(pv_per) * 100.0 / PER_FULL * fac + off


def dead_band(er: float, width: float) -> float:
    """ER after the dead band: 0 within ``±width``, else ``er`` moved towards 0 by ``width``."""
    width = max(0.0, width)
    if er > width:
        return er - width
    if er < -width:
        return er + width
    return 0.0


def seconds(ms: int) -> float:
    """A TIME (ms) in seconds."""
    return int(ms) / 1000.0


class Stateful:
    """The state objects' persistence: ``to_state``/``from_state`` as the instance DB's
    OBJECT needs (``engine.blocks``); fields no longer declared are ignored."""

    __slots__ = ()

    def to_state(self) -> dict[str, object]:
        return asdict(cast(Any, self))

    def initialise(self) -> None:
        """Every static to its initial value (COM_RST)."""
        fresh = type(self)()
        for f in fields(cast(Any, self)):
            setattr(self, f.name, getattr(fresh, f.name))

    @classmethod
    def from_state(cls, data: Mapping[str, object]) -> Self:
        obj = cls()
        names = {f.name for f in fields(cast(Any, obj))}
        for name, value in data.items():
            if name in names:
                setattr(obj, name, value)
        return obj


class _Step(Protocol):
    def __call__(self, p: Any, /) -> NamedTuple: ...


def declare(name: str, state: type[_Step], inputs: type[Any]) -> blocks.FB:
    """The engine SFB of catalogue block ``name``: each call builds ``inputs`` from the
    instance DB's input pins, steps ``state`` (the ``STATE`` static) and writes the outputs
    back to the output pins."""
    entry = lookup(name)
    sections, _ = engine_sections(entry)
    names = tuple(p.name for p in entry.inputs)

    def body(ctx: CallContext, idb: blocks.InstanceDB) -> None:
        v = idb.values
        block = v["STATE"]
        assert isinstance(block, state)
        v.update(block(inputs(**{n: v[n] for n in names}))._asdict())

    body.__doc__ = f"{entry.key} {entry.name}: {state.__doc__}"
    stat = {"STATE": (blocks.OBJECT, state)}
    return blocks.sfb(entry.number, entry.name, STAT=stat, **sections)(body)
