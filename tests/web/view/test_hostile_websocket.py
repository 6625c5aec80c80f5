"""A hostile program on the page's own origin, speaking viser's websocket protocol by hand
to the drill chart's view (a real viser server on 127.0.0.1, the CPU scanning on the
virtual clock, a users file): malformed frames and uploads close only its websocket, with
a reason and no traceback; GUI updates of the wrong type or for other properties are
ignored with a notice naming the field; a form's mark of changes (which viser relays to
the other pages) passes only for a form of its own page; a page that closes while its
panel is built leaves no panel behind; a flood of clicks, or of forms' marks, is cut to the
input rate, its clicks that pass are refused and audited, and another page still opens at
once."""

from __future__ import annotations

import math
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import msgspec
import pytest
import viser
import zstandard

from s7graph.engine.clock import VirtualClock
from s7graph.sfb.alarms import message_list
from s7graph.web.access.audit import AuditStore, read_audit
from s7graph.web.access.login import Authenticator
from s7graph.web.access.users import UsersFile
from s7graph.web.bus.gate import Gate
from s7graph.web.bus.live import LiveGraph
from s7graph.web.harness.session import ChartSession, load_chart
from s7graph.web.view.inbound import INPUT_BURST, INPUT_RATE, MAX_TEXT, bad_value
from s7graph.web.wiring.live_edge import LiveEdge
from tests.paths import ROOT
from tests.web.helpers import scanning, wait_until

pytestmark = pytest.mark.timeout(180)
DRILL = ROOT / "examples" / "drill"
PROTOCOL = f"viser-v{viser.__version__}"
CAMERA = {
    "type": "ViewerCameraMessage",
    "wxyz": [1.0, 0.0, 0.0, 0.0],
    "position": [0.0, 0.0, 10.0],
    "fov": 1.0,
    "near": 0.01,
    "far": 1000.0,
    "image_height": 800,
    "image_width": 1000,
    "look_at": [0.0, 0.0, 0.0],
    "up_direction": [0.0, 1.0, 0.0],
}


@dataclass
class Plant:
    edge: LiveEdge
    session: ChartSession
    state: Path


@pytest.fixture(scope="module")
def plant(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Plant]:
    tmp = tmp_path_factory.mktemp("hostile")
    UsersFile(tmp / "users.json").add("olga", "operator", "correct horse")
    state = tmp / "state.sqlite"
    audit = AuditStore(state)
    cc, table = load_chart(DRILL / "drill.s7g", DRILL / "symbols.txt")
    session = ChartSession(cc, table, VirtualClock())
    live = LiveGraph(session.graph, read=session.get, messages=message_list(session.cpu))
    gate = Gate(Authenticator(UsersFile(tmp / "users.json")), audit)
    try:
        with LiveEdge(live, port=0, gate=gate) as edge, scanning(session, edge):
            yield Plant(edge, session, state)
    finally:
        audit.close()


@dataclass
class Peer:
    """A raw websocket on the page's origin: what it was sent, by label and as notices."""

    ws: Any
    uuids: dict[str, str] = field(default_factory=dict)
    notices: list[str] = field(default_factory=list)
    dirty: list[object] = field(default_factory=list)  # the forms' marks relayed to it
    closed: Any = None

    def send(self, message: object) -> None:
        self.ws.send(msgspec.msgpack.encode(message))

    def update(self, label: str, **updates: object) -> None:
        self.send({"type": "GuiUpdateMessage", "uuid": self.uuids[label], "updates": updates})

    def pump(self, until: Any = lambda: False, timeout: float = 10.0) -> bool:
        """Read frames until ``until()`` holds, the websocket closes or ``timeout`` s."""
        deadline = time.monotonic() + timeout
        unzip = zstandard.ZstdDecompressor()
        while not until() and self.closed is None and time.monotonic() < deadline:
            try:
                frame = self.ws.recv(timeout=0.1)
            except TimeoutError:
                continue
            except Exception as exc:  # the websocket closed
                self.closed = exc
                break
            size = int.from_bytes(frame[:8], "little")
            packed = frame[16 : 16 + int.from_bytes(frame[8:16], "little")]
            for m in msgspec.msgpack.decode(unzip.decompress(packed, max_output_size=size))[
                "messages"
            ]:
                props = m.get("props") or {}
                if m["type"].startswith("Gui") and "uuid" in m and props.get("label"):
                    self.uuids.setdefault(props["label"], m["uuid"])
                if m["type"] == "NotificationShowMessage":
                    self.notices.append(f"{props.get('title')}: {props.get('body')}")
                if m["type"] == "GuiFormDirtyMessage":
                    self.dirty.append(m.get("uuid"))
        return bool(until())


@pytest.fixture
def peer(plant: Plant) -> Iterator[Peer]:
    with _connect(plant) as p:
        yield p


def _connect(plant: Plant) -> Any:
    from contextlib import contextmanager

    from websockets.sync.client import connect

    @contextmanager
    def opened() -> Iterator[Peer]:
        url = plant.edge.url.replace("http://", "ws://")
        origin = plant.edge.url.rstrip("/")
        with connect(url, origin=origin, subprotocols=[PROTOCOL], max_size=None) as ws:
            p = Peer(ws)
            p.send(CAMERA)  # viser builds a page's panel after its first camera report
            assert p.pump(lambda: "Show step" in p.uuids, 30), "no panel"
            yield p

    return opened()


def _panels(plant: Plant) -> dict[int, Any]:
    assert plant.edge.edge is not None
    return plant.edge.edge.view.panels  # type: ignore[no-any-return]


def _panel(plant: Plant, peer: Peer) -> Any:
    """The panel of ``peer``'s page, known by the uuid of its "Show step" field (a page is
    sent its fields while its panel is built, so the panel is kept a moment later)."""
    uuid = peer.uuids["Show step"]

    def found() -> Any:
        mine = [p for p in list(_panels(plant).values()) if p.detail_step._impl.uuid == uuid]
        return mine[0] if mine else None

    assert wait_until(lambda: found() is not None, 20), "the page's panel was never kept"
    return found()


def test_bad_value_says_what_each_field_takes() -> None:
    def state(value: object, **props: object) -> Any:
        return SimpleNamespace(value=value, is_button=False, props=SimpleNamespace(**props))

    number, text = state(1), state("", multiline=False)
    assert bad_value(number, 7) == bad_value(number, 2.5) == ""
    assert bad_value(number, "abc") == "a finite number is expected, not text"
    assert bad_value(number, math.nan) == "a finite number is expected, not NaN"
    assert bad_value(number, math.inf) == "a finite number is expected, not an infinite number"
    assert bad_value(number, True) == "a finite number is expected, not true/false"
    assert bad_value(text, None) == "text is expected, not nothing"
    assert bad_value(text, "x" * (MAX_TEXT + 1)) == f"at most {MAX_TEXT:,} characters"
    assert bad_value(state("All", options=("All", "Open")), "Open") == ""
    assert bad_value(state("All", options=("All", "Open")), "x") == "not one of its options"
    button = SimpleNamespace(value=False, is_button=True, props=SimpleNamespace())
    assert bad_value(button, True) == "" and bad_value(button, [1]) != ""


@pytest.mark.parametrize(
    ("frame", "code", "reason"),
    [
        ("hello", 1003, "text frames are not accepted"),
        (b"\xc1\xc1garbage", 1007, "malformed message: not MessagePack"),
        (msgspec.msgpack.encode({"type": "NoSuch"}), 1007, "malformed message: unknown type"),
        (msgspec.msgpack.encode([1, 2]), 1007, "malformed message: no message type"),
        (
            msgspec.msgpack.encode({**CAMERA, "image_width": math.nan}),
            1007,
            "malformed message: bad fields for ViewerCameraMessage",
        ),
        (
            msgspec.msgpack.encode(
                {
                    "type": "FileTransferStartUpload",
                    "source_component_uuid": "x",
                    "transfer_uuid": "t",
                    "filename": "a",
                    "mime_type": "x",
                    "part_count": 10**9,
                    "size_bytes": 10**15,
                }
            ),
            1008,
            "file uploads are not accepted",
        ),
        (
            msgspec.msgpack.encode({"type": "GuiFormDirtyMessage", "uuid": [5]}),
            1007,
            "malformed message: bad fields for GuiFormDirtyMessage",
        ),
    ],
    ids=["text", "not-msgpack", "unknown-type", "not-a-map", "nan-camera", "upload", "dirty"],
)
def test_a_malformed_frame_or_an_upload_closes_only_its_websocket_with_a_reason(
    plant: Plant,
    peer: Peer,
    frame: bytes | str,
    code: int,
    reason: str,
    capfd: pytest.CaptureFixture[str],
) -> None:
    cycle = plant.session.cpu.cycle
    peer.ws.send(frame)
    peer.pump(timeout=20)
    closed = getattr(peer.closed, "rcvd", None)
    assert closed is not None and closed.code == code and closed.reason.startswith(reason)
    with _connect(plant) as other:  # the page serves the next page
        other.update("Show step", value=1)
    assert wait_until(lambda: plant.session.cpu.cycle > cycle + 5, 20)  # and the CPU scans
    err = capfd.readouterr().err
    assert "Traceback" not in err, err


def test_a_gui_update_of_the_wrong_type_is_ignored_with_a_notice_naming_the_field(
    plant: Plant, peer: Peer, capfd: pytest.CaptureFixture[str]
) -> None:
    panel = _panel(plant, peer)
    step = panel.step_number.value
    for value, why in [
        ("abc", "Step: a finite number is expected, not text"),
        (math.nan, "Step: a finite number is expected, not NaN"),
        ([1, 2], "Step: a finite number is expected, not a list"),
    ]:
        peer.update("Step", value=value)
        assert peer.pump(lambda why=why: f"input ignored: {why}" in peer.notices), peer.notices
        assert panel.step_number.value == step
    peer.update("Show step", update_cb=5)  # viser would set its internal state
    notice = "input ignored: Show step: only its value may be set, not update_cb"
    assert peer.pump(lambda: notice in peer.notices), peer.notices
    assert isinstance(panel.detail_step._impl.update_cb, list)
    peer.update("Show", value="anything")  # the alarm filter's dropdown
    assert peer.pump(lambda: "input ignored: Show: not one of its options" in peer.notices)
    peer.update("Step", value=3)  # a good value still goes through
    assert wait_until(lambda: panel.step_number.value == 3)
    err = capfd.readouterr().err
    assert "Traceback" not in err, err


def test_a_flood_of_clicks_is_cut_to_the_input_rate_audited_and_other_pages_open_at_once(
    plant: Plant, peer: Peer
) -> None:
    init = {"type": "GuiUpdateMessage", "uuid": peer.uuids["Initialize"], "updates": {}}
    frame = msgspec.msgpack.encode({**init, "updates": {"value": True}})
    start = time.monotonic()
    for _ in range(5000):  # a viewer's clicks on a disabled button: refused by the CPU
        peer.ws.send(frame)
    opened = time.monotonic()
    with _connect(plant):
        took = time.monotonic() - opened
    assert took < 5.0, f"another page waited {took:.1f} s for its panel"
    refused = "initialize refused: not logged in: log in first (no token)"
    peer.pump(lambda: "input ignored" in " ".join(peer.notices), 20)
    assert any(n.startswith("input ignored: too many inputs") for n in peer.notices)
    peer.pump(timeout=3)
    passed = peer.notices.count(refused)
    assert 0 < passed <= INPUT_BURST + INPUT_RATE * (time.monotonic() - start)
    rows = [r for r in read_audit(plant.state) if r.op == "init" and r.outcome == "refused"]
    assert rows  # the clicks that passed reached the CPU, which refused and audited them


def test_a_forms_mark_of_changes_naming_no_form_of_its_own_page_reaches_no_other_page(
    plant: Plant, peer: Peer
) -> None:
    """The page has no form (its Login is a folder): another page's element, a field, a
    made-up name or its own folder named in a form's mark are ignored, never relayed."""
    with _connect(plant) as other:
        theirs, mine = other.uuids["Login"], peer.uuids["Login"]
        for uuid in (theirs, peer.uuids["User"], "no-such-form", mine):
            peer.send({"type": "GuiFormDirtyMessage", "uuid": uuid})
        other.pump(timeout=1)
        assert other.dirty == []
        assert peer.closed is None and not peer.notices


def test_a_flood_of_forms_marks_is_cut_to_the_input_rate_and_other_pages_open_at_once(
    plant: Plant, peer: Peer
) -> None:
    frame = msgspec.msgpack.encode({"type": "GuiFormDirtyMessage", "uuid": peer.uuids["Login"]})
    for _ in range(5000):  # each relayed to every other page, were it not cut
        peer.ws.send(frame)
    opened = time.monotonic()
    with _connect(plant):
        took = time.monotonic() - opened
    assert took < 5.0, f"another page waited {took:.1f} s for its panel"
    peer.pump(lambda: "input ignored" in " ".join(peer.notices), 20)
    assert any(n.startswith("input ignored: too many inputs") for n in peer.notices)


def test_pages_that_close_while_their_panel_is_built_leave_no_panel_behind(
    plant: Plant,
) -> None:
    from websockets.sync.client import connect

    url, origin = plant.edge.url.replace("http://", "ws://"), plant.edge.url.rstrip("/")
    for _ in range(20):  # connect, say the camera, see the panel start, go
        with connect(url, origin=origin, subprotocols=[PROTOCOL], max_size=None) as ws:
            quick = Peer(ws)
            quick.send(CAMERA)
            assert quick.pump(lambda q=quick: "Log in" in q.uuids, 30)
    with _connect(plant):  # this page's panel, and none of theirs
        assert wait_until(lambda: len(_panels(plant)) == 1, 20), set(_panels(plant))
    assert wait_until(lambda: not _panels(plant), 20), set(_panels(plant))
