"""What the view takes from a page's websocket: only what a page of its own could send.

A websocket of the page's own origin may still be a hostile program, not the page. Every
frame it sends is screened (:func:`screen_connection`) before viser reads it, on the
server's event loop, so nothing it sends reaches viser's handlers unchecked:

- a frame that is not a viser message — text, bytes that are not MessagePack, an unknown
  message type, fields of the wrong shape — and a file upload (the page has no upload
  button) close the websocket with a reason naming what was wrong (1003, 1007, 1008); a
  frame larger than :data:`MAX_FRAME` closes it too (1009);
- a GUI update that names an element of this page may set its *value* only, of the
  element's own type — a whole number or a finite number for a number field, text for a
  text field (at most :data:`MAX_TEXT` characters, :data:`MAX_SOURCE` for the editor's
  source), one of the offered options for a dropdown, true for a button — and is
  otherwise ignored with a notice on that page naming the field and what it takes;
- a form's mark of changes not yet submitted (``GuiFormDirtyMessage``, which viser relays to
  every other page) passes only for a form of this page: naming another element, or none,
  it is ignored, and with a name that is not text it closes the websocket (1007);
- inputs (GUI updates, clicks on the chart, forms' marks) beyond :data:`INPUT_RATE` a second
  (:data:`INPUT_BURST` at once), and camera reports beyond :data:`CAMERA_RATE`, are
  ignored (the inputs with one notice a second), so one page's flood never queues up
  before another page's work in viser's thread pool.

None of this prints a traceback: viser would print one for each bad frame and close the
connection with 1011.
"""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from typing import Any, Final

import msgspec
import viser
from viser import _messages
from viser.infra import Message

__all__ = [
    "CAMERA_RATE",
    "INPUT_BURST",
    "INPUT_RATE",
    "MAX_FRAME",
    "MAX_SOURCE",
    "MAX_TEXT",
    "Refusal",
    "bad_value",
    "screen_connection",
]

MAX_FRAME: Final = 8 * 1024 * 1024
"""The largest frame a page may send (viser's own limit is 50 MiB)."""
MAX_TEXT: Final = 65_536
"""The most characters a one-line text field takes."""
MAX_SOURCE: Final = 2_000_000
"""The most characters a multi-line text field (the editor's source) takes."""
INPUT_RATE: Final = 40.0
INPUT_BURST: Final = 80.0
CAMERA_RATE: Final = 240.0
NOTICE_EVERY_S: Final = 1.0

UNSUPPORTED_DATA: Final = 1003
POLICY_VIOLATION: Final = 1008
INVALID_PAYLOAD: Final = 1007
_UPLOADS: Final = (_messages.FileTransferStartUpload, _messages.FileTransferPart)
_INPUTS: Final = (
    _messages.GuiUpdateMessage,
    _messages.SceneNodeClickMessage,
    _messages.GuiButtonHoldMessage,
    _messages.GuiFormSubmitMessage,
    _messages.GuiFormDirtyMessage,
    _messages.CommandTriggerMessage,
)


@dataclass(frozen=True, slots=True)
class Refusal:
    """Why a frame is not passed on: ``close`` with ``code`` (the websocket ends), or a
    notice for the page (the frame is ignored; no reason: ignored silently; ``flood``:
    one of too many, told at most once a second)."""

    reason: str
    close: bool = False
    code: int = INVALID_PAYLOAD
    flood: bool = False


@dataclass(slots=True)
class _Bucket:
    """A token bucket: ``rate`` a second, at most ``burst`` at once."""

    rate: float
    burst: float
    tokens: float = 0.0
    at: float = field(default_factory=time.monotonic)

    def __post_init__(self) -> None:
        self.tokens = self.burst

    def take(self, now: float) -> bool:
        self.tokens = min(self.burst, self.tokens + (now - self.at) * self.rate)
        self.at = now
        if self.tokens < 1.0:
            return False
        self.tokens -= 1.0
        return True


def _kind(value: object) -> str:
    """A value's kind as a page's user would name it."""
    if isinstance(value, bool):
        return "true/false"
    if isinstance(value, float) and not math.isfinite(value):
        return "NaN" if math.isnan(value) else "an infinite number"
    if isinstance(value, int | float):
        return "a number"
    if isinstance(value, str):
        return "text"
    if value is None:
        return "nothing"
    if isinstance(value, dict):
        return "a map"
    if isinstance(value, list | tuple):
        return "a list"
    return "binary data" if isinstance(value, bytes) else "something else"


def _finite(value: object) -> bool:
    if isinstance(value, bool) or not isinstance(value, int | float):
        return False
    return math.isfinite(value)


def bad_value(state: Any, value: object) -> str:
    """Why ``value`` cannot be the value of the GUI element whose viser state is
    ``state`` ("" when it can): the element's own type, finite, within its options and
    its length."""
    current = state.value
    if state.is_button and not isinstance(current, str):
        return "" if value is True else f"a click is true, not {_kind(value)}"
    if isinstance(current, bool):
        return "" if isinstance(value, bool) else f"true/false is expected, not {_kind(value)}"
    if isinstance(current, int | float):
        return "" if _finite(value) else f"a finite number is expected, not {_kind(value)}"
    if isinstance(current, str):
        if not isinstance(value, str):
            return f"text is expected, not {_kind(value)}"
        options = getattr(state.props, "options", None)
        if options is not None and value not in options:
            return "not one of its options"
        most = MAX_SOURCE if getattr(state.props, "multiline", False) else MAX_TEXT
        return "" if len(value) <= most else f"at most {most:,} characters"
    if isinstance(current, tuple):
        if isinstance(value, list | tuple) and len(value) == len(current):
            return "" if all(_finite(v) for v in value) else "a list of finite numbers is expected"
        return f"a list of {len(current)} finite numbers is expected"
    return "this field takes no input"


def _gui_state(server: viser.ViserServer, client_id: int, uuid: str) -> Any:
    """The viser state of the GUI input ``uuid`` of page ``client_id`` (or the server's),
    None if it has none."""
    client = server._connected_clients.get(client_id)
    apis = [client.gui] if client is not None else []
    for api in (*apis, server.gui):
        handle = api._gui_input_handle_from_uuid.get(uuid)
        if handle is not None:
            return handle._impl
    return None


def _gui_refusal(server: viser.ViserServer, client_id: int, message: Any) -> Refusal | None:
    """A GUI update that may not be applied: a property other than ``value``, or a value
    not of its element's type (an unknown element: viser ignores it, as for a removed one)."""
    state = _gui_state(server, client_id, message.uuid)
    if state is None or state.removed:
        return None
    label = str(getattr(state.props, "label", "") or "a field")[:60]
    others = sorted(str(k)[:30] for k in message.updates if k != "value")
    if others:
        return Refusal(f"{label}: only its value may be set, not {', '.join(others)}")
    if "value" not in message.updates:
        return Refusal("")
    why = bad_value(state, message.updates["value"])
    return Refusal(f"{label}: {why}") if why else None


def _dirty_refusal(server: viser.ViserServer, client_id: int, uuid: object) -> Refusal | None:
    """A form's mark of changes (viser relays it to every other page) that names no form
    of this page: ignored (None: it names one); a name that is not text closes the page."""
    if not isinstance(uuid, str):
        return Refusal("malformed message: bad fields for GuiFormDirtyMessage", close=True)
    client = server._connected_clients.get(client_id)
    forms = client.gui._container_handle_from_uuid if client is not None else {}
    return None if isinstance(forms.get(uuid), viser.GuiFormHandle) else Refusal("")


def _decode(raw: object) -> Message | Refusal:
    """``raw`` as a viser message, or why it closes the websocket."""
    if not isinstance(raw, bytes):
        reason = "text frames are not accepted: the page speaks MessagePack"
        return Refusal(reason, close=True, code=UNSUPPORTED_DATA)
    try:
        mapping = msgspec.msgpack.decode(raw)
    except msgspec.DecodeError:
        return Refusal("malformed message: not MessagePack", close=True)
    kind = mapping.get("type") if isinstance(mapping, dict) else None
    if not isinstance(kind, str):
        return Refusal("malformed message: no message type", close=True)
    if kind not in Message._subclass_from_type_string():
        return Refusal(f"malformed message: unknown type {kind[:40]!r}", close=True)
    try:
        return Message.deserialize(raw)
    except Exception:
        return Refusal(f"malformed message: bad fields for {kind[:40]}", close=True)


class _Screen:
    """The screen of one websocket: its buckets and when it last got a notice."""

    def __init__(self, server: viser.ViserServer, client_id: int) -> None:
        self.server = server
        self.client_id = client_id
        self.inputs = _Bucket(INPUT_RATE, INPUT_BURST)
        self.camera = _Bucket(CAMERA_RATE, 2 * CAMERA_RATE)
        self.noticed = -math.inf
        self.dropped = 0

    def verdict(self, raw: object) -> Refusal | None:
        """None to pass ``raw`` on, else why not."""
        message = _decode(raw)
        if isinstance(message, Refusal):
            return message
        if isinstance(message, _UPLOADS):
            reason = "file uploads are not accepted: the page has no upload"
            return Refusal(reason, close=True, code=POLICY_VIOLATION)
        now = time.monotonic()
        if isinstance(message, _messages.ViewerCameraMessage):
            return None if self.camera.take(now) else Refusal("")
        if isinstance(message, _INPUTS) and not self.inputs.take(now):
            self.dropped += 1
            return Refusal("too many inputs from this page", flood=True)
        if isinstance(message, _messages.GuiUpdateMessage):
            return _gui_refusal(self.server, self.client_id, message)
        if isinstance(message, _messages.GuiFormDirtyMessage):
            return _dirty_refusal(self.server, self.client_id, message.uuid)
        return None

    def notify(self, refusal: Refusal) -> None:
        """Tell the page why its input was ignored (a flood: at most once a second)."""
        now = time.monotonic()
        reason = refusal.reason
        if refusal.flood:
            if now - self.noticed < NOTICE_EVERY_S:
                return
            self.noticed = now
            reason, self.dropped = f"{reason} ({self.dropped} since the last notice)", 0
        client = self.server._connected_clients.get(self.client_id)
        if reason and client is not None:
            client.add_notification("input ignored", reason, auto_close_seconds=4.0, color="red")


def screen_connection(server: viser.ViserServer, client_id: int, live: Any) -> None:
    """Screen what websocket ``live`` (page ``client_id``) sends before viser reads it."""
    # viser warns of each value that does not match its field, on stderr: a peer's garbage
    warnings.filterwarnings("ignore", message=r"\[viser\] .* does not match annotation")
    live.protocol.max_message_size = MAX_FRAME
    receive: Callable[[], Awaitable[Any]] = live.recv
    screen = _Screen(server, client_id)

    async def recv() -> Any:
        while True:
            raw = await receive()
            refusal = screen.verdict(raw)
            if refusal is None:
                return raw
            if refusal.close:
                await live.close(
                    refusal.code, refusal.reason.encode()[:120].decode(errors="ignore")
                )
                return await receive()  # raises ConnectionClosed: viser ends the page quietly
            screen.notify(refusal)

    live.recv = recv
