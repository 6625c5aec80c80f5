"""The OPC UA face against a CPU on a real zenoh bus, with asyncua's client on loopback:
the address space (browse names and node ids made of names and step numbers, typed
values, engineering units), a step change reaching a subscription, the union's ops as
methods through the CPU's gate — audited under the OPC UA user —, writes that are
commands, and what an anonymous session and a wrong password get (docs/opcua.md)."""

from __future__ import annotations

import asyncio
from collections.abc import Iterator
from typing import TYPE_CHECKING

import pytest
from asyncua import ua
from asyncua.ua.uaerrors import UaStatusCodeError

from s7graph.web.access.audit import UNAUTHENTICATED, AuditRecord, read_audit
from s7graph.web.commands import COMMAND_TYPES
from tests.web.helpers import wait_until
from tests.web.opcua.helpers import FACE_CN, FaceRig, connected, eventually, face_rig, node, run

if TYPE_CHECKING:
    from tests.conftest import BusCerts

pytestmark = pytest.mark.timeout(120)


@pytest.fixture(scope="module")
def face(tmp_path_factory: pytest.TempPathFactory, bus_certs: BusCerts) -> Iterator[FaceRig]:
    with face_rig(tmp_path_factory.mktemp("face"), bus_certs) as rig:
        rig.set("Guard", True)
        yield rig


def _code(exc: BaseException) -> int:
    assert isinstance(exc, UaStatusCodeError), exc
    return int(exc.code)


async def _names(client: object, path: str) -> dict[str, str]:
    """Browse name → node id of the children of ``path``."""
    out = {}
    for child in await node(client, path).get_children():
        out[(await child.read_browse_name()).Name] = str(child.nodeid.Identifier)
    return out


def _commands(face: FaceRig) -> list[AuditRecord]:
    """The audit rows of commands (logins and logouts left out)."""
    return [r for r in read_audit(face.rig.state) if r.op not in ("login", "logout")]


def test_the_address_space_is_the_cpu_its_fbs_sequences_steps_and_symbols(face: FaceRig) -> None:
    async def check() -> None:
        async with connected(face.url) as c:
            assert await c.get_namespace_index("urn:s7graph:plc") == 2
            cpu = await _names(c, "cpu1")
            assert {"State", "StopReason", "Cycle", "Online", "CycleTime", "Symbols"} <= set(cpu)
            assert {"Messages", "Seq_mix", "Stop", "Start", "Force"} <= set(cpu)
            fb = await _names(c, "cpu1/Seq_mix")
            assert fb["Mode"] == "cpu1/Seq_mix/Mode" and fb["Sequence1"] == "cpu1/Seq_mix/Sequence1"
            assert {"ActiveSteps", "Halted", "Pins", "Variables", "ChartVersion"} <= set(fb)
            ops = {k.__name__ for k in COMMAND_TYPES if k.where in ("fb", "online")}
            assert ops <= set(fb) and "AckStep" in ops
            seq = await _names(c, "cpu1/Seq_mix/Sequence1")
            assert {"S1", "S2", "S3", "Number", "Name"} <= set(seq)
            s2 = await _names(c, "cpu1/Seq_mix/S2")
            assert {"Active", "T", "U", "Fault", "InterlockError", "SupervisionFault"} <= set(s2)
            assert s2["Supervision"] == "cpu1/Seq_mix/S2/Supervision" and "Interlock" in s2
            shown = await node(c, "cpu1/Seq_mix/S2").read_display_name()
            assert shown.Text == "S2 Fill"
            symbols = await _names(c, "cpu1/Symbols")
            assert set(symbols) == {"Start", "Guard", "Valve", "Level", "Flow", "Total"}
            assert set(await _names(c, "cpu1/Seq_mix/Variables")) == {"count", "dwell"}
            assert {"S_NO", "ERR_FLT", "INIT_SQ"} <= set(await _names(c, "cpu1/Seq_mix/Pins"))

    run(check())


def test_values_are_typed_with_their_units(face: FaceRig) -> None:
    async def check() -> None:
        async with connected(face.url) as c:
            assert await eventually(lambda: _reads(c, "cpu1/State", "RUN"))
            assert await eventually(lambda: _reads(c, "cpu1/Seq_mix/Mode", "AUTO"))
            assert await eventually(lambda: _reads(c, "cpu1/Seq_mix/S1/Active", True))
            assert await eventually(lambda: _reads(c, "cpu1/Seq_mix/Variables/dwell", 2000))
            types = {
                "cpu1/Symbols/Level": ua.VariantType.Int16,
                "cpu1/Symbols/Flow": ua.VariantType.Float,
                "cpu1/Symbols/Start": ua.VariantType.Boolean,
                "cpu1/Seq_mix/Pins/S_NO": ua.VariantType.Int16,
                "cpu1/Seq_mix/S2/T": ua.VariantType.Double,
                "cpu1/Cycle": ua.VariantType.UInt64,
                "cpu1/CycleTime/ScanPriority": ua.VariantType.UInt16,
                "cpu1/CycleTime/ScanCore": ua.VariantType.Int16,
            }
            for path, vt in types.items():
                value = await node(c, path).read_data_value()
                assert value.StatusCode.is_good(), path
                assert value.Value.VariantType == vt, path
                data_type = await node(c, path).read_data_type()
                duration = path.endswith("/T")  # a Double of ms: its data type Duration
                want = ua.NodeId(ua.ObjectIds.Duration if duration else vt.value)
                assert data_type == want, path
            for path in ("cpu1/Seq_mix/S2/T", "cpu1/Seq_mix/Variables/dwell"):
                units = await node(c, path + "/EngineeringUnits").read_value()
                assert units.DisplayName.Text == "ms", path
            address = await node(c, "cpu1/Symbols/Level/Address").read_value()
            assert address == "MW20"

    run(check())


async def _reads(client: object, path: str, expected: object) -> bool:
    try:
        return bool(await node(client, path).read_value() == expected)
    except UaStatusCodeError:
        return False


def test_a_step_change_reaches_a_subscription(face: FaceRig) -> None:
    class Seen:
        def __init__(self) -> None:
            self.values: list[tuple[str, object]] = []

        def datachange_notification(self, n: object, value: object, data: object) -> None:
            self.values.append((str(n.nodeid.Identifier), value))

    async def check() -> None:
        async with connected(face.url) as c:
            seen = Seen()
            sub = await c.create_subscription(20, seen)
            paths = ["cpu1/Seq_mix/S2/Active", "cpu1/Seq_mix/ActiveSteps"]
            await sub.subscribe_data_change([node(c, p) for p in paths])
            await asyncio.sleep(0.3)
            face.set("Start", True)

            async def reached() -> bool:
                return ("cpu1/Seq_mix/S2/Active", True) in seen.values and (
                    "cpu1/Seq_mix/ActiveSteps",
                    [2],
                ) in seen.values

            assert await eventually(reached), seen.values
            face.set("Start", False)
            await sub.delete()

    run(check())
    face.set("Level", 200)
    assert wait_until(lambda: face.active() == [3] or face.active() == [1])
    face.set("Level", 0)
    assert wait_until(lambda: face.active() == [1])


def test_the_ops_are_methods_with_the_structs_arguments(face: FaceRig) -> None:
    async def check() -> None:
        async with connected(face.url) as c:
            args = await node(c, "cpu1/Seq_mix/AckStep/InputArguments").read_value()
            assert [(a.Name, a.DataType) for a in args] == [("step", ua.NodeId(5))]  # UInt16
            args = await node(c, "cpu1/Force/InputArguments").read_value()
            assert [a.Name for a in args] == ["address", "value", "all"]
            args = await node(c, "cpu1/Seq_mix/SetMode/InputArguments").read_value()
            assert "AUTO, MAN, TAP, TOP" in args[0].Description.Text

    run(check())


def test_synchronize_answers_where_the_process_stands_to_any_session(face: FaceRig) -> None:
    face.set("Start", False)  # T3 into S1 holds, T1 out of it not; S2's interlock holds

    async def check() -> None:
        async with connected(face.url) as c:  # anonymous: a read
            args = await node(c, "cpu1/Seq_mix/Synchronize/OutputArguments").read_value()
            assert [a.Name for a in args] == ["Likely", "Fits", "Cycle"]
            fb = node(c, "cpu1/Seq_mix")
            likely, fits, cycle = await fb.call_method(ua.NodeId("cpu1/Seq_mix/Synchronize", 2))
            assert (likely, fits) == ([1], [1, 2]) and cycle > 0
            with pytest.raises(UaStatusCodeError) as refused:
                await fb.call_method(ua.NodeId("cpu1/Seq_mix/Synchronize", 2), 1)
            assert _code(refused.value) == ua.StatusCodes.BadTooManyArguments

    before = len(_commands(face))
    run(check())
    assert len(_commands(face)) == before  # a read: no command, no audit row


def test_an_operator_commands_through_the_gate_and_is_audited(face: FaceRig) -> None:
    """A refusal's status code is its kind's, whatever its words: a message id that reads
    like a denial is still an unknown message (``BadEventIdUnknown``)."""

    async def check() -> None:
        async with connected(face.url, "olga") as c:
            fb = node(c, "cpu1/Seq_mix")
            out = await fb.call_method(ua.NodeId("cpu1/Seq_mix/SetMode", 2), "MAN")
            assert out[1] > 0  # the cycle it was applied at
            assert await eventually(lambda: _reads(c, "cpu1/Seq_mix/Mode", "MAN"))
            step = ua.Variant(3, ua.VariantType.UInt16)
            await fb.call_method(ua.NodeId("cpu1/Seq_mix/StepOn", 2), step)
            assert await eventually(lambda: _reads(c, "cpu1/Seq_mix/S3/Active", True))
            with pytest.raises(UaStatusCodeError) as refused:  # S3 is active already
                await fb.call_method(ua.NodeId("cpu1/Seq_mix/StepOn", 2), step)
            assert _code(refused.value) == ua.StatusCodes.BadInvalidState
            await fb.call_method(ua.NodeId("cpu1/Seq_mix/StepOff", 2), step)
            steps = ua.Variant([2], ua.VariantType.UInt16)  # S1 leaves, S2 enters: one call
            await fb.call_method(ua.NodeId("cpu1/Seq_mix/SetSteps", 2), steps)
            assert await eventually(lambda: _reads(c, "cpu1/Seq_mix/S2/Active", True))
            assert await _reads(c, "cpu1/Seq_mix/S1/Active", False)
            await fb.call_method(ua.NodeId("cpu1/Seq_mix/Init", 2))
            await fb.call_method(ua.NodeId("cpu1/Seq_mix/SetMode", 2), "AUTO")
            with pytest.raises(UaStatusCodeError) as refused:  # its kind decides, not words
                await fb.call_method(ua.NodeId("cpu1/Seq_mix/AckMsg", 2), "may not: no step")
            assert _code(refused.value) == ua.StatusCodes.BadEventIdUnknown

    run(check())
    rows = [r for r in _commands(face) if r.user == "olga"]
    ops = [(r.op, r.outcome) for r in rows]
    assert ops[:3] == [("mode", "applied"), ("step_on", "applied"), ("step_on", "refused")]
    assert ("set_steps", "applied") in ops
    assert all(r.origin.startswith(f"{FACE_CN}@tls/127.0.0.1:") for r in rows)  # its link
    assert all("claimed origin: opcua 127.0.0.1:" in r.detail for r in rows)  # the client's
    assert all(r.role == "operator" for r in rows)
    assert wait_until(lambda: face.active() == [1])


def test_a_viewer_is_refused_by_the_gate_and_audited(face: FaceRig) -> None:
    async def check() -> None:
        async with connected(face.url, "vic") as c:
            with pytest.raises(UaStatusCodeError) as refused:
                await node(c, "cpu1/Seq_mix").call_method(ua.NodeId("cpu1/Seq_mix/Init", 2))
            assert _code(refused.value) == ua.StatusCodes.BadUserAccessDenied

    run(check())
    row = [r for r in _commands(face) if r.user == "vic"][-1]
    assert (row.op, row.outcome, row.role) == ("init", "refused", "viewer")
    assert "may not init" in row.reason


def test_anonymous_reads_but_never_writes_nor_calls(face: FaceRig) -> None:
    before = len(_commands(face))

    async def check() -> None:
        async with connected(face.url) as c:
            assert await node(c, "cpu1/Seq_mix/Mode").read_value() == "AUTO"
            # what a client greys out: the session may not write or call (Part 3)
            mode, init = node(c, "cpu1/Seq_mix/Mode"), node(c, "cpu1/Seq_mix/Init")
            user = ua.AttributeIds.UserAccessLevel
            assert (await mode.read_attribute(user)).Value.Value & 0x02 == 0
            assert (await mode.read_attribute(ua.AttributeIds.AccessLevel)).Value.Value & 0x02
            execute = ua.AttributeIds.UserExecutable
            assert (await init.read_attribute(execute)).Value.Value is False
            with pytest.raises(UaStatusCodeError) as refused:
                await node(c, "cpu1/Seq_mix/Mode").write_value(
                    ua.Variant("MAN", ua.VariantType.String)
                )
            assert _code(refused.value) == ua.StatusCodes.BadUserAccessDenied
            with pytest.raises(UaStatusCodeError) as refused:
                await node(c, "cpu1/Seq_mix").call_method(ua.NodeId("cpu1/Seq_mix/Init", 2))
            assert _code(refused.value) == ua.StatusCodes.BadUserAccessDenied

    run(check())
    assert len(_commands(face)) == before  # nothing reached the CPU


def test_an_anonymous_sessions_read_only_view_is_its_own_not_the_next_sessions(
    face: FaceRig,
) -> None:
    """An anonymous read of ``UserAccessLevel`` and ``UserExecutable`` answered without
    write and call changed the values the address space holds: a logged-in session read
    them so after it."""

    async def check() -> None:
        user, execute = ua.AttributeIds.UserAccessLevel, ua.AttributeIds.UserExecutable
        async with connected(face.url) as anonymous, connected(face.url, "olga") as c:
            for client, may in ((anonymous, False), (c, True), (anonymous, False)):
                level = await node(client, "cpu1/Seq_mix/Mode").read_attribute(user)
                assert bool(level.Value.Value & 0x02) is may
                call = await node(client, "cpu1/Seq_mix/Init").read_attribute(execute)
                assert call.Value.Value is may

    run(check())


def test_a_wrong_password_is_refused_when_the_session_activates(face: FaceRig) -> None:
    async def check() -> None:
        with pytest.raises(UaStatusCodeError) as refused:
            async with connected(face.url, "olga", password="wrong one"):
                pass
        assert _code(refused.value) == ua.StatusCodes.BadUserAccessDenied

    run(check())
    row = [r for r in read_audit(face.rig.state) if r.op == "login"][-1]
    assert (row.user, row.claimed, row.outcome) == (UNAUTHENTICATED, "olga", "refused")


def test_a_write_is_a_command_and_forcing_and_modifying_are_an_engineers(
    face: FaceRig,
) -> None:
    async def check() -> None:
        level = ua.Variant(42, ua.VariantType.Int16)
        async with connected(face.url, "olga") as c:
            await node(c, "cpu1/Seq_mix/Mode").write_value(ua.Variant("MAN", ua.VariantType.String))
            assert await eventually(lambda: _reads(c, "cpu1/Seq_mix/Mode", "MAN"))
            await node(c, "cpu1/Seq_mix/Mode").write_value(
                ua.Variant("AUTO", ua.VariantType.String)
            )
            with pytest.raises(UaStatusCodeError) as refused:  # force: an engineer's
                await node(c, "cpu1/Symbols/Level").write_value(level)
            assert _code(refused.value) == ua.StatusCodes.BadUserAccessDenied
        async with connected(face.url, "eng") as c:
            await node(c, "cpu1/Symbols/Level").write_value(level)
            assert await eventually(lambda: _reads(c, "cpu1/Symbols/Level", 42))
            assert await eventually(lambda: _reads(c, "cpu1/ForceJobs", 1))
            for path, value, code in (
                ("cpu1/Symbols/Level", ua.Variant(1.5, ua.VariantType.Double), "BadTypeMismatch"),
                ("cpu1/Symbols/Level", ua.Variant(70000, ua.VariantType.Int32), "BadOutOfRange"),
                ("cpu1/Seq_mix/Mode", ua.Variant("FAST", ua.VariantType.String), "BadOutOfRange"),
                (
                    "cpu1/Seq_mix/S2/Active",
                    ua.Variant(True, ua.VariantType.Boolean),
                    "BadNotWritable",
                ),
                ("cpu1/Symbols/Total", ua.Variant(1, ua.VariantType.Int16), "BadNotWritable"),
                (
                    "cpu1/Seq_mix/Variables/count",  # with --writes modify only
                    ua.Variant(1, ua.VariantType.Int16),
                    "BadNotWritable",
                ),
            ):
                with pytest.raises(UaStatusCodeError) as refused:
                    await node(c, path).write_value(value)
                assert _code(refused.value) == getattr(ua.StatusCodes, code), path
            force = ua.NodeId("cpu1/Force", 2)
            await node(c, "cpu1").call_method(force, "Level", ua.Variant(None))  # unforce
            assert await eventually(lambda: _reads(c, "cpu1/ForceJobs", 0))
            modify = ua.NodeId("cpu1/Modify", 2)  # once, not held: no force job
            await node(c, "cpu1").call_method(modify, "Level", ua.Variant(7, ua.VariantType.Int16))
            assert await eventually(lambda: _reads(c, "cpu1/Symbols/Level", 7))
            assert await _reads(c, "cpu1/ForceJobs", 0)

    run(check())
    audit = read_audit(face.rig.state)
    rows = [(r.user, r.op, r.outcome) for r in audit if r.op in ("force", "modify")]
    assert rows == [
        ("olga", "force", "refused"),
        ("eng", "force", "applied"),
        ("eng", "force", "applied"),
        ("eng", "modify", "applied"),
    ]


def test_an_array_on_a_scalar_or_a_method_on_another_object_is_refused_and_not_sent(
    face: FaceRig,
) -> None:
    """``[False]`` written to the Boolean ``Halted`` is a type mismatch (Python would read
    the list as true: a halt), and a method called through an object that does not have
    it is ``BadMethodInvalid`` (OPC UA Part 4, Call): neither reaches the CPU."""

    async def check() -> None:
        async with connected(face.url, "eng") as c:
            for path, value in (
                ("cpu1/Seq_mix/Halted", ua.Variant([False], ua.VariantType.Boolean)),
                ("cpu1/Seq_mix/Mode", ua.Variant(["MAN"], ua.VariantType.String)),
                ("cpu1/Symbols/Level", ua.Variant([42], ua.VariantType.Int16)),
            ):
                with pytest.raises(UaStatusCodeError) as refused:
                    await node(c, path).write_value(value)
                assert _code(refused.value) == ua.StatusCodes.BadTypeMismatch, path
            for owner, method in (
                ("cpu1/Symbols", "cpu1/Seq_mix/Init"),
                ("cpu1", "cpu1/Seq_mix/Halt"),
            ):
                with pytest.raises(UaStatusCodeError) as refused:
                    await node(c, owner).call_method(ua.NodeId(method, 2), False)
                assert _code(refused.value) == ua.StatusCodes.BadMethodInvalid, method

    before = len(read_audit(face.rig.state))
    run(check())
    rows = read_audit(face.rig.state)[before:]
    assert not [r for r in rows if r.op in ("halt", "init", "mode", "force")], rows
