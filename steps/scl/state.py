"""How the instance DBs of an S7-SCL FB are recognised in a state file, and carried over by
name when the FB changed (docs/state-file.md; docs/scl.md, "On the command line").

The engine recognises an instance by its FB's interface — names, engine types and sections
— where an ARRAY or a STRUCT is one type, ``OBJECT``; an SCL FB's ``SclState`` names each
variable's full type instead (``ARRAY[1..5] OF INT``, a STRUCT's members, a multi-instance's
own fingerprint), so a changed bound or member is a change. Saved beside the data, its shape
(variable → type) lets ``adapt`` keep, by name, every variable whose type is the same and
report the others: dropped when no longer declared, at their initial values when new or of
another type.
"""

from __future__ import annotations

import hashlib
import json
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from s7graph.steps.scl import types as ty

__all__ = ["CarryPlan", "SclState", "carried", "type_text"]


def type_text(t: ty.SclType, fingerprints: dict[str, str]) -> str:
    """``t`` spelled out: a STRUCT with its members, a multi-instance with its FB's
    fingerprint (``fingerprints`` by label)."""
    if t.kind == "STRUCT":
        inner = "; ".join(f"{n} : {type_text(ft, fingerprints)}" for n, ft in t.fields)
        return f"STRUCT {inner} END_STRUCT"
    if t.kind == "ARRAY" and t.element is not None:
        dims = ", ".join(f"{lo}..{hi}" for lo, hi in t.dims)
        return f"ARRAY[{dims}] OF {type_text(t.element, fingerprints)}"
    if t.kind == "FB":
        return f"{t.name} {fingerprints.get(t.name, '')}".strip()
    return str(t)


@dataclass(frozen=True)
class SclState:
    """The ``state_format`` of an SCL FB: its stored variables' types, in order."""

    types: tuple[tuple[str, str], ...]

    @property
    def fingerprint(self) -> str:
        text = json.dumps(self.types, separators=(",", ":"))
        return "scl:" + hashlib.sha256(text.encode()).hexdigest()[:16]

    def shape(self) -> object:
        return dict(self.types)

    def adapt(self, shape: object, data: dict[str, object]) -> tuple[dict[str, object], list[str]]:
        """``data`` saved under ``shape`` (variable → type; None: saved before SCL FBs had
        one, when only elementary values are known to fit) kept by name where the type is
        the same; the notes say what was not."""
        now = dict(self.types)
        before = shape if isinstance(shape, dict) else None
        kept: dict[str, object] = {}
        dropped, changed = [], []
        for name, value in data.items():
            if name not in now:
                dropped.append(name)
            elif _same(before, name, now[name], value):
                kept[name] = value
            else:
                changed.append(name)
        new = [name for name in now if name not in data]
        notes = [f"interface changed; variables kept by name ({len(kept)})"]
        if dropped:
            notes.append(f"dropped (no longer declared): {', '.join(sorted(dropped))}")
        if changed:
            notes.append(f"of another type, at their initial values: {', '.join(changed)}")
        if new:
            notes.append(f"new, at their initial values: {', '.join(new)}")
        return kept, notes


def _same(before: dict[str, object] | None, name: str, now: str, value: object) -> bool:
    if before is not None:
        return before.get(name) == now
    return not isinstance(value, list | dict) and not now.startswith(("ARRAY", "STRUCT", "FB"))


# ---------------------------------------------------------------- an online change's carry

_WIDER: dict[tuple[str, str], Callable[[Any], object]] = {
    ("BOOL", "BYTE"): int,
    ("BOOL", "WORD"): int,
    ("BOOL", "DWORD"): int,
    ("BYTE", "WORD"): int,
    ("BYTE", "DWORD"): int,
    ("WORD", "DWORD"): int,
    ("INT", "DINT"): int,
    ("INT", "REAL"): float,  # every INT is exact in a REAL's 24 bits
    ("CHAR", "STRING"): str,
}
"""Type changes every value of the old type survives unchanged (S7-SCL's implicit class A
conversions that lose nothing): the value is carried, converted."""
_STRING = re.compile(r"STRING\[(\d+)\]")


def carried(old: str, new: str) -> Callable[[object], object] | None:
    """How a value of type ``old`` (a ``type_text``) becomes one of ``new`` without loss:
    None when it cannot (another structure, a narrower type)."""
    if old == new:
        return _same_value
    o, n = _STRING.fullmatch(old), _STRING.fullmatch(new)
    if o is not None and n is not None:
        return str if int(o[1]) <= int(n[1]) else None
    if old == "CHAR" and n is not None:
        return str
    return _WIDER.get((old, new))


def _same_value(value: object) -> object:
    return value


@dataclass
class CarryPlan:
    """What an online change does with an instance's variables: ``kept`` by name (with the
    conversion of each), ``dropped`` (no longer declared), ``new`` (at their initial
    values) and ``refused`` (another type that does not carry the value: ``name: OLD →
    NEW``)."""

    kept: dict[str, Callable[[object], object]] = field(default_factory=dict)
    dropped: list[str] = field(default_factory=list)
    new: list[str] = field(default_factory=list)
    refused: list[str] = field(default_factory=list)

    @staticmethod
    def between(old: SclState, new: SclState) -> CarryPlan:
        """The plan from an instance of ``old``'s FB to one of ``new``'s."""
        plan = CarryPlan()
        before, now = dict(old.types), dict(new.types)
        for name, t in before.items():
            if name not in now:
                plan.dropped.append(name)
                continue
            how = carried(t, now[name])
            if how is None:
                plan.refused.append(f"{name}: {t} → {now[name]}")
            else:
                plan.kept[name] = how
        plan.new = [name for name in now if name not in before]
        return plan

    def apply(self, data: dict[str, object]) -> dict[str, object]:
        """The values of ``data`` (an instance's snapshot) the plan keeps, converted."""
        return {n: how(data[n]) for n, how in self.kept.items() if n in data}

    def notes(self) -> list[str]:
        """What the plan drops and starts afresh (nothing: the values all stay)."""
        out = []
        if self.dropped:
            out.append(f"dropped (no longer declared): {', '.join(self.dropped)}")
        if self.new:
            out.append(f"new, at their initial values: {', '.join(self.new)}")
        return out
