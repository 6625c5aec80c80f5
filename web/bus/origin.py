"""Where a login or a command came from, as the transport says — not as its sender claims.

A client names its session in each query (``source_info``: its zenoh id, :func:`stamp`);
the CPU looks that id up among its own links (``session.info.links()``) and describes the
link: ``<identity>@<remote locator>`` — ``client.olga@tls/127.0.0.1:38574`` (the
certificate's common name or the usrpwd user name, the address it connects from) — or the
locator alone when the link proved nobody. The rule (:func:`transport_origin`):

1. the claimed id is one of this session's links: that link;
2. else exactly one link, or exactly one link to a router: that link, ``(relayed)`` when
   it is a router's (the sender is behind it);
3. else ``unknown transport``: the CPU cannot tell which link it came over, and
   :func:`query_origin` says why and what the client must do — the CPU refuses such a
   login or command with that reason (``web.bus.publisher``).

A query that names this session's own id is "this process" only when it also carries this
process's own ``source_sn`` (:func:`stamp`: a random number drawn at start): every reply
shows a CPU's id, so a peer could copy it to pass for the CPU itself — its failed logins
counted per page it claims, its audit rows "this process". Such a copy counts as a query
that names no one (rules 2 and 3).

The limits: the id is the sender's claim, so a peer with valid credentials connected to the
same CPU could name another connected peer's id and be described as that peer's link;
through a router the CPU sees the router's link, not the sender's. The origin the sender
claims itself (``page 3 (10.0.0.7)``, ``shell olga@host pid 42``) stays in the audit row
as a note (``web.bus.gate.claimed_note``), never as its origin.
"""

from __future__ import annotations

import secrets
from typing import Any

import zenoh

__all__ = [
    "RELAYS",
    "UNKNOWN",
    "UNPROVEN",
    "lockout_source",
    "query_origin",
    "stamp",
    "transport_origin",
]

UNKNOWN = "unknown transport"
UNPROVEN = "origin unproven"
"""How a refusal of a query whose link the CPU cannot name begins."""
RELAYS = ("cpu.", "view.", "opcua.")
"""Identities that relay many people over one link (a view serves many pages, an OPC UA
face many clients; ``run --web`` and ``run --opcua`` give theirs the CPU's certificate,
or meet it on a unix socket in a folder only its own user may open): the page or client
such a link names is believed."""
_OWN_SN = secrets.randbits(32)
"""The ``source_sn`` of this process's stamps (a query from its own session is believed to
be by it only with this number, which no peer sees: only a CPU may serve its keys)."""


def stamp(session: zenoh.Session) -> zenoh.SourceInfo:
    """The ``source_info`` a client sends with a login or a command: its session's id."""
    return zenoh.SourceInfo(session.id, _OWN_SN)


def _describe(link: Any, relayed: bool = False) -> str:
    who = link.auth_identifier
    where = f"{who}@{link.dst}" if who else str(link.dst)
    return f"{where} (relayed)" if relayed else where


def transport_origin(session: zenoh.Session, source_info: zenoh.SourceInfo | None) -> str:
    """Where a query with ``source_info`` came from by this session's links (the module's
    rule); never raises (a failure is :data:`UNKNOWN`)."""
    return query_origin(session, source_info)[0]


def query_origin(session: zenoh.Session, source_info: zenoh.SourceInfo | None) -> tuple[str, str]:
    """(where a query with ``source_info`` came from, "") by the module's rule, or
    (:data:`UNKNOWN`, why the CPU cannot tell and what the client must do); never raises."""
    claimed, links, routers = "", [], 0
    try:
        claimed = str(source_info.source_id.zid) if source_info is not None else ""
        if claimed and claimed == str(session.zid()):
            if source_info is not None and source_info.source_sn == _OWN_SN:
                return "this process", ""
            claimed = ""  # the CPU's id copied by a peer: a query that names no one
        links = list(session.info.links())
        for link in links:
            if claimed and str(link.zid) == claimed:
                return _describe(link), ""
        zids = {str(t.zid) for t in session.info.transports() if t.whatami == zenoh.WhatAmI.ROUTER}
        via = [link for link in links if str(link.zid) in zids]
        routers = len(via)
        if routers == 1:
            return _describe(via[0], relayed=True), ""
        if len(links) == 1:
            return _describe(links[0]), ""
    except Exception:  # never raise on a zenoh thread
        return UNKNOWN, f"{UNPROVEN}: the CPU could not read its own links; ask again"
    return UNKNOWN, _unproven(bool(claimed), len(links), routers)


def _unproven(named: bool, links: int, routers: int) -> str:
    """Why a query's link cannot be named, and what its sender must do."""
    have = f"this CPU has {links} link{'s' if links != 1 else ''}"
    if not named:
        return (
            f"{UNPROVEN}: {have} and the request names no session of its own: send it with "
            "zenoh source_info naming your session (zenoh.SourceInfo(session.id, n)), as "
            "s7graph's own clients do"
        )
    also = ", or through a router" if not routers else ""
    return (
        f"{UNPROVEN}: the session the request names is not linked to this CPU, and the CPU "
        f"cannot tell which of its {links} links relayed it ({routers} to routers): connect "
        f"to the CPU directly{also}"
    )


def lockout_source(transport: str, claimed: str) -> str:
    """Where failed logins are counted from: the transport's identity and host, without
    the port (a client that connects again is the same source); for a link of a
    :data:`RELAYS` identity, a unix socket, or this process, also the page it names, so one
    bad page locks out itself and not every page of that view — an OPC UA face's client
    (``opcua HOST:PORT``) by its host, as a direct client. Any other claim is ignored: a
    client could change it at every try to dodge the lockout."""
    who, at, where = transport.partition("@")
    if not at:
        who, where = "", transport
    relayed = where.endswith(" (relayed)")
    host = where.removesuffix(" (relayed)")
    if host.startswith("unixsock-stream/"):
        host = "unixsock-stream"  # each connection has its own name: the socket is one place
    elif host.count(":") and not host.endswith("]"):
        host = host.rsplit(":", 1)[0]
    key = f"{who}@{host}" if who else host
    key += " (relayed)" if relayed else ""
    local = transport == "this process" or host == "unixsock-stream"
    if claimed and (local or who.startswith(RELAYS)):
        if claimed.startswith("opcua ") and ":" in claimed:  # its port changes per session
            claimed = claimed.rsplit(":", 1)[0]
        return f"{key} / {claimed}"
    return key
