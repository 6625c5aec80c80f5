"""A CPU gone from the bus: its values keep their last value, with
``UncertainNoCommunicationLastUsableValue`` (a Bad status would empty them),
``Online`` turns false and the server's ``ServiceLevel`` drops to 0 — what an OPC UA
client takes for a stale source (docs/opcua.md, "Values and their status")."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import pytest
from asyncua import ua

from tests.web.opcua.helpers import connected, eventually, face_rig, node, run

if TYPE_CHECKING:
    from tests.conftest import BusCerts

pytestmark = pytest.mark.timeout(120)


def test_the_values_of_a_cpu_gone_are_kept_as_the_last_usable_ones(
    tmp_path: Path, bus_certs: BusCerts
) -> None:
    with face_rig(tmp_path, bus_certs) as face:

        async def check() -> None:
            async with connected(face.url) as c:
                state = node(c, "cpu1/State")

                async def running() -> bool:
                    value = await state.read_data_value()
                    return bool(value.StatusCode.is_good() and value.Value.Value == "RUN")

                assert await eventually(running)
                level = await c.nodes.server.get_child("0:ServiceLevel")
                assert await level.read_value() == 255
                face.rig.edge.close()  # the CPU's bus goes (its liveliness token with it)

                async def stale() -> bool:
                    value = await state.read_data_value(raise_on_bad_status=False)
                    stale = ua.StatusCodes.UncertainNoCommunicationLastUsableValue
                    return value.StatusCode.value == stale and value.Value.Value == "RUN"

                assert await eventually(stale, 20)
                value = await node(c, "cpu1/Seq_mix/S1/Active").read_data_value(
                    raise_on_bad_status=False
                )
                stale = ua.StatusCodes.UncertainNoCommunicationLastUsableValue
                assert value.StatusCode.value == stale and value.Value.Value is not None
                assert await node(c, "cpu1/Online").read_value() is False
                assert await level.read_value() == 0

        run(check())


def test_a_conditions_state_of_a_cpu_gone_is_kept_as_the_last_usable_one(
    tmp_path: Path, bus_certs: BusCerts
) -> None:
    """A condition node's state children are values of the face like any other: once the
    CPU leaves the bus they keep what its last event said, marked as the last usable."""
    with face_rig(tmp_path, bus_certs) as face:

        async def check() -> None:
            supervision = "cpu1/Seq_mix/S2/Supervision"
            async with connected(face.url) as c:
                active = node(c, f"{supervision}/ActiveState/Id")
                face.set("Guard", True)
                face.set("Start", True)  # S2: past 400 ms its supervision latches

                async def came() -> bool:
                    value = await active.read_data_value(raise_on_bad_status=False)
                    return bool(value.StatusCode.is_good() and value.Value.Value is True)

                assert await eventually(came, 20)
                face.rig.edge.close()  # the CPU's bus goes (its liveliness token with it)
                stale = ua.StatusCodes.UncertainNoCommunicationLastUsableValue

                async def kept() -> bool:
                    value = await active.read_data_value(raise_on_bad_status=False)
                    return value.StatusCode.value == stale and value.Value.Value is True

                assert await eventually(kept, 20)

        run(check())
