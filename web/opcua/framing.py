"""The face's OPC UA TCP connections: a message chunk larger than the server receives
ends its connection as soon as its header says so (docs/opcua.md, "Limits").

asyncua buffers a chunk whole before it checks its size against the receive buffer it
agreed on, copying the buffer anew for each read: a client whose header claimed a chunk of
4 GiB had the face hold everything it sent (80 MB in 8 s) and took the event loop from
every other client for each read, the longer the more it sent. :class:`FaceProtocol`
reads each chunk's size from its header and, past the server's receive buffer (no chunk
of any client may be larger: OPC UA Part 6, "Hello"), answers ``BadTcpMessageTooLarge``
and closes the connection. Its requests go to a :class:`FaceProcessor`, which serves
``BrowseNext`` (``web.opcua.paging``) and leaves the rest to asyncua's.
:class:`FaceUaServer` is asyncua's server serving each connection so.
"""

from __future__ import annotations

import logging
import socket
import struct
import time
from typing import Any, Final

from asyncua import ua
from asyncua.crypto import uacrypto
from asyncua.server.binary_server_asyncio import BinaryServer, OPCUAProtocol
from asyncua.server.uaprocessor import UaProcessor
from asyncua.ua.ua_binary import struct_from_binary, struct_to_binary

from s7graph.web.opcua.typed import ObjectIds, Server, StatusCodes, ua_id, ua_status

__all__ = ["FaceProcessor", "FaceProtocol", "FaceUaServer"]

_log = logging.getLogger("s7graph.web.opcua")

_HEADER: Final = struct.Struct("<3scI")  # message type, chunk type, the chunk's size
_BROWSE_NEXT: Final = ua_id(ObjectIds.BrowseNextRequest_Encoding_DefaultBinary)


class FaceProcessor(UaProcessor):
    """asyncua's request processor, serving ``BrowseNext`` too (asyncua 2.1 answers it
    ``BadServiceUnsupported``): the session's continuation points, ``web.opcua.paging``."""

    async def _process_message(self, typeid: Any, requesthdr: Any, seqhdr: Any, body: Any) -> Any:
        served: Any = super()._process_message  # asyncua's, untyped
        if typeid != _BROWSE_NEXT:
            return await served(typeid, requesthdr, seqhdr, body)
        session = self.session
        if session is None:  # as asyncua refuses any request before a session
            raise ua.uaerrors.BadUserAccessDenied
        rules: Any = self._connection.security_policy.permissions
        if rules is not None and rules.check_validity(session.user, typeid, body) is False:
            raise ua.uaerrors.BadUserAccessDenied
        self.session_last_activity = time.monotonic()
        session.touch()
        params = struct_from_binary(ua.BrowseNextParameters, body)
        response = ua.BrowseNextResponse()
        response.Parameters.Results = await session.browse_next(params)
        send: Any = self.send_response
        send(requesthdr.RequestHandle, seqhdr, response)
        return True


class FaceProtocol(OPCUAProtocol):
    """asyncua's connection, ended at the header of a chunk larger than it takes, its
    requests served by a :class:`FaceProcessor`."""

    def connection_made(self, transport: Any) -> None:
        super().connection_made(transport)
        if type(self.processor) is UaProcessor:  # made by asyncua just now, nothing served
            self.processor.__class__ = FaceProcessor

    def data_received(self, data: bytes) -> None:
        super().data_received(data)
        buffer, transport = self._buffer, self.transport
        if len(buffer) < _HEADER.size or transport is None or transport.is_closing():
            return
        _, _, size = _HEADER.unpack_from(buffer)
        limit = self.limits.max_recv_buffer
        if size <= limit:
            return
        self._buffer = b""
        reason = f"a chunk of {size} bytes; the server receives at most {limit}"
        _log.info("opcua: %s closed: %s", self.peer_name, reason)
        error = ua.ErrorMessage(ua_status(StatusCodes.BadTcpMessageTooLarge), ua.String(reason))
        body = struct_to_binary(error)
        transport.write(_HEADER.pack(b"ERR", b"F", _HEADER.size + len(body)) + body)
        transport.close()


class _FaceBinaryServer(BinaryServer):
    def _make_protocol(self) -> OPCUAProtocol:
        return FaceProtocol(
            iserver=self.iserver,
            policies=self._policies,
            clients=self.clients,
            closing_tasks=self.closing_tasks,
            limits=self.limits,
        )


class FaceUaServer(Server):
    """asyncua's server (2.1), its connections :class:`FaceProtocol` s."""

    async def start(self) -> None:
        """Listen, as asyncua's ``Server.start`` does, with :class:`FaceProtocol`."""
        if self.iserver.certificate is not None:
            uacrypto.check_certificate(
                self.iserver.certificate, self._application_uri, socket.gethostname()
            )
        await self._setup_server_nodes()
        await self.iserver.start()
        try:
            host, port = self._get_bind_socket_info()
            self.bserver = _FaceBinaryServer(self.iserver, host or "", port or 0, self.limits)
            self.bserver.set_policies(self._policies)
            await self.bserver.start()
        except Exception:
            await self.iserver.stop()
            raise
