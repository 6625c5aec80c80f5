"""DB variables by name for ``sim``'s ``--watch`` and stimuli and ``run``'s watch list:
``DBn.var`` or ``"DBname".var``, nested with dots and indexed with ``[i]`` (``DB20.avg``,
``DB3.motor[2].on``; docs/cli.md, "s7graph sim").

An instance DB is read through its FB's structure when the FB is written in S7-SCL
(``SclProgram.types``), else by the names of its FB's interface (an SFB's ``DB10.ET``, a
Python FB's variables) one level deep; a global DB declared in an S7-SCL source through
its STRUCT, as S7 lays it out. A DB by name is one the CPU's symbol table names
(``"Data" ; DB 20``) or whose name the CPU knows (a chart's instance DB by the chart's name,
a DB an SCL source names). Values keep their type (``steps.scl.access.plain``). An address
(``DB1.DBW2``) is not a DB variable: the callers try addresses first, so what an address
trace gave stays as it was.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import replace
from typing import Any

from s7graph.engine.blocks import FB, Decl, InstanceDB
from s7graph.engine.errors import S7Error
from s7graph.steps.scl import types as ty
from s7graph.steps.scl.access import (
    Member,
    hidden_members,
    member,
    parse_name,
    plain,
    read_bytes,
    write_bytes,
)
from s7graph.web.harness.operands import bad_address, stimulus_value

__all__ = ["DbVariables"]


class DbVariables:
    """The DB variables of ``cpu`` by name; ``types``: the structures of S7-SCL FBs and
    global DBs by label (``FB17``, ``DB20``)."""

    def __init__(self, cpu: Any, types: Mapping[str, ty.SclType] | None = None) -> None:
        self.cpu = cpu
        self.types = dict(types or {})

    def is_db_name(self, name: str) -> bool:
        """Whether ``name`` has a DB variable's form (it may still not resolve)."""
        try:
            return parse_name(name) is not None
        except ValueError:
            return True

    def check(self, name: str, *, writing: bool, unknown: str) -> None:
        """``S7Error`` unless ``name`` is a DB variable that resolves (one that can be
        written, with ``writing``): a name written as an S7 address that is none is refused
        as that address, with why (``bad address 'M10.8': bit 8 outside 0..7``), any other
        name of no DB variable's form as ``unknown``."""
        bad = bad_address(name)
        if not self.is_db_name(name):
            raise bad or S7Error(unknown)
        try:
            (self.writer if writing else self.reader)(name)
        except S7Error:
            if bad is None:
                raise
            raise bad from None

    def reader(self, name: str) -> Callable[[], Any]:
        """A function giving the variable's value as JSON holds it; ``S7Error`` when the
        name does not resolve."""
        where, m, _ = self._find(name)
        if isinstance(where, InstanceDB):
            keys = m.keys
            return lambda: plain(_walk(where, keys, whole=True))
        buf = where
        return lambda: plain(read_bytes(buf, m))

    def writer(self, name: str) -> Callable[[Any], None]:
        """A function writing an elementary variable (its value checked against its type);
        ``S7Error`` when the name does not resolve or names an ARRAY, STRUCT or instance."""
        where, m, t = self._find(name)
        if t.aggregate or t.kind == "FB":
            raise S7Error(f"{name} is {t}: set its elements one by one")
        engine_type = ty.engine_type(t)

        def checked(value: Any) -> Any:
            return stimulus_value(engine_type, name, value)

        if isinstance(where, InstanceDB):
            *parents, last = m.keys
            idb = where

            def write(value: Any) -> None:
                _walk(idb, parents)[last] = checked(value)

            return write
        buf = where
        return lambda value: write_bytes(buf, m, checked(value))

    def _find(self, name: str) -> tuple[InstanceDB | bytearray, Member, ty.SclType]:
        try:
            parsed = parse_name(name)
        except ValueError as exc:
            raise S7Error(str(exc)) from None
        if parsed is None:
            raise S7Error(f"{name} is not a DB variable (DBn.name)")
        db, path = parsed
        number = db if isinstance(db, int) else self.number_of(db, name)
        idb = self.cpu.instance_dbs.get(number)
        if idb is not None:
            structure = self.types.get(idb.fb.label) or _interface(idb.fb)
            found = _member(structure, path, _structures(self.types, self.cpu), name)
            return idb, found, found.type
        block = self.cpu.mem.dbs.get(number)
        if block is None:
            raise S7Error(f"{name}: DB{number} is not in this CPU")
        declared = self.types.get(f"DB{number}")
        if declared is None:
            why = "its structure is not declared in an S7-SCL source"
            raise S7Error(f"{name}: {why}; read DB{number} by address (DB{number}.DBW0)")
        found = _member(replace(declared, name=f"DB{number}"), path, self.types, name)
        return block.data, found, found.type

    def number_of(self, db: str, name: str) -> int:
        """The number of the DB named ``db`` (``Cpu.db_named``; ``name`` for the message);
        S7Error if none."""
        try:
            number = self.cpu.db_named(db)
        except S7Error as exc:
            raise S7Error(f"{name}: {exc.message}") from None
        if number is None:
            raise S7Error(
                f'{name}: no DB is named "{db}" (name it in the symbol table: "{db}" ; DB n)'
            )
        return int(number)


def _member(structure: ty.SclType, path: Any, types: dict[str, ty.SclType], name: str) -> Member:
    try:
        return member(structure, path, types, name)
    except ValueError as exc:
        raise S7Error(str(exc)) from None


def _structures(types: Mapping[str, ty.SclType], cpu: Any) -> dict[str, ty.SclType]:
    """The S7-SCL structures by FB label, and for a multi-instance of a system block or a
    Python FB (``tmr : TON;`` in an S7-SCL FB, read as ``DB10.tmr.Q``) its interface."""
    found = {label: _interface(b) for label, b in cpu.blocks.items() if isinstance(b, FB)}
    return {**found, **types}


def _interface(fb: FB) -> ty.SclType:
    """The structure of an FB not written in S7-SCL: its variables by their engine types;
    its Python state (an IEC timer's ``STATE``) left out."""
    fields = []
    hidden = hidden_members(fb)
    for var in fb.interface:
        if var.decl is Decl.TEMP or var.name in hidden:
            continue
        t = ty.by_name(var.type.split("[")[0]) if isinstance(var.type, str) else None
        if isinstance(var.type, str) and var.type.upper().startswith("STRING["):
            t = ty.string(int(var.type[7:-1]))
        fields.append((var.name, t or ty.ANY))
    return ty.SclType("STRUCT", fields=tuple(fields), name=fb.label)


def _walk(idb: InstanceDB, keys: Sequence[str | int], whole: bool = False) -> Any:
    """The value at ``keys`` inside an instance DB (a multi-instance: its own values, or
    with ``whole`` the instance itself when it is the last, for ``plain`` to read)."""
    value: Any = idb.values
    key: Any
    for i, key in enumerate(keys):
        value = value[key]
        if isinstance(value, InstanceDB) and not (whole and i == len(keys) - 1):
            value = value.values
    return value
