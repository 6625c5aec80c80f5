"""User and system blocks: OB, FB, FC, SFB, SFC, DB and instance DBs (docs/runtime.md, "Programs of
blocks in Python").

A decorator declares a block's interface (Siemens' Program Design for S7-300/400, ch. 2, Table
2-2)::

    @fb(1, IN={"start": "BOOL"}, OUT={"busy": "BOOL"}, STAT={"n": ("INT", 0)})
    def motor(ctx, db): ...

An FB keeps IN, OUT, IN_OUT and STAT in an ``InstanceDB`` (TEMP never); an FC has no
memory, STAT is refused and its locals take no initial values. A STAT of type ``OBJECT``
holds any object with ``to_state()``/``from_state()`` (e.g. a GraphFB state); a STAT whose
value is an FB is a multi-instance stored inside the caller's instance DB.
"""

from __future__ import annotations

import copy
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from datetime import date, datetime
from enum import StrEnum
from typing import Any, Protocol, runtime_checkable

from s7graph.engine.datatypes import DT_MIN, Layout, check_value, decode, type_of
from s7graph.engine.errors import BlockError, TypeMismatch

OBJECT = "OBJECT"
"""Type of a STAT holding a Python object with ``to_state()``/``from_state()``."""


class Decl(StrEnum):
    """Declaration types of block variables (Siemens' Program Design for S7-300/400, table 2-2)."""

    IN = "IN"
    OUT = "OUT"
    IN_OUT = "IN_OUT"
    STAT = "STAT"
    TEMP = "TEMP"


class BlockKind(StrEnum):
    """Kinds of blocks; SFB/SFC belong to the operating system and need no download."""

    OB = "OB"
    FB = "FB"
    FC = "FC"
    SFB = "SFB"
    SFC = "SFC"
    DB = "DB"


@dataclass(frozen=True, slots=True)
class Var:
    """One declared variable of a block interface."""

    name: str
    type: str
    decl: Decl
    init: object = None
    comment: str = ""


# A body's first argument is its ``engine.context.CallContext``; typed ``Any`` here because the
# call context is built on the blocks (blocks never import the context).
FBBody = Callable[[Any, "InstanceDB"], None]
FCBody = Callable[[Any, dict[str, object]], object]
OBBody = Callable[[Any], None]
SectionSpec = Mapping[str, "str | tuple[Any, ...] | Var | FB"]

_STRINGY = ("STRING", "CHAR", OBJECT)
_CELL_TYPES = {"TIMER": "TIMER", "COUNTER": "COUNTER"}


def is_stringy(type_name: str) -> bool:
    """True if a ``str`` actual parameter is a value of this type, not an operand address."""
    return type_name.upper().startswith(_STRINGY)


def _is_multi(var: Var) -> bool:
    return isinstance(var.init, FB) and var.decl is Decl.STAT


def _check_type(owner: str, var: Var) -> None:
    if var.type == OBJECT or _is_multi(var) or var.type.upper().startswith(("ARRAY", "STRUCT")):
        return
    try:
        type_of(var.type)
    except TypeMismatch as exc:
        raise BlockError(f"{owner}: variable {var.name!r}: {exc.message}") from None


def _params(label: str, kind: BlockKind, interface: tuple[Var, ...]) -> dict[str, tuple[Decl, str]]:
    """The checked interface's stored parameters by name (all but TEMP): ``(decl, type)``;
    the parameter types TIMER and COUNTER in capitals (the call passes their number)."""
    _check_interface(label, kind, interface)
    return {
        v.name: (v.decl, _CELL_TYPES.get(v.type.upper(), v.type))
        for v in interface
        if v.decl is not Decl.TEMP
    }


def _check_interface(owner: str, kind: BlockKind, interface: tuple[Var, ...]) -> None:
    seen: set[str] = set()
    for var in interface:
        if var.name in seen:
            raise BlockError(f"{owner}: variable {var.name!r} declared twice")
        seen.add(var.name)
        _check_type(owner, var)
        if var.decl is Decl.STAT and kind not in (BlockKind.FB, BlockKind.SFB):
            raise BlockError(f"{owner}: STAT variables exist only in FBs ({var.name!r})")
        if var.decl is Decl.TEMP and var.init is not None:
            raise BlockError(f"{owner}: TEMP variable {var.name!r} cannot have an initial value")
        if kind in (BlockKind.FC, BlockKind.SFC) and var.init is not None:
            raise BlockError(f"{owner}: FC locals cannot have initial values ({var.name!r})")
        if var.init is not None and var.type != OBJECT and not _is_multi(var):
            try:
                check_value(var.type, var.init)
            except TypeMismatch as exc:
                raise BlockError(f"{owner}: initial value of {var.name!r}: {exc.message}") from None


@runtime_checkable
class StateFormat(Protocol):
    """How the data of an FB's instance DBs is recognised on disk (a GRAPH FB: by its
    compiled chart, ``sequencer/change/carry.py``); ``engine/persistence.py`` reads it.

    ``fingerprint`` names what the data describes; ``shape()`` is a JSON-able description
    saved beside the data; ``adapt(shape, data)`` carries data written under another
    fingerprint (described by its saved ``shape``) over to this one and returns it with
    notes of what it could not keep — ValueError/KeyError/TypeError when it cannot."""

    @property
    def fingerprint(self) -> str: ...

    def shape(self) -> object: ...

    def adapt(
        self, shape: object, data: dict[str, object]
    ) -> tuple[dict[str, object], list[str]]: ...


@dataclass(frozen=True, slots=True)
class FB:
    """A function block (or SFB): its interface and a body ``body(ctx, instance_db)``;
    ``state_format`` (optional) recognises its instance data on disk."""

    number: int
    name: str
    interface: tuple[Var, ...]
    body: FBBody
    kind: BlockKind = BlockKind.FB
    state_format: StateFormat | None = field(default=None, repr=False, compare=False)
    params: dict[str, tuple[Decl, str]] = field(
        init=False, repr=False, compare=False, hash=False, default_factory=dict
    )
    out_names: tuple[str, ...] = field(init=False, repr=False, compare=False, default=())
    stored: tuple[Var, ...] = field(init=False, repr=False, compare=False, default=())
    """The variables an instance DB stores (all but TEMP), in declaration order."""
    objects: tuple[str, ...] = field(init=False, repr=False, compare=False, default=())
    """The names of the stored OBJECT variables (a sequencer's state)."""

    def __post_init__(self) -> None:
        object.__setattr__(self, "params", _params(self.label, self.kind, self.interface))
        outs = tuple(v.name for v in self.interface if v.decl in (Decl.OUT, Decl.IN_OUT))
        object.__setattr__(self, "out_names", outs)
        stored = tuple(v for v in self.interface if v.decl is not Decl.TEMP)
        object.__setattr__(self, "stored", stored)
        object.__setattr__(self, "objects", tuple(v.name for v in stored if v.type == OBJECT))

    @property
    def label(self) -> str:
        return f"{self.kind}{self.number}"

    def var(self, name: str) -> Var:
        """The declared variable ``name``; BlockError if there is none."""
        for var in self.interface:
            if var.name == name:
                return var
        raise BlockError(f"{self.label} has no variable {name!r}")

    def __hash__(self) -> int:
        return hash((self.kind, self.number, self.name))


@dataclass(frozen=True, slots=True)
class FC:
    """A function (or SFC): ``body(ctx, params) -> RET_VAL``; every parameter must be supplied."""

    number: int
    name: str
    interface: tuple[Var, ...]
    body: FCBody
    kind: BlockKind = BlockKind.FC
    ret_type: str | None = None
    params: dict[str, tuple[Decl, str]] = field(
        init=False, repr=False, compare=False, hash=False, default_factory=dict
    )

    def __post_init__(self) -> None:
        object.__setattr__(self, "params", _params(self.label, self.kind, self.interface))

    @property
    def label(self) -> str:
        return f"{self.kind}{self.number}"

    def __hash__(self) -> int:
        return hash((self.kind, self.number, self.name))


@dataclass(frozen=True, slots=True)
class OB:
    """An organization block, called only by the CPU: ``body(ctx)`` (Siemens' Program Design for
    S7-300/400, ch. 3-4)."""

    number: int
    name: str
    body: OBBody

    @property
    def label(self) -> str:
        return f"OB{self.number}"

    @property
    def kind(self) -> BlockKind:
        return BlockKind.OB


@dataclass(frozen=True, slots=True)
class DB:
    """A global data block as downloaded: size and initial bytes (its load-memory image),
    and ``layout``, its variables by name when its structure was declared (an S7-SCL
    ``DATA_BLOCK``), so a watch can read ``DB20.avg``."""

    number: int
    size: int
    init: bytes | None = None
    retain: bool = True
    name: str = ""
    layout: Layout | None = field(default=None, hash=False)

    @property
    def label(self) -> str:
        return f"DB{self.number}"

    @property
    def kind(self) -> BlockKind:
        return BlockKind.DB


Block = OB | FB | FC | DB


# ---- instance DBs ------------------------------------------------------------------------


def default_value(type_name: str) -> object:
    """The zero value of an S7 type (FALSE, 0, 0.0, '', D#1990-01-01, DT#1990-01-01-0:0)."""
    upper = type_name.upper()
    if upper in ("DATE_AND_TIME", "DT"):
        return DT_MIN
    if upper.startswith("STRING"):
        return ""
    if upper == OBJECT or upper.startswith(("ARRAY", "STRUCT")):
        return None
    spec = type_of(type_name)
    return decode(spec.name, bytes(spec.size))


def _initial(var: Var, number: int) -> object:
    if _is_multi(var):
        assert isinstance(var.init, FB)
        return InstanceDB(number, var.init, name=var.name)
    if var.type == OBJECT:
        init = var.init
        if isinstance(init, type):
            return init()
        if init is not None and hasattr(init, "to_state"):
            return copy.deepcopy(init)
        return init() if callable(init) else init
    if var.init is None:
        return default_value(var.type)
    return check_value(var.type, var.init)


def _plain(var: Var) -> bool:
    """A variable of an elementary type (checked with ``check_value`` on a strict restore)."""
    upper = var.type.upper()
    return not (
        _is_multi(var) or upper == OBJECT or upper.startswith(("ARRAY", "STRUCT", "DATE", "DT"))
    )


_AS_IS = frozenset((bool, int, float, str, type(None)))
"""Value types a snapshot takes as they are (what ``_encode`` would return unchanged)."""


def _encode(var: Var, value: object, live: bool = False) -> object:
    if isinstance(value, InstanceDB):
        return value.snapshot(live=live)
    if var.type == OBJECT:
        take = (live and getattr(value, "state_view", None)) or getattr(value, "to_state", None)
        return take() if take is not None else value
    if isinstance(value, datetime | date):
        return value.isoformat()
    if isinstance(value, list):
        return copy.deepcopy(value)
    return value


def _decode(var: Var, current: object, data: object) -> object:
    if isinstance(current, InstanceDB):
        if isinstance(data, dict):
            current.restore(data)
        return current
    if var.type == OBJECT:
        holder: object = current if current is not None else var.init
        from_state = getattr(holder, "from_state", None)
        if from_state is None:
            return data
        restored = from_state(data)
        return current if restored is None else restored
    return from_stored(var.type, data)


def from_stored(type_name: str, data: object) -> object:
    """A value as a snapshot keeps it, in its type again: a DATE or DATE_AND_TIME kept as
    ISO text is a date (ValueError when the text is none); anything else as it is."""
    upper = type_name.upper()
    if isinstance(data, str) and upper == "DATE":
        return date.fromisoformat(data)
    if isinstance(data, str) and upper in ("DATE_AND_TIME", "DT"):
        return datetime.fromisoformat(data)
    return data


class InstanceDB:
    """Data of one FB instance: IN, OUT, IN_OUT, STAT by name (attribute or item access)."""

    __slots__ = ("fb", "name", "number", "presets", "values")

    number: int
    fb: FB
    name: str
    values: dict[str, object]
    presets: dict[str, Callable[[], object]]
    """This instance's own initial values, where they differ from the FB's (an S7-SCL
    ``DATA_BLOCK DB10 FB17 BEGIN x := 5;``): a function giving each, for ``reset``."""

    def __init__(self, number: int, fb: FB, *, name: str | None = None) -> None:
        object.__setattr__(self, "number", number)
        object.__setattr__(self, "fb", fb)
        object.__setattr__(self, "name", name if name is not None else f"DB{number}")
        object.__setattr__(self, "values", {})
        object.__setattr__(self, "presets", {})
        self.reset()

    def reset(self) -> None:
        """Every variable back to its initial value (cold restart): the instance's own
        (``presets``), else its FB's."""
        self.values.clear()
        for var in self.fb.interface:
            if var.decl is not Decl.TEMP:
                self.values[var.name] = _initial(var, self.number)
        for name, initial in self.presets.items():
            if name in self.values:
                self.values[name] = initial()

    def __getattr__(self, name: str) -> object:
        try:
            return object.__getattribute__(self, "values")[name]
        except KeyError:
            raise AttributeError(f"{self.fb.label} {self.name} has no variable {name!r}") from None

    def __setattr__(self, name: str, value: object) -> None:
        if name not in self.values:
            raise BlockError(f"{self.fb.label} {self.name} has no variable {name!r}")
        self.values[name] = value

    def __getitem__(self, name: str) -> object:
        try:
            return self.values[name]
        except KeyError:
            raise BlockError(f"{self.fb.label} {self.name} has no variable {name!r}") from None

    def __setitem__(self, name: str, value: object) -> None:
        self.__setattr__(name, value)

    def __contains__(self, name: object) -> bool:
        return name in self.values

    def __repr__(self) -> str:
        return f"InstanceDB({self.name} of {self.fb.label} {self.fb.name!r}: {self.values!r})"

    def snapshot(self, *, live: bool = False) -> dict[str, object]:
        """A JSON-ready copy of every stored value (OBJECT via ``to_state()``); ``live``:
        OBJECT values through ``state_view()`` where they have one, sharing their lists —
        to be encoded at once, never kept (the state file's staging)."""
        values = self.values
        out: dict[str, object] = {}
        for var in self.fb.stored:
            value = values[var.name]
            out[var.name] = value if type(value) in _AS_IS else _encode(var, value, live)
        return out

    def encode(self, var: Var) -> object:
        """The JSON-ready value of the declared variable ``var`` (as in ``snapshot()``)."""
        return _encode(var, self.values[var.name])

    def restore(self, data: Mapping[str, object], *, strict: bool = False) -> None:
        """Load a ``snapshot()``; names no longer declared are ignored, missing ones kept.

        ``strict`` (a state file): an undeclared name or a value that does not fit its
        type raises ValueError/TypeMismatch instead, and nothing is changed."""
        decoded: dict[str, object] = {}
        if strict:
            unknown = sorted(set(data) - {v.name for v in self.fb.interface})
            if unknown:
                raise ValueError(f"undeclared variable(s) {', '.join(unknown)}")
        for var in self.fb.interface:
            if var.decl is not Decl.TEMP and var.name in data:
                value = _decode(var, self.values[var.name], data[var.name])
                if strict and _plain(var):
                    value = check_value(var.type, value)
                decoded[var.name] = value
        self.values.update(decoded)


# ---- decorators -------------------------------------------------------------------------

_SECTIONS = {s.value: s for s in Decl}


def _vars(owner: str, sections: Mapping[str, SectionSpec | None]) -> tuple[Var, ...]:
    out: list[Var] = []
    for key, spec in sections.items():
        decl = _SECTIONS.get(key.upper())
        if decl is None:
            raise BlockError(f"{owner}: unknown declaration section {key!r}")
        for name, item in (spec or {}).items():
            out.append(_var(name, decl, item))
    return tuple(out)


def _var(name: str, decl: Decl, item: object) -> Var:
    if isinstance(item, Var):
        return item
    if isinstance(item, FB):
        return Var(name, item.label, decl, item)
    if isinstance(item, str):
        return Var(name, item, decl)
    if isinstance(item, tuple) and 1 <= len(item) <= 3 and isinstance(item[0], str):
        return Var(name, item[0], decl, *item[1:])
    raise BlockError(f"variable {name!r}: declare as 'TYPE', (TYPE, init[, comment]) or an FB")


def fb(
    number: int, name: str | None = None, *, kind: BlockKind = BlockKind.FB, **sections: Any
) -> Callable[[FBBody], FB]:
    """Declare an FB: ``@fb(1, IN={...}, OUT={...}, IN_OUT={...}, STAT={...}, TEMP={...})``."""

    def wrap(body: FBBody) -> FB:
        label = name or body.__name__
        return FB(number, label, _vars(f"{kind}{number}", sections), body, kind)

    return wrap


def sfb(number: int, name: str, **sections: Any) -> Callable[[FBBody], FB]:
    """Declare a system function block (needs an instance DB, no download)."""
    return fb(number, name, kind=BlockKind.SFB, **sections)


def fc(
    number: int,
    name: str | None = None,
    *,
    kind: BlockKind = BlockKind.FC,
    RET: str | None = None,
    **sections: Any,
) -> Callable[[FCBody], FC]:
    """Declare an FC: ``@fc(2, IN={...}, OUT={...}, RET='INT')``; the body returns RET_VAL."""

    def wrap(body: FCBody) -> FC:
        label = name or body.__name__
        return FC(number, label, _vars(f"{kind}{number}", sections), body, kind, RET)

    return wrap


def sfc(
    number: int, name: str, *, RET: str | None = None, **sections: Any
) -> Callable[[FCBody], FC]:
    """Declare a system function (SFC); like ``fc``."""
    return fc(number, name, kind=BlockKind.SFC, RET=RET, **sections)


def ob(number: int, name: str | None = None) -> Callable[[OBBody], OB]:
    """Declare an organization block: ``@ob(1)`` over ``def main(ctx): ...``."""

    def wrap(body: OBBody) -> OB:
        return OB(number, name or body.__name__, body)

    return wrap
