"""What a plant's OPC UA integrator counts on: the node ids and browse names are the same
after the face starts again, and an online change that adds a step and renames another
gives the new step its node and keeps every other node id (docs/opcua.md, "The address
space")."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import pytest
from asyncua import ua
from asyncua.ua.uaerrors import UaStatusCodeError

from s7graph.web.bus.client import find_cpus
from s7graph.web.bus.session import open_session
from s7graph.web.opcua.server import OpcuaOptions, OpcuaServer
from tests.web.opcua.helpers import (
    CHART,
    FACE_CN,
    PASSWORD,
    connected,
    eventually,
    face_rig,
    free_port,
    node,
    run,
)

if TYPE_CHECKING:
    from tests.conftest import BusCerts

pytestmark = pytest.mark.timeout(180)


async def _tree(client: Any, path: str = "cpu1") -> dict[str, str]:
    """Node id → browse name of everything under ``path`` (references down only)."""
    out: dict[str, str] = {}
    todo = [node(client, path)]
    while todo:
        here = todo.pop()
        out[str(here.nodeid.Identifier)] = (await here.read_browse_name()).Name
        for child in await here.get_children():
            if child.nodeid.NamespaceIndex == 2 and str(child.nodeid.Identifier) not in out:
                todo.append(child)
    return out


def test_node_ids_stay_across_a_restart_and_an_online_change(
    tmp_path: Path, bus_certs: BusCerts
) -> None:
    with face_rig(tmp_path, bus_certs) as face:
        first = run(_tree_of(face.url))
        assert "cpu1/Seq_mix/S2/Active" in first and "cpu1/Symbols/Level/Address" in first
        assert "cpu1/Seq_mix/AckStep/InputArguments" in first
        with open_session(connect=[face.rig.endpoint], tls=bus_certs.tls(FACE_CN)) as session:
            status = find_cpus(session)[0]
            url = f"opc.tcp://127.0.0.1:{free_port()}"
            again = OpcuaServer(session, status, OpcuaOptions(url=url))
            again.start()
            try:
                assert run(_tree_of(url)) == first  # a second face: the same space
            finally:
                again.stop()

        edited = (
            CHART.replace(
                '  STEP S3 "Drain":\n  END_STEP\n',
                '  STEP S3 "Drain it":\n  END_STEP\n  STEP S4 "Rest":\n  END_STEP\n',
            )
            .replace("FROM S3 TO S1", "FROM S3 TO S4")
            .replace("END_SEQUENCE", '  TRANSITION T4 "Again" FROM S4 TO S1 := TRUE;\nEND_SEQUENCE')
        )

        async def changed() -> dict[str, str]:
            async with connected(face.url) as c:
                seen: list[tuple[str, object]] = []

                class Seen:
                    def datachange_notification(self, n: Any, value: object, _: Any) -> None:
                        seen.append((str(n.nodeid.Identifier), value))

                sub = await c.create_subscription(20, Seen())
                await sub.subscribe_data_change([node(c, "cpu1/Seq_mix/S1/Active")])
                await _download(face.url, edited)
                assert await eventually(lambda: _reads(c, "cpu1/Seq_mix/ChartVersion", 2), 20)
                assert await eventually(lambda: _reads(c, "cpu1/Seq_mix/S3/Name", "Drain it"))
                shown = await node(c, "cpu1/Seq_mix/S3").read_display_name()
                assert shown.Text == "S3 Drain it"
                face.set("Start", True)  # S1 leaves: a kept step's item still reports

                async def left() -> bool:
                    return ("cpu1/Seq_mix/S1/Active", False) in seen

                assert await eventually(left), seen
                face.set("Start", False)
                await sub.delete()
                return await _tree(c)

        after = run(changed())
        new = {k for k in after if k not in first}
        assert "cpu1/Seq_mix/S4" in new and "cpu1/Seq_mix/S4/Active" in new
        assert all(k.startswith("cpu1/Seq_mix/S4") for k in new), new
        assert set(first) <= set(after)  # every node id kept


async def _tree_of(url: str) -> dict[str, str]:
    async with connected(url) as c:
        return await _tree(c)


async def _reads(client: Any, path: str, expected: object) -> bool:
    try:
        return bool(await node(client, path).read_value() == expected)
    except UaStatusCodeError:
        return False


async def _download(url: str, source: str) -> None:
    async with connected(url, "eng", PASSWORD) as c:
        download = ua.NodeId("cpu1/Seq_mix/Download", 2)
        out = await node(c, "cpu1/Seq_mix").call_method(
            download, source, ua.Variant(1, ua.VariantType.UInt64)
        )
        assert out[3] == 2  # Version: the chart version running now
