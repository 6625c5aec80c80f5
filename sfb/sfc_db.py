"""SFC22 CREAT_DB, SFC23 DEL_DB, SFC24 TEST_DB (docs/runtime.md, "The block runtime"; STEP7
comprehensive guide vol. 2, ch. 12).

* CREAT_DB creates the *lowest free* number in LOW_LIMIT..UP_LIMIT with COUNT bytes; COUNT
  must be even and non-zero (``W#16#80A2``), a bad range is ``80A1``, no free number
  ``80B1``. So unguarded calls every scan create DB10, DB11, … until the range is used up.
  The contents are not initialised on a real CPU (here: zero). Such DBs are marked
  ``created``: a cold restart deletes them.
* DEL_DB deletes a DB (``80B1`` missing); instance DBs are refused (``80B2``) ``[K]``.
* TEST_DB returns DB_LENGTH and WRITE_PROT; a missing DB is ``W#16#80B1``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, cast

from s7graph.engine import blocks
from s7graph.sfb.catalogue import OK, engine_sections, lookup, specific_error

if TYPE_CHECKING:
    from s7graph.engine.context import CallContext

WRONG_NUMBER = 0x80A1
WRONG_LENGTH = 0x80A2
NO_DB = 0x80B1  # CREAT_DB: no free number in the range; DEL_DB/TEST_DB: DB missing
NOT_DELETABLE = 0x80B2
MAX_DB = 65535
MAX_DB_BYTES = 65534


def _declare(name: str, body: blocks.FCBody) -> blocks.FC:
    entry = lookup(name)
    sections, ret = engine_sections(entry)
    return blocks.sfc(entry.number, entry.name, RET=ret, **sections)(body)


def _used(ctx: CallContext) -> set[int]:
    return set(ctx.mem.dbs) | set(ctx.cpu.instance_dbs)


def _creat_db(ctx: CallContext, params: dict[str, object]) -> int:
    low, up = cast(int, params["LOW_LIMIT"]), cast(int, params["UP_LIMIT"])
    count = cast(int, params["COUNT"])
    if not 1 <= low <= up <= MAX_DB:
        return specific_error(WRONG_NUMBER)
    if count == 0 or count % 2 or count > MAX_DB_BYTES:
        return specific_error(WRONG_LENGTH)
    used = _used(ctx)
    number = next((n for n in range(low, up + 1) if n not in used), None)
    if number is None:
        return specific_error(NO_DB)
    ctx.mem.create_db(number, count, created=True)
    params["DB_NUMBER"] = number
    return OK


def _del_db(ctx: CallContext, params: dict[str, object]) -> int:
    number = cast(int, params["DB_NUMBER"])
    if not 1 <= number <= MAX_DB:
        return specific_error(WRONG_NUMBER)
    if number in ctx.cpu.instance_dbs:
        return specific_error(NOT_DELETABLE)
    if number not in ctx.mem.dbs:
        return specific_error(NO_DB)
    ctx.mem.delete_db(number)
    ctx.cpu.blocks.pop(f"DB{number}", None)
    return OK


def _test_db(ctx: CallContext, params: dict[str, object]) -> int:
    number = cast(int, params["DB_NUMBER"])
    if not 1 <= number <= MAX_DB:
        return specific_error(WRONG_NUMBER)
    db = ctx.mem.dbs.get(number)
    if db is None:
        return specific_error(NO_DB)
    params["DB_LENGTH"] = len(db)
    params["WRITE_PROT"] = False
    return OK


SFC22 = _declare("CREAT_DB", _creat_db)
SFC23 = _declare("DEL_DB", _del_db)
SFC24 = _declare("TEST_DB", _test_db)
BLOCKS = (SFC22, SFC23, SFC24)
