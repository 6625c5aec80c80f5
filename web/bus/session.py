"""How a session meets the zenoh bus: only the given endpoints, multicast and gossip
scouting off, TLS with :class:`TlsFiles`; every session must be closed."""

from __future__ import annotations

import json
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import zenoh

__all__ = ["BusEnds", "TlsFiles", "loopback_config", "open_session"]


@dataclass(frozen=True, slots=True)
class TlsFiles:
    """PEM files for zenoh's ``tls/`` endpoints: the CA that signed the peers'
    certificates, and this node's certificate and key (needed to listen)."""

    ca: str
    cert: str | None = None
    key: str | None = None


def loopback_config(
    listen: Iterable[str] = (),
    connect: Iterable[str] = (),
    *,
    mode: str | None = None,
    tls: TlsFiles | None = None,
) -> zenoh.Config:
    """A zenoh config that talks only to the given endpoints, never multicasts or gossips.

    Endpoints look like ``tcp/127.0.0.1:7447``, ``tls/localhost:7447`` or
    ``unixsock-stream/<dir>/z.sock``. With no endpoints at all, the session only reaches
    itself (useful in one process). ``mode`` None: ``peer`` when listening (or with no
    endpoints), else ``client`` — a client reaches everyone through the peer or router it
    connects to."""
    listen, connect = list(listen), list(connect)
    if mode is None:
        mode = "client" if connect and not listen else "peer"
    config = zenoh.Config()
    config.insert_json5("mode", json.dumps(mode))
    config.insert_json5("listen/endpoints", json.dumps(listen))
    config.insert_json5("connect/endpoints", json.dumps(connect))
    config.insert_json5("scouting/multicast/enabled", "false")
    config.insert_json5("scouting/gossip/enabled", "false")
    if tls is not None:
        config.insert_json5("transport/link/tls/root_ca_certificate", json.dumps(tls.ca))
        if tls.cert and tls.key:
            config.insert_json5("transport/link/tls/listen_certificate", json.dumps(tls.cert))
            config.insert_json5("transport/link/tls/listen_private_key", json.dumps(tls.key))
    return config


def open_session(
    listen: Iterable[str] = (),
    connect: Iterable[str] = (),
    *,
    mode: str | None = None,
    tls: TlsFiles | None = None,
) -> zenoh.Session:
    """Open a session on the given endpoints; the caller closes it (``with open_session(...)``)."""
    return zenoh.open(loopback_config(listen, connect, mode=mode, tls=tls))


@dataclass(frozen=True, slots=True)
class BusEnds:
    """Where a session meets the bus: endpoints to listen on and to connect to, and TLS."""

    listen: Sequence[str] = ()
    connect: Sequence[str] = ()
    tls: TlsFiles | None = None
