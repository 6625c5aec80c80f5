"""A Read's or a Write's ``IndexRange`` (OPC UA Part 4, 7.27 "NumericRange"; docs/opcua.md,
"Values and their status"): asyncua ignored it, so a client asking for one element of
``ActiveSteps`` got the whole array, and a write of a range wrote the whole value.

A read of a range answers that part of an array value (a String or ByteString is an array
of its characters or bytes, and a second dimension takes part of each String of an array
of them); an upper bound past the end gives what there is. A range whose syntax is not
Part 4's is ``BadIndexRangeInvalid``; a valid one that selects nothing — a lower bound
past the end, a scalar that is no String, more dimensions than the value has —
``BadIndexRangeNoData``. The face's writable variables are scalars written whole: a write
with a range is ``BadIndexRangeInvalid`` or ``BadWriteNotSupported``.
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Sequence
from typing import Any, Final

from asyncua import ua

from s7graph.web.opcua.typed import AttributeIds, StatusCodes, data_value, ua_status

__all__ = ["follow_ranges", "item_problem", "parse_range", "read_ranges", "write_problem"]

_DIMENSION: Final = re.compile(r"(\d{1,9})(?::(\d{1,9}))?")


class RangeError(ValueError):
    """A range that cannot be served: ``status`` says why."""

    def __init__(self, status: int) -> None:
        super().__init__(ua_status(status).name)
        self.status = status


def parse_range(text: str) -> list[tuple[int, int]]:
    """The dimensions of ``text`` as inclusive (first, last) pairs; ``BadIndexRangeInvalid``
    for anything but ``n`` or ``n:m`` (n < m) joined by commas."""
    dims: list[tuple[int, int]] = []
    for part in text.split(","):
        found = _DIMENSION.fullmatch(part)
        if found is None:
            raise RangeError(StatusCodes.BadIndexRangeInvalid)
        first = int(found.group(1))
        last = int(found.group(2)) if found.group(2) is not None else first
        if found.group(2) is not None and last <= first:
            raise RangeError(StatusCodes.BadIndexRangeInvalid)
        dims.append((first, last))
    return dims


def _cut(items: Any, dim: tuple[int, int]) -> Any:
    """``items[first..last]``; ``BadIndexRangeNoData`` when ``first`` is past the end."""
    first, last = dim
    if first >= len(items):
        raise RangeError(StatusCodes.BadIndexRangeNoData)
    return items[first : last + 1]


def _part(variant: ua.Variant, dims: Sequence[tuple[int, int]]) -> ua.Variant:
    """The part of ``variant`` that ``dims`` selects."""
    value = variant.Value
    textual = variant.VariantType in (ua.VariantType.String, ua.VariantType.ByteString)
    if isinstance(value, list):
        if len(dims) > 2 or (len(dims) == 2 and not textual):
            raise RangeError(StatusCodes.BadIndexRangeNoData)
        items = _cut(value, dims[0])
        if len(dims) == 2:
            items = [_cut(item or "", dims[1]) for item in items]
        return ua.Variant(items, variant.VariantType, is_array=True)
    if textual and isinstance(value, str | bytes) and len(dims) == 1:
        return ua.Variant(_cut(value, dims[0]), variant.VariantType)
    raise RangeError(StatusCodes.BadIndexRangeNoData)


def _ranged(asked: ua.ReadValueId, value: ua.DataValue) -> ua.DataValue:
    """``value`` as a read of ``asked`` answers it: its range's part, or a bad status."""
    if not asked.IndexRange or asked.AttributeId != AttributeIds.Value:
        return value
    status = value.StatusCode
    if status is not None and status.is_bad():
        return value
    try:
        dims = parse_range(asked.IndexRange)
        if value.Value is None or value.Value.Value is None:
            raise RangeError(StatusCodes.BadIndexRangeNoData)
        part = _part(value.Value, dims)
    except RangeError as refused:
        return data_value(code=refused.status)
    return dataclasses.replace(value, Value=part)  # a copy: the address space keeps its own


def read_ranges(asked: Sequence[ua.ReadValueId], values: list[ua.DataValue]) -> list[ua.DataValue]:
    """The values of a Read with each one's ``IndexRange`` applied."""
    return [_ranged(a, v) for a, v in zip(asked, values, strict=False)]


def write_problem(asked: ua.WriteValue) -> int | None:
    """Why a write is refused for its range (None: it has none)."""
    if not asked.IndexRange:
        return None
    try:
        parse_range(asked.IndexRange)
    except RangeError as refused:
        return refused.status
    return StatusCodes.BadWriteNotSupported


def item_problem(item: ua.MonitoredItemCreateRequest) -> int | None:
    """Why a monitored item is not made for its range (None: it has none, or a valid one)."""
    rng = item.ItemToMonitor.IndexRange
    if not rng or item.ItemToMonitor.AttributeId != AttributeIds.Value:
        return None
    try:
        parse_range(rng)
    except RangeError as refused:
        return refused.status
    return None


def follow_ranges(service: Any) -> None:
    """Make a subscription's monitored item ``service`` (asyncua's
    ``MonitoredItemService``) notify each data change item of the part of the value its
    ``IndexRange`` selects, as a Read answers it — its first value too."""
    if getattr(service, "_s7graph_ranges", False):
        return
    plain = service.datachange_callback

    async def ranged(handle: int, value: ua.DataValue, error: ua.StatusCode | None = None) -> None:
        mid = service._monitored_datachange.get(handle)
        data = service._monitored_items.get(mid)
        asked = getattr(data, "read_value_id", None)
        if error is None and isinstance(asked, ua.ReadValueId):
            value = _ranged(asked, value)
        await plain(handle, value, error)

    service.datachange_callback = ranged
    service._s7graph_ranges = True
