"""The command-line options that put a CPU or a view on a network, and their checks.

``--listen`` / ``--connect`` are zenoh endpoints (several allowed), ``--host`` the page's
address, ``--tls-ca/--tls-cert/--tls-key`` the PEM files for ``tls/`` endpoints,
``--users`` the users file. Without a users file everything stays on this machine: a
``--listen`` or ``--host`` that is not loopback is refused (names would be claimed by
anyone who can reach the port).
"""

from __future__ import annotations

import ipaddress
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from s7graph.web.bus.protocol import valid_name
from s7graph.web.bus.session import BusEnds, TlsFiles

__all__ = ["NetOptions", "is_loopback_endpoint", "is_loopback_host"]

_LOCAL_NAMES = {"localhost", "localhost.localdomain", "ip6-localhost"}


def is_loopback_host(host: str) -> bool:
    """Whether ``host`` (a name or an address, IPv6 in brackets or not) is this machine only."""
    name = host.strip().strip("[]").lower()
    if name in _LOCAL_NAMES:
        return True
    try:
        return ipaddress.ip_address(name.split("%")[0]).is_loopback
    except ValueError:
        return False


def is_loopback_endpoint(endpoint: str) -> bool:
    """Whether a zenoh endpoint reaches this machine only (unix sockets, 127.0.0.1, ::1)."""
    proto, _, address = endpoint.partition("/")
    if proto.startswith("unixsock") or proto == "unixpipe":
        return True
    address = address.split("#")[0].split("?")[0]
    host = address.rsplit(":", 1)[0] if ":" in address else address
    return is_loopback_host(host)


@dataclass(frozen=True)
class NetOptions:
    """Where the bus and the page are reachable, and who may use them."""

    cpu: str = "cpu1"
    listen: Sequence[str] = ()
    connect: Sequence[str] = ()
    host: str = "127.0.0.1"
    users: Path | None = None
    tls_ca: Path | None = None
    tls_cert: Path | None = None
    tls_key: Path | None = None
    origins: Sequence[str] = field(default_factory=tuple)

    def problem(self, *, listening: bool = True) -> str | None:
        """What is wrong with these options (one line), or None."""
        if not valid_name(self.cpu):
            return f"--cpu {self.cpu!r}: use letters, digits, _ . - (up to 64)"
        for ep in (*self.listen, *self.connect):
            if "/" not in ep:
                return f"endpoint {ep!r}: write it as PROTOCOL/ADDRESS, e.g. tcp/127.0.0.1:7447"
        if self.users is None:
            for ep in self.listen:
                if not is_loopback_endpoint(ep):
                    return (
                        f"--listen {ep} is not loopback: without --users the bus stays on "
                        "this machine (give a users file to open it)"
                    )
            if listening and not is_loopback_host(self.host):
                return (
                    f"--host {self.host} is not loopback: without --users the page stays on "
                    "this machine (give a users file to open it)"
                )
        tls = [ep for ep in (*self.listen, *self.connect) if ep.startswith("tls/")]
        if (tls or self.tls_cert or self.tls_key) and self.tls_ca is None:
            return "tls/ endpoints need --tls-ca (the CA that signed the certificates)"
        if any(ep.startswith("tls/") for ep in self.listen) and not (
            self.tls_cert and self.tls_key
        ):
            return "listening on a tls/ endpoint needs --tls-cert and --tls-key"
        for path in (self.tls_ca, self.tls_cert, self.tls_key):
            if path is not None and not path.is_file():
                return f"{path}: no such file"
        return None

    @property
    def tls(self) -> TlsFiles | None:
        if self.tls_ca is None:
            return None
        cert = str(self.tls_cert) if self.tls_cert else None
        key = str(self.tls_key) if self.tls_key else None
        return TlsFiles(str(self.tls_ca), cert, key)

    @property
    def ends(self) -> BusEnds:
        return BusEnds(listen=tuple(self.listen), connect=tuple(self.connect), tls=self.tls)

    @property
    def on_bus(self) -> bool:
        """Whether the CPU should be on a bus even without a page."""
        return bool(self.listen or self.connect)
