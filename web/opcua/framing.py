"""The face's OPC UA TCP connections: a message chunk larger than the server receives
ends its connection as soon as its header says so (docs/opcua.md, "Limits").

asyncua buffers a chunk whole before it checks its size against the receive buffer it
agreed on, copying the buffer anew for each read: a client whose header claimed a chunk of
4 GiB had the face hold everything it sent (80 MB in 8 s) and took the event loop from
every other client for each read, the longer the more it sent. :class:`FaceProtocol`
reads each chunk's size from its header and, past the server's receive buffer (no chunk
of any client may be larger: OPC UA Part 6, "Hello"), answers ``BadTcpMessageTooLarge``
and closes the connection. :class:`FaceUaServer` is asyncua's server serving each
connection so.
"""

from __future__ import annotations

import logging
import socket
import struct
from typing import Final

from asyncua import ua
from asyncua.crypto import uacrypto
from asyncua.server.binary_server_asyncio import BinaryServer, OPCUAProtocol
from asyncua.ua.ua_binary import struct_to_binary

from s7graph.web.opcua.typed import Server, StatusCodes, ua_status

__all__ = ["FaceProtocol", "FaceUaServer"]

_log = logging.getLogger("s7graph.web.opcua")

_HEADER: Final = struct.Struct("<3scI")  # message type, chunk type, the chunk's size


class FaceProtocol(OPCUAProtocol):
    """asyncua's connection, ended at the header of a chunk larger than it takes."""

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
