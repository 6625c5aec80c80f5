"""The CPU's program: downloading blocks, finding them, and its instance DBs (docs/runtime.md,
"Restarts: warm, hot, cold").

``ProgramBlocks`` is a part of ``engine.cpu.Cpu``, which owns the attributes it declares.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from s7graph.engine.blocks import DB, FB, FC, OB, BlockKind, InstanceDB
from s7graph.engine.errors import BlockError
from s7graph.engine.memory import Memory

__all__ = ["ProgramBlocks"]


class ProgramBlocks:
    """Loaded blocks by label, OBs by number, instance DBs by number."""

    mem: Memory
    blocks: dict[str, OB | FB | FC | DB]
    obs: dict[int, OB]
    instance_dbs: dict[int, InstanceDB]
    hot_blockers: set[str]

    def load(self, *blocks: OB | FB | FC | DB | Iterable[Any]) -> None:
        """Download blocks (a later block replaces one with the same label); DBs are created."""
        for item in blocks:
            if isinstance(item, OB | FB | FC | DB):
                self._load_one(item)
            elif isinstance(item, Iterable) and not isinstance(item, str | bytes):
                self.load(*item)
            else:
                raise BlockError(f"cannot load {item!r}: not a block")
        self.hot_blockers.add("program download")

    def _load_one(self, block: OB | FB | FC | DB) -> None:
        self.blocks[block.label] = block
        if isinstance(block, OB):
            self.obs[block.number] = block
        elif isinstance(block, DB):
            if block.number in self.instance_dbs:
                raise BlockError(f"DB{block.number} is already an instance DB")
            self.mem.dbs.pop(block.number, None)
            self.mem.create_db(
                block.number,
                block.size,
                init=block.init,
                retain=block.retain,
                name=block.name,
                layout=block.layout,
            )

    def block(self, ref: str | int) -> OB | FB | FC | DB:
        """A loaded block by label (``'FC2'``, ``'SFB4'``), name, or FB/FC number."""
        if isinstance(ref, int):
            found = self.blocks.get(f"FB{ref}") or self.blocks.get(f"FC{ref}")
        else:
            key = "".join(ref.split()).upper()
            found = self.blocks.get(key)
            if found is None:
                found = next(
                    (b for b in self.blocks.values() if getattr(b, "name", "") == ref), None
                )
        if found is None:
            raise BlockError(f"block {ref} is not loaded")
        return found

    def create_instance_db(self, number: int, fb: FB, *, name: str | None = None) -> InstanceDB:
        """Create instance DB ``number`` from a loaded FB's interface (or an SFB's)."""
        if fb.kind is BlockKind.FB and self.blocks.get(fb.label) != fb:
            raise BlockError(f"{fb.label} {fb.name!r} must be loaded before its instance DB")
        if number in self.instance_dbs or number in self.mem.dbs:
            raise BlockError(f"DB{number} already exists")
        idb = InstanceDB(number, fb, name=name)
        self.instance_dbs[number] = idb
        return idb

    def replace_instance_db(self, number: int, fb: FB, *, name: str | None = None) -> InstanceDB:
        """Re-create instance DB ``number`` from ``fb``'s interface, replacing the one there
        (a changed FB downloaded into a running CPU: the caller carries the values over)."""
        if number not in self.instance_dbs:
            raise BlockError(f"DB{number} is not an instance DB")
        if fb.kind is BlockKind.FB and self.blocks.get(fb.label) != fb:
            raise BlockError(f"{fb.label} {fb.name!r} must be loaded before its instance DB")
        idb = InstanceDB(number, fb, name=name)
        self.instance_dbs[number] = idb
        return idb

    def no_db_bytes(self, number: int) -> str:
        """Why DB ``number`` has no byte addresses: an FB's instance DB is kept by variable
        name here (``DB1.S_NO``, not ``DB1.DBW0``); "" for a DB that does not exist."""
        idb = self.instance_dbs.get(number)
        if idb is None:
            return ""
        names = [v.name for v in idb.fb.interface[:3]]
        example = f" (DB{number}.{names[0]})" if names else ""
        return (
            f"DB{number} is the instance DB of {idb.fb.label} {idb.fb.name!r}: it has no byte "
            f"addresses here; read and write its variables by name{example}"
        )

    def instance_db(self, number: int) -> InstanceDB:
        try:
            return self.instance_dbs[number]
        except KeyError:
            raise BlockError(f"instance DB{number} is not loaded") from None

    def db_named(self, name: str) -> int | None:
        """The number of the DB named ``name`` (quotes optional, case-insensitive): a DB
        symbol of the symbol table first, then an instance DB's or a global DB's own name;
        None when nothing has the name; SymbolError when the symbol names another block or
        an operand."""
        symbols = self.mem.symbols
        if symbols is not None:
            block = symbols.block(name)
            if block is not None and block.kind == "DB":
                return block.number
        key = name.strip('"').casefold()
        for number, idb in self.instance_dbs.items():
            if idb.name.casefold() == key:
                return int(number)
        for number, db in self.mem.dbs.items():
            if db.name.casefold() == key:
                return int(number)
        return symbols.db_number(name) if symbols is not None else None
