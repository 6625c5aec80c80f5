"""The CPU's ``login`` queryable: decoded on the zenoh thread, answered on a worker.

A login step (a users file read, the SCRAM exchange) may take milliseconds, so the zenoh
thread only decodes the request, names the link it came over (``web.bus.origin``) and
hands it to one worker thread, which asks the :class:`~web.bus.gate.Gate` and replies. A
login or proof whose link the CPU cannot name (a query without zenoh ``source_info`` on a
CPU with several links) is refused, and audited, with the reason the origin gives: what
the client must do. A logout is taken whatever its link: it only ends a session, and its
session key signs it.
"""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor

import zenoh

from s7graph.engine.errors import internal_error
from s7graph.web.bus.gate import Gate
from s7graph.web.bus.protocol import LoginReply, LoginRequest, ProtocolError, decode, encode

__all__ = ["LoginDoor"]

Origin = Callable[[zenoh.Query], tuple[str, str]]
"""Where a query came from, and why that cannot be told ("": it can)."""


class LoginDoor:
    """The ``login`` queryable of one CPU (``key``): logins answered by ``gate`` on a worker
    thread; ``origin`` names the link of each query (``BusPublisher.origin``)."""

    def __init__(self, key: str, gate: Gate, origin: Origin) -> None:
        self._key = key
        self._gate = gate
        self._origin = origin
        self._worker = ThreadPoolExecutor(max_workers=1, thread_name_prefix="s7graph-login")

    def on_query(self, query: zenoh.Query) -> None:
        """A zenoh thread: only the exact key (never a wildcard), decode, and hand the step
        to the worker, which replies; never raises."""
        if str(query.key_expr) != self._key:
            return
        try:
            payload = query.payload
            if payload is None:
                raise ProtocolError("empty login")
            request = decode(payload.to_bytes(), LoginRequest)
        except ProtocolError as exc:
            _reply(query, LoginReply(ok=False, reason=str(exc)))
            return
        source, unproven = self._origin(query)
        if request.op == "logout":
            unproven = ""
        try:
            self._worker.submit(self._login, request, query, source, unproven)
        except RuntimeError:  # shut down
            _reply(query, LoginReply(ok=False, reason="CPU bus closed"))

    def _login(self, request: LoginRequest, query: zenoh.Query, source: str, unproven: str) -> None:
        """Answer a login on the worker; ``source``: where it came from by the transport,
        ``unproven``: why that cannot be told (the refusal)."""
        try:
            reply = self._gate.login(request, source=source, unproven=unproven)
        except Exception:  # its message stays here: the asker is not logged in yet
            why = internal_error(f"in the CPU while answering a {request.op} request")
            reply = LoginReply(ok=False, reason=f"login failed: {why}")
        _reply(query, reply)

    def close(self) -> None:
        """Steps still waiting are dropped (their askers time out); none starts after."""
        self._worker.shutdown(wait=False, cancel_futures=True)


def _reply(query: zenoh.Query, reply: LoginReply) -> None:
    try:
        query.reply(query.key_expr, encode(reply), encoding=zenoh.Encoding.APPLICATION_JSON)
    except zenoh.ZError:
        pass  # the asker went away (timed out); nothing to tell
    finally:
        query.drop()  # type: ignore[no-untyped-call]  # zenoh's stub has no annotations
