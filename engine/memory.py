"""CPU operand memory: I/Q process images, PI/PQ module side, M, L, T, C and DBs (docs/runtime.md,
"The block runtime").

Every area is a big-endian ``bytearray`` (MB10 is the high byte of MW10, Siemens' Program Design for
S7-300/400, ch. 5); timers and counters are cells (``S5Timer``/``S5Counter``) whose logic lives in
sfb/. Retentivity follows Siemens' Program Design for S7-300/400, ch. 9: by default MB0..MB15, no
timers and C0..C7 are retentive; DBs keep their contents on warm restart and reload initial values
on cold restart (docs/runtime.md, "Restarts: warm, hot, cold").
"""

from __future__ import annotations

import base64
from collections.abc import Callable, Sequence
from dataclasses import dataclass, fields
from typing import TYPE_CHECKING, Any

from s7graph.engine.address import Address, Area, Width, parse_address
from s7graph.engine.datatypes import Layout, decode, encode, ms_to_s5time, type_of
from s7graph.engine.errors import AddressError, BlockError, TypeMismatch

if TYPE_CHECKING:
    from s7graph.engine.symbols import SymbolTable

__all__ = [
    "AreaLengthError",
    "AreaWriteError",
    "DataBlock",
    "IOAccessError",
    "Memory",
    "S5Counter",
    "S5Timer",
]


class AreaLengthError(AddressError):
    """Access beyond an area or DB length: the S7 area-length error (``[K]``
    SW_FLT 16#22 read / 16#23 write); ``write`` says which."""

    def __init__(self, message: str, *, write: bool) -> None:
        super().__init__(message)
        self.write = write

    @property
    def sw_flt(self) -> int:
        """OB121 fault id: 16#22 area-length error on read, 16#23 on write."""
        return 0x23 if self.write else 0x22


class AreaWriteError(AddressError):
    """A write the program may not make: the peripheral inputs (PI) are the modules' side,
    read-only to blocks (``[K]`` OB121 SW_FLT 16#25, area error on write)."""

    write = True
    sw_flt = 0x25


class IOAccessError(AddressError):
    """Direct access to a peripheral address no module answers (PI/PQ outside the modules):
    the S7 I/O access error, OB122 (``[K]`` SW_FLT 16#42 on read, 16#43 on write; Siemens'
    Program Design for S7-300/400, ch. 3-4). ``address`` names the operand."""

    def __init__(self, message: str, *, write: bool, address: str) -> None:
        super().__init__(message)
        self.write = write
        self.address = address

    @property
    def sw_flt(self) -> int:
        """OB122 fault id: 16#42 I/O access error on read, 16#43 on write."""
        return 0x43 if self.write else 0x42


IOErrorHandler = Callable[[IOAccessError], int]
"""``handler(error) -> replacement``: what ``Memory.io_error`` calls (the CPU's OB122)."""


@dataclass(slots=True)
class S5Timer:
    """One S5 timer cell ``T n`` (El-Shahat's S7-300/400 course, timers and counters); sfb/ runs the
    timer functions.

    ``value_ms`` is the remaining time, counted in steps of ``time_base_ms``.
    """

    value_ms: int = 0
    preset_ms: int = 0
    time_base_ms: int = 10
    running: bool = False
    q: bool = False
    start_ns: int = 0
    mode: str = ""  # SP SE SD SS SF: the function last started
    s_edge: bool = False  # last RLO at the start input (edge memory)
    fr_edge: bool = False  # last RLO at FR (enable)
    resume: bool = False  # restored running: ``start_ns`` is another clock's until the next
    # tick rebases it on the time left (``sfb.s5_timers.tick``)

    def binary(self) -> int:
        """``L T n``: remaining time in time-base units, binary (El-Shahat's S7-300/400 course,
        timers and counters)."""
        return self.value_ms // self.time_base_ms

    def bcd(self) -> int:
        """``LC T n``: remaining time as an S5TIME word (BCD + time base, El-Shahat's S7-300/400
        course, timers and counters)."""
        code = {10: 0, 100: 1, 1000: 2, 10000: 3}.get(self.time_base_ms)
        if code is None:
            return ms_to_s5time(self.value_ms)
        count = min(self.binary(), 999)
        return (code << 12) | int(str(count), 16)

    def reset(self) -> None:
        """Back to the power-on state (value 0, Q 0, stopped, edges cleared)."""
        for f in fields(self):
            setattr(self, f.name, f.default)


@dataclass(slots=True)
class S5Counter:
    """One S5 counter cell ``C n`` / ``Z n``: value 0..999, ``q`` = value > 0 (El-Shahat's
    S7-300/400 course, timers and counters)."""

    value: int = 0
    q: bool = False
    cu_edge: bool = False
    cd_edge: bool = False
    s_edge: bool = False
    r_edge: bool = False
    fr_edge: bool = False

    def set_value(self, value: int) -> None:
        """Set the count clamped to 0..999 and update ``q`` (no wrap, El-Shahat's S7-300/400 course,
        timers and counters)."""
        self.value = max(0, min(999, value))
        self.q = self.value > 0

    def bcd(self) -> int:
        """``LC C n``: the count as 3 BCD digits."""
        return int(str(self.value), 16)

    def reset(self) -> None:
        for f in fields(self):
            setattr(self, f.name, f.default)


@dataclass(eq=False)
class DataBlock:
    """A global or instance DB: ``data`` is the live image, ``initial`` the load-memory values.

    ``retain`` DBs are kept by snapshot/restore; ``created`` marks DBs made at run time
    (SFC22), which a cold restart deletes.
    """

    number: int
    data: bytearray
    retain: bool = True
    initial: bytes = b""
    layout: Layout | None = None
    name: str = ""
    created: bool = False

    def __len__(self) -> int:
        return len(self.data)

    def reset(self) -> None:
        """Reload the initial values (cold restart, docs/runtime.md, "Restarts: warm, hot,
        cold")."""
        self.data[:] = self.initial.ljust(len(self.data), b"\0")[: len(self.data)]

    def field_address(self, name: str) -> Address:
        """The address of a named field of ``layout`` (BOOL → DBX, else DBB of its start)."""
        if self.layout is None or name not in self.layout.slots:
            raise AddressError(f"DB{self.number} has no field {name!r}")
        slot = self.layout.slots[name]
        width = {0: Width.BIT, 2: Width.WORD, 4: Width.DWORD}.get(slot.size, Width.BYTE)
        if slot.type == "BOOL":
            width = Width.BIT
        return Address(Area.DB, width, slot.byte, slot.bit, self.number)


def _b64(data: bytes | bytearray) -> str:
    return base64.b64encode(bytes(data)).decode("ascii")


class Memory:
    """All operand areas of one CPU, addressed by ``Address`` (docs/architecture.md, "Seams").

    ``read``/``write`` move raw unsigned values (BIT → bool); ``read_as``/``write_as``
    convert S7 types. Fast paths for compiled code: ``read_bit``/``write_bit`` and
    ``area_bytes`` (the live bytearray).
    """

    def __init__(
        self,
        *,
        inputs: int = 128,
        outputs: int = 128,
        markers: int = 256,
        timers: int = 256,
        counters: int = 256,
        local: int = 1024,
        periph_in: int = 1024,
        periph_out: int = 1024,
        retentive_markers: range = range(0, 16),
        retentive_timers: range = range(0, 0),
        retentive_counters: range = range(0, 8),
        pq_updates_q: bool = True,
    ) -> None:
        self.inputs = bytearray(inputs)
        self.outputs = bytearray(outputs)
        self.markers = bytearray(markers)
        self.local = bytearray(local)
        self.periph_in = bytearray(periph_in)
        self.periph_out = bytearray(periph_out)
        self.timers: list[S5Timer] = [S5Timer() for _ in range(timers)]
        self.counters: list[S5Counter] = [S5Counter() for _ in range(counters)]
        self.dbs: dict[int, DataBlock] = {}
        self.retentive_markers = retentive_markers
        self.retentive_timers = retentive_timers
        self.retentive_counters = retentive_counters
        self.pq_updates_q = pq_updates_q
        """Writing PQ inside the Q image also updates Q (Siemens' Program Design for S7-300/400, ch.
        5)."""
        self.symbols: SymbolTable | None = None
        self.io_error: IOErrorHandler | None = None
        """Called for an I/O access error (``IOAccessError``) instead of raising it: the CPU
        runs OB122 there; a read returns what it returns (the REPL_VAL replacement value), a
        write is not made. None: the error is raised."""
        self.pi_locked = False
        """True while the program runs (the CPU sets it around every OB): a write to PI is
        then an ``AreaWriteError``. The modules' side — a plant, a stimulus — writes PI."""
        self.no_db: Callable[[int], str] | None = None
        """Why a DB has no bytes (the CPU says: an FB's instance DB, by name only); None:
        ``DB<n> does not exist``."""
        self._areas: dict[str, bytearray] = {
            Area.I: self.inputs,
            Area.Q: self.outputs,
            Area.M: self.markers,
            Area.L: self.local,
            Area.PI: self.periph_in,
            Area.PQ: self.periph_out,
        }

    # ---- fast paths ----------------------------------------------------------------------

    def area_bytes(self, area: Area | str, db: int | None = None) -> bytearray:
        """The live bytearray of ``area`` (or of DB ``db``); compiled code may index it."""
        buf = self._areas.get(area)  # StrEnum: "I" and Area.I are the same key
        if buf is not None:
            return buf
        if area == Area.DB:
            if db is None or db not in self.dbs:
                why = self.no_db(db) if self.no_db is not None and db is not None else ""
                raise AddressError(why or f"DB{db} does not exist")
            return self.dbs[db].data
        raise AddressError(f"area {area} has no byte image")

    def read_bit(self, area: Area | str, byte: int, bit: int, db: int | None = None) -> bool:
        """One bit (``I0.3`` = bit 3 of IB0, Siemens' Program Design for S7-300/400, ch. 5)."""
        buf = self.area_bytes(area, db)
        if not 0 <= byte < len(buf):
            raise AreaLengthError(f"{_name(area, byte, bit, db)} is outside the area", write=False)
        return bool(buf[byte] >> bit & 1)

    def write_bit(
        self, area: Area | str, byte: int, bit: int, value: bool, db: int | None = None
    ) -> None:
        buf = self.area_bytes(area, db)
        if not 0 <= byte < len(buf):
            raise AreaLengthError(f"{_name(area, byte, bit, db)} is outside the area", write=True)
        if value:
            buf[byte] |= 1 << bit
        else:
            buf[byte] &= ~(1 << bit) & 0xFF
        if area == Area.PQ and self.pq_updates_q and byte < len(self.outputs):
            self.outputs[byte] = buf[byte]

    # ---- raw access ----------------------------------------------------------------------

    def _span(self, addr: Address, size: int, write: bool) -> bytearray:
        try:
            buf = self.area_bytes(addr.area, addr.db)
        except AddressError as exc:
            raise AddressError(f"{addr}: {exc.message}") from None
        if write and self.pi_locked and addr.area is Area.PI:
            raise AreaWriteError(f"{addr}: the peripheral inputs are read-only to the program")
        if addr.byte + size > len(buf):
            if addr.area is Area.PI or addr.area is Area.PQ:
                where = f"{addr.area} ends at byte {len(buf) - 1}"
                raise IOAccessError(
                    f"{addr}: no module at this address ({where})", write=write, address=str(addr)
                )
            what = f"DB{addr.db} length {len(buf)}" if addr.db else f"{addr.area} size {len(buf)}"
            raise AreaLengthError(f"{addr} is outside {what}", write=write)
        return buf

    def _cell(self, addr: Address) -> S5Timer | S5Counter:
        cells: list[S5Timer] | list[S5Counter] = (
            self.timers if addr.area is Area.T else self.counters
        )
        if addr.byte >= len(cells):
            raise AddressError(f"{addr}: only {len(cells)} {addr.area} cells exist")
        return cells[addr.byte]

    def read(self, addr: Address) -> int | bool:
        """Raw value: BIT → bool, else unsigned big-endian int; ``T n``/``C n`` → binary value."""
        buf = self._areas.get(addr.area)
        if buf is not None and addr.width is Width.BIT and addr.byte < len(buf):
            return bool(buf[addr.byte] >> addr.bit & 1)  # the hot path
        if addr.area is Area.T or addr.area is Area.C:
            cell = self._cell(addr)
            return cell.binary() if isinstance(cell, S5Timer) else cell.value
        try:
            buf = self._span(addr, addr.size, write=False)
        except IOAccessError as err:
            return self._replacement(err, addr.size)
        if addr.width is Width.BIT:
            return bool(buf[addr.byte] >> addr.bit & 1)
        return int.from_bytes(buf[addr.byte : addr.byte + addr.size], "big")

    def write(self, addr: Address, value: int | bool) -> None:
        """Store a raw unsigned value; a value outside the width raises TypeMismatch."""
        if addr.area in (Area.T, Area.C):
            self._write_cell(addr, "WORD", value)
            return
        if addr.width is Width.BIT:
            if value not in (0, 1):
                raise TypeMismatch(f"{value!r} does not fit the bit {addr}")
            self._span(addr, 1, write=True)
            self.write_bit(addr.area, addr.byte, addr.bit, bool(value), addr.db)
            return
        if not isinstance(value, int) or not 0 <= value < 1 << addr.width:
            raise TypeMismatch(f"{value!r} does not fit {addr} (0..{(1 << addr.width) - 1})")
        self._store(addr, value.to_bytes(addr.size, "big"))

    def _replacement(self, err: IOAccessError, size: int) -> int:
        """An I/O access error: the handler's replacement value for a read of ``size``
        bytes (its low bytes), 0 for a write; raised when there is no handler."""
        if self.io_error is None:
            raise err
        return self.io_error(err) & ((1 << 8 * size) - 1)

    def _store(self, addr: Address, data: bytes) -> None:
        try:
            buf = self._span(addr, len(data), write=True)
        except IOAccessError as err:
            self._replacement(err, 0)  # OB122 ran; the write is not made
            return
        end = addr.byte + len(data)
        buf[addr.byte : end] = data
        if addr.area is Area.PQ and self.pq_updates_q and end <= len(self.outputs):
            self.outputs[addr.byte : end] = data

    # ---- typed access --------------------------------------------------------------------

    def _check_fit(self, addr: Address, type_name: str) -> str:
        spec = type_of(type_name)
        if spec.size_bits <= 32 and spec.size_bits != addr.width:
            raise TypeMismatch(f"{addr} is a {addr.width.name}, not a {spec.name}")
        if spec.size_bits > 32 and addr.width is Width.BIT:
            raise TypeMismatch(f"{addr} is a bit, not the start of a {spec.name}")
        return spec.name

    def read_as(self, addr: Address, type_name: str) -> object:
        """Read ``addr`` as ``type_name`` (INT signed, REAL float, TIME ms, DATE date …).

        Types up to 32 bits must match the address width; longer types (DT, STRING[n])
        read from the address's first byte. Timer/counter cells: BOOL → Q, WORD/INT →
        binary value, S5TIME → remaining ms.
        """
        if addr.area in (Area.T, Area.C):
            return self._read_cell(addr, type_name)
        name = self._check_fit(addr, type_name)
        if addr.width is Width.BIT:
            return self.read(addr)
        spec = type_of(name)
        try:
            buf = self._span(addr, spec.size, write=False)
        except IOAccessError as err:
            return decode(name, self._replacement(err, spec.size).to_bytes(spec.size, "big"))
        return decode(name, buf[addr.byte : addr.byte + spec.size])

    def write_as(self, addr: Address, type_name: str, value: object) -> None:
        """Encode ``value`` as ``type_name`` at ``addr``; out of range raises TypeMismatch."""
        if addr.area in (Area.T, Area.C):
            self._write_cell(addr, type_name, value)
            return
        name = self._check_fit(addr, type_name)
        if addr.width is Width.BIT:
            data = encode("BOOL", value)
            self._span(addr, 1, write=True)
            self.write_bit(addr.area, addr.byte, addr.bit, data == b"\x01", addr.db)
            return
        self._store(addr, encode(name, value))

    def _read_cell(self, addr: Address, type_name: str) -> object:
        cell = self._cell(addr)
        name = type_of(type_name).name
        if name == "BOOL":
            return cell.q
        if name == "S5TIME" and isinstance(cell, S5Timer):
            return cell.value_ms
        if name in ("WORD", "INT", "TIMER", "COUNTER"):
            return cell.binary() if isinstance(cell, S5Timer) else cell.value
        raise TypeMismatch(f"{addr} cannot be read as {name}")

    def _write_cell(self, addr: Address, type_name: str, value: object) -> None:
        cell = self._cell(addr)
        if isinstance(cell, S5Counter) and isinstance(value, int) and 0 <= value <= 999:
            cell.set_value(value)
            return
        raise TypeMismatch(
            f"{addr} cannot be written as {type_name} {value!r}: timer cells change only "
            "through timer instructions, counters take 0..999"
        )

    # ---- text convenience ----------------------------------------------------------------

    def _resolve(self, text: str) -> tuple[Address, str | None]:
        if self.symbols is not None:
            sym = self.symbols.lookup(text)
            if sym is not None:
                return sym.address, sym.type
        return parse_address(text), None

    def get(self, text: str) -> object:
        """Value at an address or symbol text; symbols read as their declared type."""
        addr, type_name = self._resolve(text)
        if type_name is not None and type_name not in ("TIMER", "COUNTER"):
            return self.read_as(addr, type_name)
        return self.read(addr)

    def set(self, text: str, value: object) -> None:
        """Write an address or symbol: symbols as their type; bare addresses take bool/int
        (negative → INT/DINT) or float (→ REAL on a dword)."""
        addr, type_name = self._resolve(text)
        if type_name is not None and type_name not in ("TIMER", "COUNTER"):
            self.write_as(addr, type_name, value)
        elif isinstance(value, float):
            self.write_as(addr, "REAL", value)
        elif isinstance(value, int) and value < 0 and addr.width in (Width.WORD, Width.DWORD):
            self.write_as(addr, "INT" if addr.width is Width.WORD else "DINT", value)
        elif isinstance(value, int):
            self.write(addr, value)
        else:
            raise TypeMismatch(f"cannot write {value!r} to {text}")

    # ---- data blocks ---------------------------------------------------------------------

    def create_db(
        self,
        number: int,
        size: int,
        *,
        init: bytes | None = None,
        retain: bool = True,
        layout: Layout | None = None,
        name: str = "",
        created: bool = False,
    ) -> DataBlock:
        """Create DB ``number`` with ``size`` bytes from ``init`` (zero-padded).

        An existing number or an ``init`` longer than ``size`` raises BlockError.
        """
        if not 1 <= number <= 65535:
            raise BlockError(f"DB{number}: number outside 1..65535")
        if number in self.dbs:
            raise BlockError(f"DB{number} already exists")
        initial = bytes(init or b"")
        if len(initial) > size:
            raise BlockError(f"DB{number}: {len(initial)} initial bytes exceed size {size}")
        initial = initial.ljust(size, b"\0")
        db = DataBlock(number, bytearray(initial), retain, initial, layout, name, created)
        self.dbs[number] = db
        return db

    def delete_db(self, number: int) -> None:
        if self.dbs.pop(number, None) is None:
            raise BlockError(f"DB{number} does not exist")

    # ---- restart and persistence (docs/runtime.md, "Restarts: warm, hot, cold", Siemens' Program
    # Design for S7-300/400, ch. 9) ---------------------

    def clear_non_retentive(self) -> None:
        """Warm restart: zero non-retentive M, reset non-retentive T/C cells, clear L.

        Retentive ranges and all DBs are kept.
        """
        keep = self.retentive_markers
        for i in range(len(self.markers)):
            if i not in keep:
                self.markers[i] = 0
        _reset_cells(self.timers, self.retentive_timers)
        _reset_cells(self.counters, self.retentive_counters)
        self.local[:] = bytes(len(self.local))

    def clear_outputs(self, *, image: bool = True, modules: bool = True) -> None:
        """The safe output state (docs/runtime.md, "Restarts: warm, hot, cold"): zero the output
        image Q (``image``) and the module side PQ (``modules``). STOP and HOLD zero only the
        modules, a startup both or as its restart type says; the one way the CPU resets outputs."""
        if image:
            self.outputs[:] = bytes(len(self.outputs))
        if modules:
            self.periph_out[:] = bytes(len(self.periph_out))

    def reset_to_initial(self) -> None:
        """Cold restart: every M/T/C/L/I/Q/PQ zeroed, run-time DBs deleted, other DBs back
        to their initial values."""
        for buf in self._areas.values():
            buf[:] = bytes(len(buf))
        _reset_cells(self.timers, range(0))
        _reset_cells(self.counters, range(0))
        for number in [n for n, db in self.dbs.items() if db.created]:
            del self.dbs[number]
        for db in self.dbs.values():
            db.reset()

    def snapshot(self) -> dict[str, Any]:
        """The retentive state as JSON-able data: retentive M bytes, T/C cells, retain DBs."""
        rm = self.retentive_markers
        return {
            "markers": {"start": rm.start, "data": _b64(self.markers[rm.start : rm.stop])},
            "timers": {
                str(i): _cell(self.timers[i]) for i in _within(self.retentive_timers, self.timers)
            },
            "counters": {
                str(i): _cell(self.counters[i])
                for i in _within(self.retentive_counters, self.counters)
            },
            "dbs": {
                str(n): {"data": _b64(db.data), "initial": _b64(db.initial), "created": db.created}
                for n, db in self.dbs.items()
                if db.retain
            },
        }

    def hot_snapshot(self) -> dict[str, Any]:
        """What a hot restart keeps beyond ``snapshot()``: every marker byte, the output
        image Q, and the timer and counter cells that are not at rest."""
        return {
            "markers": _b64(self.markers),
            "outputs": _b64(self.outputs),
            "timers": {str(i): _cell(self.timers[i]) for i in _busy_timers(self.timers)},
            "counters": {str(i): _cell(self.counters[i]) for i in _busy_counters(self.counters)},
        }

    def restore_hot(self, data: dict[str, Any]) -> None:
        """Apply a ``hot_snapshot()`` (before ``restore``, which then puts the retentive
        parts on top)."""
        for area, key in ((self.markers, "markers"), (self.outputs, "outputs")):
            raw = base64.b64decode(data[key])
            area[: len(raw)] = raw[: len(area)]
        _restore_cells(self.timers, data.get("timers", {}), S5Timer)
        _restore_cells(self.counters, data.get("counters", {}), S5Counter)

    def restore(self, data: dict[str, Any]) -> None:
        """Apply a ``snapshot()``: retentive parts come back; DBs are recreated if missing."""
        marks = data.get("markers")
        if marks:
            raw = base64.b64decode(marks["data"])
            start = int(marks["start"])
            self.markers[start : start + len(raw)] = raw
        _restore_cells(self.timers, data.get("timers", {}), S5Timer)
        _restore_cells(self.counters, data.get("counters", {}), S5Counter)
        for key, item in data.get("dbs", {}).items():
            number, raw = int(key), base64.b64decode(item["data"])
            db = self.dbs.get(number)
            if db is None:
                initial = base64.b64decode(item.get("initial", "")) or raw
                db = self.create_db(
                    number, len(raw), init=initial, created=item.get("created", False)
                )
            db.data[:] = raw.ljust(len(db.data), b"\0")[: len(db.data)]


def _name(area: Area | str, byte: int, bit: int, db: int | None) -> str:
    return f"DB{db}.DBX{byte}.{bit}" if db is not None else f"{area}{byte}.{bit}"


def _busy_timers(cells: Sequence[S5Timer]) -> list[int]:
    """The timer cells not at rest (one loop without a call per cell: runs every scan)."""
    return [
        i
        for i, c in enumerate(cells)
        if c.running or c.q or c.value_ms or c.s_edge or c.fr_edge or c.mode
    ]


def _busy_counters(cells: Sequence[S5Counter]) -> list[int]:
    """The counter cells not at rest."""
    return [
        i
        for i, c in enumerate(cells)
        if c.value or c.q or c.cu_edge or c.cd_edge or c.s_edge or c.r_edge or c.fr_edge
    ]


def _within(keep: range, cells: Sequence[S5Timer | S5Counter]) -> range:
    return range(max(0, keep.start), min(keep.stop, len(cells)))


def _reset_cells(cells: Sequence[S5Timer | S5Counter], keep: range) -> None:
    for i, cell in enumerate(cells):
        if i not in keep:
            cell.reset()


def _restore_cells(
    cells: Sequence[S5Timer | S5Counter],
    saved: dict[str, dict[str, Any]],
    kind: Callable[..., S5Timer | S5Counter],
) -> None:
    for key, values in saved.items():
        i = int(key)
        if 0 <= i < len(cells):
            fresh = kind(**values)
            for f in fields(fresh):
                setattr(cells[i], f.name, getattr(fresh, f.name))
            cell = cells[i]
            if isinstance(cell, S5Timer):
                cell.resume = cell.running


_CELL_FIELDS: dict[type, tuple[str, ...]] = {}


def _cell(cell: S5Timer | S5Counter) -> dict[str, Any]:
    """A timer or counter cell as plain data (``asdict`` without its deep copies: the fields
    are scalars), taken every scan by the state store."""
    names = _CELL_FIELDS.get(type(cell))
    if names is None:
        names = _CELL_FIELDS[type(cell)] = tuple(f.name for f in fields(cell))
    return {name: getattr(cell, name) for name in names}
