"""IEC counters SFB0 CTU, SFB1 CTD, SFB2 CTUD (docs/runtime.md, "The block runtime"; STEP7
comprehensive guide vol. 2, ch. 12).

Counters count INT on **rising edges** of CU/CD (the previous input level is kept in the
instance), saturate at 32767 / -32768, and are pure functions of their instance data and
inputs. Priorities: R over LOAD over counting; a simultaneous CU and CD edge in CTUD
leaves CV unchanged.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING, NamedTuple, Self, cast

from s7graph.engine import blocks
from s7graph.sfb.catalogue import engine_sections, lookup

if TYPE_CHECKING:
    from s7graph.engine.context import CallContext

INT_MIN = -32768
INT_MAX = 32767


class CounterOut(NamedTuple):
    """CTU/CTD result: ``Q`` and the count ``CV``."""

    q: bool
    cv: int


class UpDownOut(NamedTuple):
    """CTUD result: ``QU`` (CV >= PV), ``QD`` (CV <= 0) and ``CV``."""

    qu: bool
    qd: bool
    cv: int


def _int(value: int) -> int:
    return max(INT_MIN, min(INT_MAX, int(value)))


@dataclass(slots=True)
class _IecCounter:
    """Instance data: latched inputs, edge memories and outputs (mirrors the instance DB)."""

    CU: bool = False
    CD: bool = False
    R: bool = False
    LOAD: bool = False
    PV: int = 0
    CV: int = 0

    def to_state(self) -> dict[str, object]:
        return asdict(self)

    @classmethod
    def from_state(cls, data: dict[str, object]) -> Self:
        obj = cls()
        for name, value in data.items():
            if name in obj.__dataclass_fields__:
                setattr(obj, name, value)
        return obj


@dataclass(slots=True)
class CTU(_IecCounter):
    """SFB0 CTU: CV + 1 on a rising CU up to 32767; R = 1 sets CV = 0; Q = (CV >= PV)."""

    Q: bool = False

    def __call__(self, CU: bool, R: bool, PV: int) -> CounterOut:
        rising = CU and not self.CU
        self.CU, self.R, self.PV = bool(CU), bool(R), _int(PV)
        if self.R:
            self.CV = 0
        elif rising and self.CV < INT_MAX:
            self.CV += 1
        self.Q = self.CV >= self.PV
        return CounterOut(self.Q, self.CV)


@dataclass(slots=True)
class CTD(_IecCounter):
    """SFB1 CTD: LOAD = 1 sets CV = PV (level); else CV - 1 on a rising CD down to -32768;
    Q = (CV <= 0)."""

    Q: bool = False

    def __call__(self, CD: bool, LOAD: bool, PV: int) -> CounterOut:
        rising = CD and not self.CD
        self.CD, self.LOAD, self.PV = bool(CD), bool(LOAD), _int(PV)
        if self.LOAD:
            self.CV = self.PV
        elif rising and self.CV > INT_MIN:
            self.CV -= 1
        self.Q = self.CV <= 0
        return CounterOut(self.Q, self.CV)


@dataclass(slots=True)
class CTUD(_IecCounter):
    """SFB2 CTUD: R (CV := 0) over LOAD (CV := PV) over counting; QU = CV >= PV, QD = CV <= 0."""

    QU: bool = False
    QD: bool = False

    def __call__(self, CU: bool, CD: bool, R: bool, LOAD: bool, PV: int) -> UpDownOut:
        up = CU and not self.CU
        down = CD and not self.CD
        self.CU, self.CD, self.R, self.LOAD, self.PV = (
            bool(CU),
            bool(CD),
            bool(R),
            bool(LOAD),
            _int(PV),
        )
        if self.R:
            self.CV = 0
        elif self.LOAD:
            self.CV = self.PV
        elif up and not down and self.CV < INT_MAX:
            self.CV += 1
        elif down and not up and self.CV > INT_MIN:
            self.CV -= 1
        self.QU, self.QD = self.CV >= self.PV, self.CV <= 0
        return UpDownOut(self.QU, self.QD, self.CV)


# --- Engine adapter: SFB0/1/2 as engine SFBs (pins from the catalogue + STATE) ------------


def _declare(cls: type[CTU] | type[CTD] | type[CTUD]) -> blocks.FB:
    entry = lookup(cls.__name__)
    sections, _ = engine_sections(entry)

    def body(ctx: CallContext, idb: blocks.InstanceDB) -> None:
        state = idb.values["STATE"]
        assert isinstance(state, cls)
        v = idb.values
        pv = cast(int, v["PV"])
        if isinstance(state, CTU):
            v["Q"], v["CV"] = state(v["CU"] is True, v["R"] is True, pv)
        elif isinstance(state, CTD):
            v["Q"], v["CV"] = state(v["CD"] is True, v["LOAD"] is True, pv)
        else:
            args = (v["CU"] is True, v["CD"] is True, v["R"] is True, v["LOAD"] is True, pv)
            v["QU"], v["QD"], v["CV"] = state(*args)

    body.__doc__ = f"{entry.key} {entry.name}: {cls.__doc__}"
    stat = {"STATE": (blocks.OBJECT, cls)}
    return blocks.sfb(entry.number, entry.name, STAT=stat, **sections)(body)


SFB0 = _declare(CTU)
SFB1 = _declare(CTD)
SFB2 = _declare(CTUD)
BLOCKS = (SFB0, SFB1, SFB2)
