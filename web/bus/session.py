"""How a session meets the zenoh bus: only the given endpoints, multicast and gossip
scouting off, and who it is — every session must be closed.

Credentials are zenoh's own: with a certificate (:class:`TlsFiles` with ``cert`` and
``key``) a node speaks **mutual TLS** on ``tls/`` endpoints — it shows its certificate
when it connects and asks for one from whoever connects to it, both checked against the
plant's CA; with a :class:`BusLogin` it proves a **user name and password** (zenoh's
``usrpwd``) on every link, and checks those of its callers against ``dictionary`` when it
listens. A node that guards CPUs (``guard``: the CPU itself, or ``s7graph router``) runs
zenoh's access control from ``web.bus.acl``: only each CPU's identity may serve its keys.

That guards the CPU's side. A node that joins a CPU — a shell, a view, an OPC UA face —
checks the other side with :func:`peer_problem`: whoever it reached directly over TLS must
be that CPU (``cpu.<name>``) or a router; any other certificate of the plant (a
``client.`` one) listening where the CPU should be would otherwise be believed, its
status and step states shown, until a login found it out.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import zenoh

from s7graph.web.bus.acl import acl_config

__all__ = ["BusEnds", "BusLogin", "TlsFiles", "loopback_config", "open_session", "peer_problem"]


@dataclass(frozen=True, slots=True)
class TlsFiles:
    """PEM files for zenoh's ``tls/`` endpoints: the CA that signed the peers'
    certificates, and this node's certificate and key (needed to listen; with them the
    node shows its certificate when it connects and asks for one when it listens)."""

    ca: str
    cert: str | None = None
    key: str | None = None

    @property
    def mutual(self) -> bool:
        """Whether this node has a certificate of its own (mutual TLS)."""
        return bool(self.cert and self.key)


@dataclass(frozen=True, slots=True)
class BusLogin:
    """zenoh's user/password authentication: this node's ``user`` and ``password``, and
    on a node that listens the ``dictionary`` file of its callers (``user:password``
    lines) — with it, a caller without a known pair cannot open a session."""

    user: str
    password: str = field(repr=False)
    dictionary: str | None = None


def loopback_config(
    listen: Iterable[str] = (),
    connect: Iterable[str] = (),
    *,
    mode: str | None = None,
    tls: TlsFiles | None = None,
    login: BusLogin | None = None,
    guard: Sequence[str] = (),
) -> zenoh.Config:
    """A zenoh config that talks only to the given endpoints, never multicasts or gossips.

    Endpoints look like ``tcp/127.0.0.1:7447``, ``tls/localhost:7447`` or
    ``unixsock-stream/<dir>/z.sock``. With no endpoints at all, the session only reaches
    itself (useful in one process). ``mode`` None: ``peer`` when listening (or with no
    endpoints), else ``client`` — a client reaches everyone through the peer or router it
    connects to. ``tls``, ``login``: this node's credentials (the module's docstring);
    ``guard``: the CPUs whose keys only they may serve (``web.bus.acl``)."""
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
        if tls.mutual:
            config.insert_json5("transport/link/tls/enable_mtls", "true")
            for side in ("listen", "connect"):
                config.insert_json5(f"transport/link/tls/{side}_certificate", json.dumps(tls.cert))
                config.insert_json5(f"transport/link/tls/{side}_private_key", json.dumps(tls.key))
    if login is not None:
        config.insert_json5("transport/auth/usrpwd/user", json.dumps(login.user))
        config.insert_json5("transport/auth/usrpwd/password", json.dumps(login.password))
        if login.dictionary is not None:
            config.insert_json5(
                "transport/auth/usrpwd/dictionary_file", json.dumps(login.dictionary)
            )
    if guard:
        config.insert_json5("access_control", json.dumps(acl_config(guard)))
    return config


def open_session(
    listen: Iterable[str] = (),
    connect: Iterable[str] = (),
    *,
    mode: str | None = None,
    tls: TlsFiles | None = None,
    login: BusLogin | None = None,
    guard: Sequence[str] = (),
) -> zenoh.Session:
    """Open a session on the given endpoints; the caller closes it (``with open_session(...)``)."""
    config = loopback_config(listen, connect, mode=mode, tls=tls, login=login, guard=guard)
    return zenoh.open(config)


def peer_problem(session: zenoh.Session, cpu: str) -> str | None:
    """Why a node ``session`` reached directly cannot be CPU ``cpu``'s way in (None: none
    can be faulted): it proved over TLS an identity (its certificate's common name) that is
    neither ``cpu.<cpu>`` nor a router's. Links that proved no one (a unix socket, TCP, a
    bus login) are not judged."""
    for link in session.info.links():
        who = link.auth_identifier or ""
        if who and who != f"cpu.{cpu}" and not who.startswith("router."):
            return (
                f"the node at {link.dst} is {who}, not cpu.{cpu} or a router: it is not "
                f"CPU {cpu} (connect to the CPU's own endpoint, or to a router)"
            )
    return None


@dataclass(frozen=True, slots=True)
class BusEnds:
    """Where a session meets the bus: endpoints to listen on and to connect to, and this
    node's credentials (TLS files, a bus login)."""

    listen: Sequence[str] = ()
    connect: Sequence[str] = ()
    tls: TlsFiles | None = None
    login: BusLogin | None = None

    def joining(self, connect: Sequence[str]) -> BusEnds:
        """These credentials, connecting to ``connect`` and listening nowhere (a view
        beside the CPU; it checks no callers, so without the login's dictionary)."""
        login = self.login
        if login is not None and login.dictionary is not None:
            login = BusLogin(login.user, login.password)
        return BusEnds(connect=tuple(connect), tls=self.tls, login=login)
