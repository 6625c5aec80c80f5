"""Checks of a state file's memory images and diagnostics rows before any of it is
restored (``engine/persistence.py``): ValueError naming what is malformed, so a file is
refused rather than half taken.

The retentive image (``Memory.snapshot``) and the hot-restart image
(``Memory.hot_snapshot``) are JSON objects of base64 byte areas and S5 timer and counter
cells. Taken unchecked, a garbled image is read as something else: invalid base64 decodes
to fewer bytes, a marker span beyond the CPU's marker area grows it, a cell number the CPU
does not have is skipped, a cell field of the wrong type is set as it is. A diagnostics row
is typed only by SQLite's affinity: a NULL or a text where a number belongs is refused, not
read as 0 or as a crash.
"""

from __future__ import annotations

import base64
import binascii
from dataclasses import fields
from typing import Any

from s7graph.engine.memory import Memory, S5Counter, S5Timer
from s7graph.engine.record import DiagEntry

__all__ = ["check_hot_image", "check_memory_image", "diag_entry", "stored_integer"]

_IMAGE_KEYS = frozenset({"markers", "timers", "counters", "dbs"})
_HOT_KEYS = frozenset({"markers", "outputs", "timers", "counters"})
_DB_KEYS = frozenset({"data", "initial", "created"})
_DIAG_FIELDS = ("t_ns", "event_id", "block", "message", "address", "ob", "priority", "wall_ns")
_DIAG_NUMBERS = ("t_ns", "event_id", "ob", "priority", "wall_ns")
_DIAG_TEXTS = ("block", "message", "address")


def check_memory_image(data: object, mem: Memory) -> None:
    """``data`` is a retentive image ``mem.restore`` can take as it is; ValueError if not."""
    image = _object(data, "the image")
    _known(image, _IMAGE_KEYS, "the image")
    marks = image.get("markers")
    if marks:
        span = _object(marks, "'markers'")
        _known(span, frozenset({"start", "data"}), "'markers'")
        start = span.get("start")
        if type(start) is not int or start < 0:
            raise ValueError(f"'markers' starts at {start!r}")
        raw = _bytes(span.get("data"), "'markers'")
        if start + len(raw) > len(mem.markers):
            raise ValueError(
                f"'markers' MB{start}..MB{start + len(raw) - 1} beyond the CPU's "
                f"{len(mem.markers)} marker bytes"
            )
    _cells(image.get("timers", {}), S5Timer, len(mem.timers), "timers")
    _cells(image.get("counters", {}), S5Counter, len(mem.counters), "counters")
    for key, item in _object(image.get("dbs", {}), "'dbs'").items():
        what = f"DB {key!r}"
        if not key.isdigit() or not 1 <= int(key) <= 65535:
            raise ValueError(f"{what}: not a DB number")
        db = _object(item, what)
        _known(db, _DB_KEYS, what)
        _bytes(db.get("data"), f"{what} data")
        _bytes(db.get("initial", ""), f"{what} initial values")
        if type(db.get("created", False)) is not bool:
            raise ValueError(f"{what}: 'created' is {db.get('created')!r}")


def check_hot_image(data: object, mem: Memory) -> None:
    """``data`` is a hot-restart image ``mem.restore_hot`` can take as it is; ValueError if
    not."""
    image = _object(data, "the image")
    _known(image, _HOT_KEYS, "the image")
    for key, area in (("markers", mem.markers), ("outputs", mem.outputs)):
        raw = _bytes(image.get(key), f"{key!r}")
        if len(raw) != len(area):
            raise ValueError(f"{key!r} holds {len(raw)} bytes, the CPU {len(area)}")
    _cells(image.get("timers", {}), S5Timer, len(mem.timers), "timers")
    _cells(image.get("counters", {}), S5Counter, len(mem.counters), "counters")


def diag_entry(row: tuple[object, ...]) -> DiagEntry:
    """The entry of a diagnostics row (``t_ns, event_id, block, message, address, ob,
    priority, wall_ns``): each number an integer (the event id a WORD), each text a text or
    NULL (empty); ValueError naming the column that is not."""
    field = dict(zip(_DIAG_FIELDS, row, strict=True))
    t_ns, event_id, ob, priority, wall_ns = (stored_integer(field[n], n) for n in _DIAG_NUMBERS)
    if not 0 <= event_id <= 0xFFFF:
        raise ValueError(f"event_id is {event_id}, not an event id (a WORD)")
    block, message, address = (_text(field[n], n) for n in _DIAG_TEXTS)
    return DiagEntry(t_ns, event_id, block, message, address, ob, priority, wall_ns)


def stored_integer(value: object, name: str, where: str = "") -> int:
    """A column's ``value`` as SQLite gave it, if an integer (not a bool, a text, a blob or
    NULL); ValueError naming ``where`` (a row) and column ``name`` if not."""
    if type(value) is not int:
        shown = "NULL" if value is None else repr(value)
        raise ValueError(f"{f'{where}: ' if where else ''}{name} is {shown}, not an integer")
    return value


def _text(value: object, name: str) -> str:
    if value is not None and not isinstance(value, str):
        raise ValueError(f"{name} is {value!r}, not text")
    return value or ""


def _object(value: object, what: str) -> dict[str, Any]:
    if not isinstance(value, dict):
        raise ValueError(f"{what} is {type(value).__name__}, not an object")
    return value


def _known(value: dict[str, Any], keys: frozenset[str], what: str) -> None:
    unknown = sorted(set(value) - keys)
    if unknown:
        raise ValueError(f"{what} holds unknown key(s) {', '.join(map(repr, unknown))}")


def _bytes(value: object, what: str) -> bytes:
    if not isinstance(value, str):
        raise ValueError(f"{what} is {value!r}, not base64 text")
    try:
        return base64.b64decode(value, validate=True)
    except (binascii.Error, ValueError):
        raise ValueError(f"{what} is not valid base64") from None


def _cells(value: object, kind: type[S5Timer | S5Counter], count: int, what: str) -> None:
    """Each cell number within the CPU's ``count`` cells, each field of the cell's type."""
    types = {f.name: type(f.default) for f in fields(kind)}
    for key, cell in _object(value, f"{what!r}").items():
        if not key.isdigit() or int(key) >= count:
            raise ValueError(f"{what} {key!r}: the CPU has {count} cells")
        state = _object(cell, f"{what} {key}")
        _known(state, frozenset(types), f"{what} {key}")
        for name, item in state.items():
            if type(item) is not types[name]:
                raise ValueError(f"{what} {key}: {name!r} is {item!r}")
        if kind is S5Counter and not 0 <= int(state.get("value", 0)) <= 999:
            raise ValueError(f"{what} {key}: the count {state['value']!r} is not in 0..999")
