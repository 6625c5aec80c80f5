"""Browse results in pages: continuation points and ``BrowseNext`` (docs/opcua.md,
"Limits").

asyncua answers a Browse with every reference of a node whatever the client's
``RequestedMaxReferencesPerNode``, and has no ``BrowseNext``: a client that asked for
100 references at a time got the 1,000 steps of a sequence in one answer, and its
``BrowseNext`` was ``BadServiceUnsupported``. :class:`Pages` keeps, per session, what a
Browse left over past the client's maximum under a continuation point (OPC UA Part 4,
"ContinuationPoint"), at most ``MAX_CONTINUATIONS`` at once: past them a node that needs
one is ``BadNoContinuationPoints``, without references, as Part 4 gives it. ``BrowseNext``
hands out the next page under a new point, or releases the points it is given; a point
unknown — never given, given to another session, used or released already — is
``BadContinuationPointInvalid``.

asyncua also fills every field of a reference whatever the Browse's ``ResultMask``:
:func:`masked` leaves each field the mask does not ask for at its null value (Part 4,
"Browse", ``resultMask``; the target's ``NodeId`` always), before the pages are cut.
"""

from __future__ import annotations

import secrets
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Final

from asyncua import ua

from s7graph.web.opcua.typed import StatusCodes, ua_status

__all__ = ["MAX_CONTINUATIONS", "Pages", "masked"]

MAX_CONTINUATIONS: Final = 8
"""Continuation points one session holds at once
(``ServerCapabilities/MaxBrowseContinuationPoints`` says so)."""


_FIELDS: Final = (
    (ua.BrowseResultMask.ReferenceTypeId, "ReferenceTypeId"),
    (ua.BrowseResultMask.IsForward, "IsForward"),
    (ua.BrowseResultMask.NodeClass, "NodeClass"),
    (ua.BrowseResultMask.BrowseName, "BrowseName"),
    (ua.BrowseResultMask.DisplayName, "DisplayName"),
    (ua.BrowseResultMask.TypeDefinition, "TypeDefinition"),
)


def masked(asked: Sequence[ua.BrowseDescription], results: Sequence[ua.BrowseResult]) -> None:
    """Each of ``results``' references with only the fields its description's
    ``ResultMask`` asks for, the others null: new references, the address space's own
    are left as they are."""
    for description, result in zip(asked, results, strict=False):
        mask = description.ResultMask or 0
        if mask & ua.BrowseResultMask.All == ua.BrowseResultMask.All:
            continue
        result.References = [_only(reference, mask) for reference in result.References]


def _only(reference: ua.ReferenceDescription, mask: int) -> ua.ReferenceDescription:
    """A copy of ``reference``: its target and the fields of ``mask``, the others null
    (``IsForward`` false)."""
    kept = ua.ReferenceDescription(NodeId=reference.NodeId, IsForward=False)
    for bit, field in _FIELDS:
        if mask & bit:
            setattr(kept, field, getattr(reference, field))
    return kept


@dataclass
class _Left:
    references: list[ua.ReferenceDescription]
    size: int  # the page size the Browse asked for


class Pages:
    """One session's continuation points: what its Browses left over."""

    def __init__(self) -> None:
        self._left: dict[bytes, _Left] = {}

    def __len__(self) -> int:
        return len(self._left)

    def browsed(self, size: int, results: Sequence[ua.BrowseResult]) -> None:
        """Cut each of a Browse's ``results`` to ``size`` references (0: no limit), the
        rest under a continuation point."""
        if size <= 0:
            return
        for result in results:
            if len(result.References) > size:
                self._page(result, _Left(list(result.References), size))

    def _page(self, result: ua.BrowseResult, left: _Left) -> None:
        """``result`` as the next page of ``left``, a point for what is left after it."""
        result.References = left.references[: left.size]
        rest = left.references[left.size :]
        result.ContinuationPoint = None
        if not rest:
            return
        if len(self._left) >= MAX_CONTINUATIONS:
            result.References = []
            result.StatusCode = ua_status(StatusCodes.BadNoContinuationPoints)
            return
        point = secrets.token_bytes(16)
        self._left[point] = _Left(rest, left.size)
        result.ContinuationPoint = point

    def next(self, params: ua.BrowseNextParameters) -> list[ua.BrowseResult]:
        """``BrowseNext``: the next page of each point, or each released."""
        results = []
        for point in params.ContinuationPoints or []:
            result = ua.BrowseResult()
            left = self._left.pop(point, None) if isinstance(point, bytes) else None
            if left is None:
                result.StatusCode = ua_status(StatusCodes.BadContinuationPointInvalid)
            elif not params.ReleaseContinuationPoints:
                self._page(result, left)
            results.append(result)
        return results
