"""Watching addresses and DB variables over the bus: STEP 7's "Monitor/Modify Variables",
triggered once at the end of a cycle (docs/bus.md, "The watch table: watch").

A :class:`~web.bus.protocol.WatchRequest` on the ``watch`` queryable names up to 64
operands; the zenoh thread checks their spelling (:func:`parse_item`) and queues the
request in its source's share (``web.bus.shares``: a request signed by a login in its
user's, apart from every source that is only a claim), and the scan thread reads them all
at the next scan boundary (:meth:`Watching.at_boundary`) — the values of one scan, never
torn by the next — and hands the answer to the publisher's outbox, which encodes and sends
it. An operand is

- an absolute address: ``MW0``, ``Q4.0``, ``IB2``, ``DB20.DBW2``, ``T5`` (S5TIME left),
  ``C3`` (the count);
- a symbol of the CPU's table (``"Start_button"``, quotes optional), in its declared type;
- a DB variable by name: ``DBn.var``, nested with dots and indexed with ``[i]`` — in an
  instance DB (``DB10.count``, ``DB10.ctu.CV``, a multi-instance's variables, an ARRAY by
  its declared bounds, a chart's own variables in its GraphFB's: ``"Seq_mix".count``) or
  in a global DB that has a layout — one declared in S7-SCL
  (``DB20.avg``, ``DB20.recipe.speed``, ``DB20.speeds[2]``, ``DB20.motor[2].on``); the DB
  also by its name, ``"Data".temps[2]``;

each optionally followed by the type to show it as (``MW0:INT``, ``MD4:REAL``,
``DB20.DBW0:S5TIME``). A value is shown as S7 writes it (``TRUE``, ``B#16#07``,
``W#16#00FF``, ``-5``, ``L#100000``, ``1.5``, ``S5T#1S200MS``, ``C#12``); one that cannot
be read says why, the others are read all the same.
"""

from __future__ import annotations

import dataclasses
import math
import re
import time
from dataclasses import dataclass
from datetime import date, datetime
from typing import Any, Final, cast

import zenoh

from s7graph.engine.address import Address, Area, Width, parse_address
from s7graph.engine.blocks import Decl, InstanceDB
from s7graph.engine.cpu import Cpu
from s7graph.engine.datatypes import type_of
from s7graph.engine.errors import S7Error, internal_error
from s7graph.engine.literals import format_literal
from s7graph.engine.memory import DataBlock
from s7graph.engine.symbols import default_type
from s7graph.sequencer.fb import chart_variables
from s7graph.web.bus.origin import lockout_source
from s7graph.web.bus.protocol import (
    CpuState,
    ProtocolError,
    WatchRequest,
    WatchValue,
    WatchValues,
    decode,
    encode,
    watch_bytes,
)
from s7graph.web.bus.publisher import BusPublisher, QueryReply
from s7graph.web.bus.shares import SharedQueue

__all__ = [
    "Segment",
    "WatchError",
    "WatchItem",
    "Watching",
    "array_bounds",
    "db_by_name",
    "element_slot",
    "element_type",
    "instance_slot",
    "layout_address",
    "login_refused",
    "parse_item",
    "split_operands",
    "watch_value",
]

QUEUE: Final = 64
"""Watch requests of proven sources waiting at most — users whose session signed them (with
a users file), this process; beyond, such a request is refused at once as busy."""
UNPROVEN: Final = 32
"""Watch requests of all other sources waiting at most, in places of their own: a link
named by the sender's own ``source_info``, requests that name no session, any request
to a CPU without a users file. However many sources a peer makes up, they never take a
proven source's place."""
PER_SOURCE: Final = 8
"""Watch requests one source may have waiting — a proven user, or a link as the transport
names it (``web.bus.origin.lockout_source``); beyond, its request is refused at once as
busy, so a source that floods ``watch`` fills its own share, never the places other
sources wait in."""
PER_BOUNDARY: Final = 8
"""Requests read at one scan boundary at most (the rest wait for the next)."""

_DB_VAR = re.compile(
    r"DB(\d{1,5})\.([^\W\d]\w*(?:\.[^\W\d]\w*|\[\s*-?\d+(?:\s*,\s*-?\d+)*\s*\])*)$",
    re.IGNORECASE,
)
_NAMED_DB_VAR = re.compile(
    r'"([^"]+)"\.([^\W\d]\w*(?:\.[^\W\d]\w*|\[\s*-?\d+(?:\s*,\s*-?\d+)*\s*\])*)$'
)
_SEGMENT = re.compile(r"\.?([^\W\d]\w*)|\[([^\]]*)\]")
_ARRAY = re.compile(r"ARRAY\s*\[(.+?)\]\s*OF\s+(.+)", re.IGNORECASE | re.DOTALL)
_BOUND = re.compile(r"\s*(-?\d+)\s*\.\.\s*(-?\d+)\s*")

Segment = str | tuple[int, ...]
"""A step of a DB variable's path: a name, or the indices of ``[i, j]``."""


class WatchError(S7Error):
    """Why one watched operand cannot be read (its text names the place)."""


@dataclass(frozen=True, slots=True)
class WatchItem:
    """One operand as asked (``text``): its target without the type, the type to show it
    as (None: its own), its path when it is a DB variable by name, or why it is no
    operand (``error``); a DB named by its name (``"Data".x``) has ``db_name``."""

    text: str
    target: str = ""
    type: str | None = None
    db: int | None = None
    path: tuple[Segment, ...] = ()
    error: str = ""
    db_name: str = ""


def split_operands(text: str) -> list[str]:
    """The operands of a comma-separated list (``MW0, Q4.0, DB20.m[1,2]``: the commas
    inside ``[…]`` kept), blanks around them dropped, empty ones left out."""
    out, depth, word = [], 0, ""
    for ch in text:
        depth += (ch == "[") - (ch == "]")
        if ch == "," and depth <= 0:
            out.append(word.strip())
            word = ""
        else:
            word += ch
    out.append(word.strip())
    return [w for w in out if w]


def parse_item(text: str) -> WatchItem:
    """The spelling of one operand checked (no CPU needed: the zenoh thread's work)."""
    spelled = text.strip()
    target, type_name = spelled, None
    closing = spelled.rfind('"')
    head, colon, tail = spelled.rpartition(":")
    if colon and not head.strip():
        return WatchItem(text, error=f"{text}: no operand before ':'")
    if colon and closing < len(head):
        target, type_name = head.strip(), tail.strip().upper()
        try:
            type_name = type_of(type_name).name
        except S7Error:
            return WatchItem(text, error=f"{text}: unknown type {tail.strip()!r} after ':'")
    if not target:
        return WatchItem(text, error="an empty operand")
    m = _DB_VAR.match(target)
    if m is not None and not _absolute(target):
        return WatchItem(text, target, type_name, int(m[1]), _segments(m[2]))
    named = _NAMED_DB_VAR.match(target)
    if named is not None:
        return WatchItem(text, target, type_name, path=_segments(named[2]), db_name=named[1])
    return WatchItem(text, target, type_name)


def _absolute(text: str) -> bool:
    try:
        parse_address(text)
    except S7Error:
        return False
    return True


def _segments(path: str) -> tuple[Segment, ...]:
    out: list[Segment] = []
    for m in _SEGMENT.finditer(path):
        if m[1] is not None:
            out.append(m[1])
        else:
            out.append(tuple(int(i) for i in m[2].split(",")))
    return tuple(out)


# ---------------------------------------------------------------- reading (scan thread)


def watch_value(cpu: Cpu, item: WatchItem) -> WatchValue:
    """Read ``item`` on ``cpu`` (between two scans): the value and its text, or why not."""
    if item.error:
        return WatchValue(address=item.text[:128], error=item.error[:4096])
    try:
        value, type_name = _read(cpu, item)
        value, shown = _shown(value, type_name, item.target)
    except S7Error as exc:
        return WatchValue(address=item.text[:128], error=_unprefixed(exc.message, item)[:4096])
    except Exception as exc:  # a block's object that does not read: say so, go on
        error = f"{item.target}: {type(exc).__name__}: {exc}"
        return WatchValue(address=item.text[:128], error=error[:4096])
    return WatchValue(address=item.text[:128], value=value, text=shown[:4096], type=type_name)


def _unprefixed(message: str, item: WatchItem) -> str:
    """``message`` without the operand it starts with: a reader shows the error beside the
    operand already (``DB1.DBW0: DB1 does not exist``, not the address twice)."""
    head = f"{item.target}: "
    return message[len(head) :] if message[: len(head)].casefold() == head.casefold() else message


def _read(cpu: Cpu, item: WatchItem) -> tuple[object, str]:
    mem = cpu.mem
    if item.db is not None or item.db_name:
        return _db_variable(cpu, item)
    symbol = mem.symbols.lookup(item.target) if mem.symbols is not None else None
    if symbol is not None:
        address, declared = symbol.address, symbol.type
    else:
        if item.target.startswith('"'):
            raise WatchError(f"{item.target}: no such symbol")
        address, declared = parse_address(item.target), None
    type_name = item.type or declared or _natural(address)
    if type_name in ("TIMER", "COUNTER") and address.area not in (Area.T, Area.C):
        type_name = _natural(address)
    return mem.read_as(address, type_name), type_name


def _natural(address: Address) -> str:
    """How an address is shown without a type: a timer's time left, a counter's count."""
    if address.area is Area.T:
        return "S5TIME"
    if address.area is Area.C:
        return "COUNTER"
    return default_type(address)


def _db_variable(cpu: Cpu, item: WatchItem) -> tuple[object, str]:
    number, path = item.db, item.path
    if number is None:
        number = db_by_name(cpu, item.db_name)
    idb = cpu.instance_dbs.get(number)
    if idb is not None:
        value, type_name = _walk_instance(idb, path, f"DB{number}")
        return value, item.type or type_name
    db = cpu.mem.dbs.get(number)
    if db is None:
        raise WatchError(f"DB{number} is not loaded")
    return _layout_variable(cpu, db, path, item.type)


def db_by_name(cpu: Cpu, name: str) -> int:
    """The number of the DB named ``name`` (``Cpu.db_named``); WatchError if none."""
    try:
        number = cpu.db_named(name)
    except S7Error as exc:
        raise WatchError(exc.message) from None
    if number is None:
        raise WatchError(f'"{name}": no DB has this name')
    return number


def _walk_instance(idb: InstanceDB, path: tuple[Segment, ...], where: str) -> tuple[object, str]:
    """The value at ``path`` in an instance DB — into multi-instances, objects' fields and
    ARRAYs by their declared bounds — and its declared type where it has one."""
    value: Any = idb
    type_name = ""
    bounds: list[tuple[int, int]] | None = None
    for step in path:
        if isinstance(value, InstanceDB):
            if not isinstance(step, str):
                raise WatchError(f"{where} is an instance DB: it takes no index")
            values, var, type_name = instance_slot(value, step, where)
            value = values[var]
            where = f"{where}.{var}"
            bounds = array_bounds(type_name)
        elif isinstance(step, str):
            value, where, type_name, bounds = (
                _field(value, step, where),
                f"{where}.{step}",
                "",
                None,
            )
        else:
            value = _element(value, step, bounds, where)
            where = f"{where}[{','.join(map(str, step))}]"
            type_name, bounds = element_type(type_name), None
    if isinstance(value, InstanceDB):
        raise WatchError(f"{where} is a multi-instance: watch one of its variables")
    return value, type_name if _elementary(type_name) else ""


def instance_slot(idb: InstanceDB, name: str, where: str) -> tuple[dict[str, Any], str, str]:
    """(the dict holding the variable ``name`` of ``idb``, its key there, its declared
    type): a variable of the FB's interface, or a chart's own variable in its GraphFB's
    instance DB (``sequencer.fb.chart_variables``), the name in any case."""
    names = [v.name for v in idb.fb.interface if v.decl is not Decl.TEMP]
    found = next((n for n in names if n.casefold() == name.casefold()), None)
    if found is not None:
        return idb.values, found, idb.fb.var(found).type
    chart = chart_variables(idb)
    if chart is not None:
        values, types = chart
        key = next((n for n in types if n.casefold() == name.casefold()), None)
        if key is not None and key in values:
            return values, key, types[key]
        names = [*types, *names]
    raise WatchError(
        f"{where} ({idb.fb.label}) has no variable {name!r}; it has {', '.join(names[:24])}"
    )


def _field(value: object, name: str, where: str) -> object:
    if isinstance(value, dict):
        key = next((k for k in value if str(k).casefold() == name.casefold()), None)
        if key is None:
            raise WatchError(f"{where} has no field {name!r}")
        return value[key]
    names = _public_names(value)
    found = next((n for n in names if n.casefold() == name.casefold()), None)
    if found is None:
        what = type(value).__name__
        has = f"; it has {', '.join(names[:24])}" if names else ""
        raise WatchError(f"{where} (a {what}) has no field {name!r}{has}")
    return getattr(value, found)


def _public_names(value: object) -> list[str]:
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return [f.name for f in dataclasses.fields(value)]
    names = list(getattr(value, "__struct_fields__", ()))
    names += [n for n in getattr(value, "__dict__", {}) if not n.startswith("_")]
    return names


def _element(
    value: object, index: tuple[int, ...], bounds: list[tuple[int, int]] | None, where: str
) -> object:
    holder, position = element_slot(value, index, bounds, where)
    return holder[position]


def element_slot(
    value: object, index: tuple[int, ...], bounds: list[tuple[int, int]] | None, where: str
) -> tuple[Any, int]:
    """(the list holding ``value[index]``, its position there): each index within its
    declared bounds (a dimension without: from 0); WatchError names the one outside."""
    if not isinstance(value, list | tuple):
        raise WatchError(f"{where} is no ARRAY: it takes no index")
    current: Any = value
    holder: Any = value
    position = 0
    for k, i in enumerate(index):
        lo, hi = bounds[k] if bounds is not None and k < len(bounds) else (0, len(current) - 1)
        if not lo <= i <= hi or not isinstance(current, list | tuple) or i - lo >= len(current):
            raise WatchError(f"{where}: index {i} outside {lo}..{hi}")
        holder, position = current, i - lo
        current = current[position]
    return holder, position


def array_bounds(type_name: str) -> list[tuple[int, int]] | None:
    m = _ARRAY.fullmatch(type_name.strip())
    if m is None:
        return None
    out = []
    for dim in m[1].split(","):
        b = _BOUND.fullmatch(dim)
        if b is None:
            return None
        out.append((int(b[1]), int(b[2])))
    return out


def element_type(type_name: str) -> str:
    m = _ARRAY.fullmatch(type_name.strip())
    return m[2].strip().upper() if m else ""


def _elementary(type_name: str) -> bool:
    if not type_name:
        return False
    try:
        return type_of(type_name).size_bits <= 64 or type_name.upper().startswith("STRING")
    except S7Error:
        return False


def _layout_variable(
    cpu: Cpu, db: DataBlock, path: tuple[Segment, ...], wanted: str | None
) -> tuple[object, str]:
    """A variable of a global DB by its layout (``engine.datatypes.layout``)."""
    address, type_name = layout_address(db, path)
    shown_as = wanted or type_name
    return cpu.mem.read_as(address, shown_as), shown_as


def layout_address(
    db: DataBlock, path: tuple[Segment, ...], verb: str = "watch"
) -> tuple[Address, str]:
    """The address and declared type of the variable ``path`` of global DB ``db``, by its
    layout (``engine.datatypes.layout``); WatchError says why not, for ``verb``."""
    where = f"DB{db.number}"
    if db.layout is None:
        raise WatchError(
            f"{where} has no variables by name (no layout): {verb} its bytes, e.g. {where}.DBW0"
        )
    slots = db.layout.slots
    name, index = _spelled(path), None
    key = _slot_key(slots, name)
    if key is None and not isinstance(path[-1], str):
        name, index = _spelled(path[:-1]), path[-1]
        key = _slot_key(slots, name)
    if key is None:
        top = [k for k in slots if "." not in k and "[" not in k]
        raise WatchError(f"{where} has no variable {name!r}; it has {', '.join(top[:24])}")
    slot = slots[key]
    byte, bit, type_name = slot.byte, slot.bit, slot.type
    if index is not None:
        byte, bit, type_name = _array_element(slot.byte, slot.type, index, f"{where}.{key}")
    if type_name == "STRUCT" or type_name.upper().startswith("ARRAY"):
        what = "an ARRAY" if type_name.upper().startswith("ARRAY") else "a STRUCT"
        raise WatchError(f"{where}.{key} is {what}: {verb} one of its elements")
    size = type_of(type_name).size
    width = {0: Width.BIT, 1: Width.BYTE, 2: Width.WORD, 4: Width.DWORD}.get(size, Width.BYTE)
    if type_name == "BOOL":
        width = Width.BIT
    return Address(Area.DB, width, byte, bit, db.number), type_name


def _spelled(path: tuple[Segment, ...]) -> str:
    """A path as a layout names it: ``motor[2].on``, ``grid[1,2]``."""
    out = ""
    for step in path:
        if isinstance(step, str):
            out += f".{step}" if out else step
        else:
            out += f"[{','.join(map(str, step))}]"
    return out


def _slot_key(slots: dict[str, Any], name: str) -> str | None:
    if name in slots:
        return name
    return next((k for k in slots if k.casefold() == name.casefold()), None)


def _array_element(
    start: int, array: str, index: tuple[int, ...], where: str
) -> tuple[int, int, str]:
    """(byte, bit, element type) of ``array[index]`` laid out from byte ``start``."""
    bounds, elem = array_bounds(array), element_type(array)
    if bounds is None or not elem:
        raise WatchError(f"{where} is no ARRAY: it takes no index")
    if len(index) != len(bounds):
        raise WatchError(f"{where} takes {len(bounds)} indices, not {len(index)}")
    k = 0
    for i, (lo, hi) in zip(index, bounds, strict=True):
        if not lo <= i <= hi:
            raise WatchError(f"{where}: index {i} outside {lo}..{hi}")
        k = k * (hi - lo + 1) + (i - lo)
    if elem == "BOOL":
        return start + k // 8, k % 8, elem
    one = type_of(elem).size
    step = one + (one & 1) if one > 1 else one
    return start + k * step, 0, type_of(elem).name


def _shown(
    value: object, type_name: str, where: str
) -> tuple[bool | int | float | str | None, str]:
    """(the value at ``where`` as a JSON scalar, as S7 writes it)."""
    if type_name == "COUNTER" and isinstance(value, int):
        return value, f"C#{value}"
    if type_name and isinstance(value, bool | int | float | str | date | datetime):
        try:
            shown = format_literal(type_name, value)
        except S7Error:
            shown = ""
        if shown:
            return _scalar(value), shown
    if isinstance(value, bool):
        return value, "TRUE" if value else "FALSE"
    if isinstance(value, float):
        return (value if math.isfinite(value) else None), repr(value)
    if isinstance(value, int | str):
        return value, str(value)
    if value is None:
        return None, "NULL"
    if isinstance(value, date | datetime):
        return value.isoformat(), value.isoformat()
    names = _public_names(value)
    what = type(value).__name__
    has = f": watch one of its fields ({', '.join(names[:12])})" if names else ""
    raise WatchError(f"{where} is a {what}{has}")


def _scalar(value: object) -> bool | int | float | str | None:
    if isinstance(value, date | datetime):
        return value.isoformat()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, bool | int | float | str):
        return value
    return str(value)


# ---------------------------------------------------------------- the queryable


class Watching:
    """The ``watch`` queryable of ``cpu`` on ``publisher``'s bus; call :meth:`at_boundary`
    in the scan thread after each scan."""

    def __init__(self, cpu: Cpu, publisher: BusPublisher) -> None:
        self.cpu = cpu
        self._publisher = publisher
        self._key = publisher.key("watch")
        self._queue: SharedQueue[tuple[QueryReply, list[WatchItem]]] = SharedQueue(
            QUEUE, PER_SOURCE, UNPROVEN
        )
        publisher.declare_queryable("watch", self._on_query)

    def at_boundary(self, t_ms: int | None = None, until_ns: int | None = None) -> int:
        """Read and answer the requests waiting — the values of the scan just ended — at
        most ``PER_BOUNDARY``, and once ``until_ns`` (``time.perf_counter_ns``: the end of
        the boundary's share for communication) is past only the first; how many were
        answered."""
        cpu = self.cpu
        done = 0
        while done < PER_BOUNDARY:
            if done and until_ns is not None and time.perf_counter_ns() >= until_ns:
                break
            waiting = self._queue.get()
            if waiting is None:
                break
            reply, items = waiting
            values = [watch_value(cpu, item) for item in items]
            at = t_ms if t_ms is not None else cpu.clock.now_ns() // 1_000_000
            state = cast(CpuState, str(cpu.mode))
            answer = WatchValues(
                cycle=max(cpu.cycle, 0), t_ms=max(at, 0), state=state, values=values
            )
            self._publisher.post(reply, answer)
            done += 1
        return done

    def _on_query(self, query: zenoh.Query) -> None:
        # a zenoh thread: only the exact key, decode, check the spelling, queue; never raise
        if str(query.key_expr) != self._key:
            return
        reply = QueryReply(query, self._key)
        try:
            payload = query.payload
            if payload is None:
                raise ProtocolError("a watch request names the addresses to watch")
            request = decode(payload.to_bytes(), WatchRequest)
            items = [parse_item(text) for text in request.addresses]
            source, proven, refused = self._source(query, request)
            if refused:
                _refuse(reply, refused)
                return
            busy = self._queue.put(source, (reply, items), proven=proven)
            if busy:
                _refuse(reply, self._busy(busy, source if proven else ""))
        except ProtocolError as exc:
            _refuse(reply, str(exc))
        except Exception as exc:
            where = "in the CPU while reading a watch request"
            _refuse(reply, f"{REFUSED}{internal_error(where, exc)}")

    def _source(self, query: zenoh.Query, request: WatchRequest) -> tuple[str, bool, str]:
        """(the share ``request`` waits in, whether its source is proven, why it is refused
        — "": it is not). With a users file a request signed by a login is its user's:
        the token must be a live session of ``user``, the ``mac`` its session key's over
        ``watch_bytes`` and ``seq`` new to it, as for a command (``web.bus.gate``). Any
        other is where the transport says it came from — a claim, unless it is this
        process (``web.bus.origin``)."""
        gate = self._publisher.gate
        if request.token and not gate.auth.demo:
            who = gate.signed_by(
                request.user or "",
                request.token,
                request.mac or "",
                watch_bytes(request),
                request.seq or 0,
            )
            if isinstance(who, str):
                return "", False, f"{REFUSED}{who}"
            return who.user, True, ""
        transport = self._publisher.origin(query)[0]
        return lockout_source(transport, ""), transport == "this process", ""

    def _busy(self, why: str, user: str) -> str:
        """The refusal of a request not queued (``why``: ``SharedQueue.put``'s), of proven
        ``user`` ("": an unproven source)."""
        if why == "source":
            of = f"of {user}" if user else "from here"
            return f"busy: {PER_SOURCE} watch requests {of} are waiting; {_ONCE_ANSWERED}"
        if user:
            return f"busy: {QUEUE} watch requests of logged-in users are waiting; ask again"
        sign = "" if self._publisher.gate.auth.demo else _SIGN
        return f"busy: {UNPROVEN} watch requests not signed by a login are waiting; ask again{sign}"


_ONCE_ANSWERED: Final = "ask again once they are answered"
_SIGN: Final = ", or log in: a watch signed by a login has places of its own"


REFUSED: Final = "watch refused: "
"""How the CPU begins its refusal of a request it cannot take (a login's it does not
accept, or a fault of its own)."""


def login_refused(error: str) -> bool:
    """Whether ``error`` refuses a signed request for its login (expired, logged out, not
    signed by its session, …) — not for a fault of the CPU, which an unsigned one meets
    too."""
    return error.startswith(REFUSED) and not error.startswith(REFUSED + "internal error")


def _refuse(reply: QueryReply, reason: str) -> None:
    try:
        reply.put(encode(WatchValues(error=reason[:4096])))
    except Exception:
        return
