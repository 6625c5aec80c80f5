"""The user blocks a chart's calls are checked against: the FBs' and FCs' interfaces and
the DBs of the program that runs beside the chart (``s7graph check CHART.s7g --blocks
BLOCKS.scl``; docs/cli.md, "s7graph check").

``program_blocks(blocks, instances)`` reads them from engine blocks — compiled S7-SCL or
Python — so the chart's checks need neither the SCL compiler nor a CPU: a pin is its name,
direction and S7 type (``OBJECT`` for an ARRAY, a STRUCT or a multi-instance, which a chart
cannot pass; ``BLOCK_DB`` for an input S7-SCL declares so, which the engine holds as the
WORD with the DB's number), an FB's static variables beside its pins (a chart reads them by
name: ``"Motor_DB".Running``), an FB's instance DBs are those the program names, a global
DB is one the program holds.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

from s7graph.engine.blocks import DB, FB, FC, Decl
from s7graph.steps.scl.types import is_block_db_var

__all__ = ["Interface", "ProgramBlocks", "UserPin", "is_block_db", "program_blocks"]


@dataclass(frozen=True, slots=True)
class UserPin:
    """One formal parameter of a user block: name, ``IN``/``OUT``/``IN_OUT`` and type."""

    name: str
    direction: str
    type: str

    @property
    def is_input(self) -> bool:
        return self.direction in ("IN", "IN_OUT")

    @property
    def is_output(self) -> bool:
        return self.direction in ("OUT", "IN_OUT")


@dataclass(frozen=True, slots=True)
class Interface:
    """A user FB or FC as a call sees it: ``FB17`` and its pins in declared order (an FC's
    function value as the output ``RET_VAL``)."""

    kind: str
    number: int
    name: str
    pins: tuple[UserPin, ...]
    statics: tuple[UserPin, ...] = ()
    """An FB's static variables (``STAT``), in its instance DB beside its parameters."""

    @property
    def label(self) -> str:
        return f"{self.kind}{self.number}"

    def pin(self, name: str) -> UserPin | None:
        upper = name.upper()
        return next((p for p in self.pins if p.name.upper() == upper), None)

    def variable(self, name: str) -> UserPin | None:
        """The parameter or static variable ``name`` (any case) of the instance DB."""
        upper = name.upper()
        return self.pin(name) or next((p for p in self.statics if p.name.upper() == upper), None)


@dataclass(frozen=True)
class ProgramBlocks:
    """The program's FBs and FCs by label (``FB17``) and by name, its instance DBs (number →
    FB label) and global DBs; ``sources`` names where they come from, for messages."""

    blocks: Mapping[str, Interface] = field(default_factory=dict)
    instances: Mapping[int, str] = field(default_factory=dict)
    global_dbs: frozenset[int] = frozenset()
    sources: str = ""

    def find(self, kind: str, block: int | str) -> Interface | None:
        """The block ``CALL FB 17`` or ``CALL "Name"`` names, None if the program lacks it."""
        key = f"{kind}{block}" if kind else str(block)
        return self.blocks.get(key.upper())

    def known(self, kind: str) -> str:
        """The labels of the program's blocks of ``kind``, for a message."""
        labels = sorted({i.label for i in self.blocks.values() if i.kind == kind})
        return " ".join(labels) or "none"


_DIRECTIONS = {Decl.IN: "IN", Decl.OUT: "OUT", Decl.IN_OUT: "IN_OUT"}


def is_block_db(var: Any) -> bool:
    """Whether an engine block's variable is a BLOCK_DB input: the WORD with a DB's number
    that S7-SCL declares so, marked by its comment (``steps.scl.blocks``)."""
    return is_block_db_var(var.type, getattr(var, "comment", ""))


def _pin_type(v: Any) -> str:
    if not isinstance(v.type, str):
        return "OBJECT"
    return "BLOCK_DB" if is_block_db(v) else v.type


def _interface(block: FB | FC) -> Interface:
    pins = [
        UserPin(v.name, _DIRECTIONS[v.decl], _pin_type(v))
        for v in block.interface
        if v.decl in _DIRECTIONS
    ]
    if isinstance(block, FC) and block.ret_type is not None:
        pins.append(UserPin("RET_VAL", "OUT", block.ret_type))
    statics = tuple(
        UserPin(v.name, "STAT", v.type if isinstance(v.type, str) else "OBJECT")
        for v in block.interface
        if v.decl is Decl.STAT and isinstance(block, FB)
    )
    return Interface(str(block.kind), block.number, block.name, tuple(pins), statics)


def program_blocks(
    blocks: Iterable[Any], instances: Mapping[int, str] | None = None, *, sources: str = ""
) -> ProgramBlocks:
    """The interfaces of the user FBs and FCs among ``blocks`` (engine blocks; OBs and
    system blocks are left out), ``instances`` (DB number → FB label) and the global DBs."""
    found: dict[str, Interface] = {}
    dbs: set[int] = set()
    for block in blocks:
        if isinstance(block, DB):
            dbs.add(block.number)
        elif isinstance(block, FB | FC) and str(block.kind) in ("FB", "FC"):
            interface = _interface(block)
            found[interface.label] = interface
            found.setdefault(block.name.upper(), interface)
    return ProgramBlocks(found, dict(instances or {}), frozenset(dbs), sources)
