"""Browsing a node with more references than a client asks for at once, with a real
asyncua client: the face answers pages of the size asked, each with a continuation point
for the rest, served by ``BrowseNext``; a point used, released or of another session is
``BadContinuationPointInvalid``, and past the session's points a node that needs one is
``BadNoContinuationPoints`` (OPC UA Part 4, "Browse", "BrowseNext"; docs/opcua.md,
"Limits")."""

from __future__ import annotations

from collections.abc import Iterator
from typing import TYPE_CHECKING, Any

import pytest
from asyncua import ua

from s7graph.web.opcua.paging import MAX_CONTINUATIONS
from tests.web.opcua.helpers import FaceRig, connected, face_rig, run

if TYPE_CHECKING:
    from tests.conftest import BusCerts

pytestmark = pytest.mark.timeout(120)

FB = ua.NodeId("cpu1/Seq_mix", 2)


@pytest.fixture(scope="module")
def face(tmp_path_factory: pytest.TempPathFactory, bus_certs: BusCerts) -> Iterator[FaceRig]:
    with face_rig(tmp_path_factory.mktemp("paging"), bus_certs) as rig:
        yield rig


def _browse(
    *nodes: ua.NodeId, size: int, mask: int = ua.BrowseResultMask.All
) -> ua.BrowseParameters:
    params = ua.BrowseParameters()
    params.RequestedMaxReferencesPerNode = size
    for nid in nodes:
        description = ua.BrowseDescription()
        description.NodeId = nid
        description.BrowseDirection = ua.BrowseDirection.Both
        description.ResultMask = mask
        params.NodesToBrowse.append(description)
    return params


def _next(*points: bytes, release: bool = False) -> ua.BrowseNextParameters:
    return ua.BrowseNextParameters(ReleaseContinuationPoints=release, ContinuationPoints=[*points])


def _ids(result: ua.BrowseResult) -> list[str]:
    return [
        f"{r.ReferenceTypeId.to_string()} {r.IsForward} {r.NodeId.to_string()}"
        for r in result.References
    ]


def test_a_browse_asking_for_fewer_references_gets_pages_and_browse_next_the_rest(
    face: FaceRig,
) -> None:
    async def check() -> None:
        async with connected(face.url) as c:
            ua_client: Any = c.uaclient
            (whole,) = await ua_client.browse(_browse(FB, size=0))
            assert whole.ContinuationPoint is None and len(whole.References) > 20
            (page,) = await ua_client.browse(_browse(FB, size=7))
            seen, point = _ids(page), page.ContinuationPoint
            assert len(seen) == 7 and point
            while point:
                (page,) = await ua_client.browse_next(_next(point))
                assert page.StatusCode.is_good() and 0 < len(page.References) <= 7
                seen, used, point = seen + _ids(page), point, page.ContinuationPoint
            assert seen == _ids(whole)  # every reference once, in order
            (again,) = await ua_client.browse_next(_next(used))
            assert again.StatusCode.value == ua.StatusCodes.BadContinuationPointInvalid

    run(check())


def test_continuation_points_are_bounded_released_and_the_sessions_own(face: FaceRig) -> None:
    async def check() -> None:
        async with connected(face.url) as c, connected(face.url) as other:
            ua_client: Any = c.uaclient
            results = await ua_client.browse(_browse(*[FB] * (MAX_CONTINUATIONS + 1), size=1))
            points = [r.ContinuationPoint for r in results[:MAX_CONTINUATIONS]]
            assert all(points) and len(set(points)) == MAX_CONTINUATIONS
            last = results[-1]
            assert last.StatusCode.value == ua.StatusCodes.BadNoContinuationPoints
            assert last.References == [] and last.ContinuationPoint is None
            (theirs,) = await other.uaclient.browse_next(_next(points[0]))
            assert theirs.StatusCode.value == ua.StatusCodes.BadContinuationPointInvalid
            released = await ua_client.browse_next(_next(*points, release=True))
            assert [r.StatusCode.is_good() and not r.References for r in released] == [True] * len(
                points
            )
            (page,) = await ua_client.browse(_browse(FB, size=1))
            assert page.StatusCode.is_good() and page.ContinuationPoint  # free again

    run(check())


def test_a_browse_returns_only_the_fields_its_result_mask_asks_for_on_every_page(
    face: FaceRig,
) -> None:
    def fields(r: ua.ReferenceDescription) -> tuple[object, ...]:
        return (r.ReferenceTypeId, r.IsForward, r.NodeClass, r.BrowseName, r.DisplayName)

    async def check() -> None:
        async with connected(face.url) as c:
            ua_client: Any = c.uaclient
            (whole,) = await ua_client.browse(_browse(FB, size=0))
            mask = ua.BrowseResultMask.BrowseName | ua.BrowseResultMask.NodeClass
            (page,) = await ua_client.browse(_browse(FB, size=5, mask=mask))
            got = list(page.References)
            while page.ContinuationPoint:
                (page,) = await ua_client.browse_next(_next(page.ContinuationPoint))
                got += page.References
            null_type, null_name = ua.NodeId(), ua.LocalizedText()
            assert [r.NodeId for r in got] == [r.NodeId for r in whole.References]
            assert [(r.BrowseName, r.NodeClass) for r in got] == [
                (r.BrowseName, r.NodeClass) for r in whole.References
            ]
            nulls = (null_type, False, null_name, ua.ExpandedNodeId())
            assert all(
                (r.ReferenceTypeId, r.IsForward, r.DisplayName, r.TypeDefinition) == nulls
                for r in got
            )
            (bare,) = await ua_client.browse(_browse(FB, size=0, mask=0))
            assert [r.NodeId for r in bare.References] == [r.NodeId for r in whole.References]
            assert all(not r.BrowseName.Name and not r.NodeClass for r in bare.References)
            (again,) = await ua_client.browse(_browse(FB, size=0))
            assert [fields(r) for r in again.References] == [fields(r) for r in whole.References]
            assert any(r.DisplayName.Text for r in again.References)  # the node's own, kept

    run(check())
