"""The CPU's operands on the bus: the symbol table's operands and each FB's variables and
pins, for a face that is no page (``web.opcua``, the OPC UA server) — docs/bus.md,
"Operands".

:class:`OperandFeed` reads them in the scan thread at a scan boundary, at most every
``PERIOD_MS``, and publishes an :class:`OperandValues` on ``operands`` when one changed
(the outbox's thread encodes and puts it; ``BusPublisher.feed``); ``operands/list`` serves
their :class:`OperandCatalog` (names, S7 types, addresses, comments), whose ``version``
changes when an online change brings other variables, pins or symbols. A read of an OPC
UA client is answered from what the face received here: it never reaches the CPU.

Each name is resolved to a reader once (``ChartSession.reader``), again after an online
change; one that cannot be read (an address the CPU lacks) is left out of the values, and
a symbol named like one of the FB's variables or pins is left out altogether (its name
would read the variable). It never raises into the scan.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import msgspec

from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.compiled import CompiledChart
from s7graph.sequencer.params import is_pin, pins_for
from s7graph.sequencer.text.comments import find_comments
from s7graph.web.bus.protocol import (
    FbOperands,
    OperandCatalog,
    OperandInfo,
    OperandValues,
    encode,
)

if TYPE_CHECKING:
    from s7graph.web.bus.publisher import BusPublisher
    from s7graph.web.harness.session import ChartSession

__all__ = ["MAX_SYMBOLS", "PERIOD_MS", "OperandFeed"]

PERIOD_MS = 100.0
"""At most this often the operands are read and, when changed, published."""
MAX_SYMBOLS = 4096
"""Symbols beyond this many are left out (a message's limit)."""

_Reader = tuple[str, Callable[[], object]]
_PLAIN = (bool, int, float, str)


def _scalar(value: object) -> bool | int | float | str | None:
    if value is None or isinstance(value, _PLAIN):
        return value
    return str(value)


def _comment(written: str) -> str:
    """A chart variable's comment as text: its ``//`` and ``(* … *)`` comments as written
    in the chart (``sequencer.text.comments``), without their delimiters."""
    texts = (
        c.text.removeprefix("//").removeprefix("(*").removesuffix("*)").strip()
        for c in find_comments(written)
    )
    return " ".join(t for t in texts if t)


def _read(readers: tuple[_Reader, ...]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for name, read in readers:
        try:
            out[name] = _scalar(read())
        except Exception:  # an operand the CPU cannot read now: left out
            continue
    return out


class OperandFeed:
    """The operands of ``session``'s symbol table and of its FB ``fb`` on the bus; call
    :meth:`attach` once, then :meth:`at_boundary` at every scan boundary."""

    def __init__(self, session: ChartSession, *, fb: str, period_ms: float = PERIOD_MS) -> None:
        self.session = session
        self.fb = fb
        self._period_ns = int(period_ms * 1e6)
        self._next_ns = 0
        self._made_for: tuple[CompiledChart, SymbolTable] | None = None
        self._symbols: tuple[_Reader, ...] = ()
        self._fb: tuple[_Reader, ...] = ()
        self._catalog = OperandCatalog()
        self._catalog_bytes = encode(self._catalog)
        self._last: tuple[dict[str, Any], dict[str, Any]] | None = None
        self._seq = 0
        self._post: Callable[[msgspec.Struct], None] | None = None
        self.published = 0

    def attach(self, publisher: BusPublisher) -> None:
        """Publish on ``publisher``'s bus: ``operands`` and ``operands/list``."""
        self._prepare()
        self._post = publisher.feed("operands")
        publisher.serve("operands/list", lambda: self._catalog_bytes)

    @property
    def catalog(self) -> OperandCatalog:
        return self._catalog

    def at_boundary(self, cycle: int) -> bool:
        """Read the operands if ``PERIOD_MS`` has passed and publish them if one changed
        (the scan thread, at a scan boundary); whether they went out. Never raises."""
        now = time.monotonic_ns()
        if self._post is None or now < self._next_ns:
            return False
        self._next_ns = now + self._period_ns
        try:
            session = self.session
            if self._made_for != (session.cc, session.symbols):
                self._prepare()
            values = _read(self._symbols), _read(self._fb)
            if values == self._last:
                return False
            self._last = values
            self._seq += 1
            self._post(
                OperandValues(
                    seq=self._seq,
                    cycle=max(cycle, 0),
                    catalog=self._catalog.version,
                    symbols=values[0],
                    fbs={self.fb: values[1]},
                )
            )
        except Exception:  # the scan goes on; the next boundary tries again
            return False
        self.published += 1
        return True

    def _prepare(self) -> None:
        """Readers and the catalog for the chart and symbol table the session has now."""
        session = self.session
        cc, table = session.cc, session.symbols
        pins = pins_for(cc.parameters)
        variables = [(name, t) for name, t in cc.var_types.items()]
        said = {v.name: _comment(v.trailing or v.comment) for v in cc.chart.vars}
        taken = {name for name, _ in variables} | {p.name for p in pins}
        symbols = [
            s for s in table if s.name not in taken and not is_pin(s.name) and len(s.name) <= 128
        ]
        symbols = symbols[:MAX_SYMBOLS]
        self._symbols = self._readers(s.name for s in symbols)
        self._fb = self._readers([*(n for n, _ in variables), *(p.name for p in pins)])
        catalog = OperandCatalog(
            version=self._catalog.version + 1,
            symbols=[
                OperandInfo(
                    name=s.name[:128],
                    type=s.type[:256],
                    address=str(s.address)[:64],
                    comment=s.comment[:4096],
                )
                for s in symbols
            ],
            fbs={
                self.fb: FbOperands(
                    variables=[
                        OperandInfo(name=n, type=t[:256], comment=said.get(n, "")[:4096])
                        for n, t in variables
                    ],
                    pins=[
                        OperandInfo(
                            name=p.name,
                            type=p.type,
                            comment=p.comment[:4096],
                            direction="IN" if p.direction.value == "IN" else "OUT",
                        )
                        for p in pins
                    ],
                )
            },
        )
        self._catalog = catalog
        self._catalog_bytes = encode(catalog)
        self._made_for = (cc, table)
        self._last = None

    def _readers(self, names: Any) -> tuple[_Reader, ...]:
        out: list[_Reader] = []
        for name in names:
            try:
                out.append((name, self.session.reader(name)))
            except Exception:  # unknown to the CPU (an address it lacks): left out
                continue
        return tuple(out)
