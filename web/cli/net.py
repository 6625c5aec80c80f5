"""The command-line options that put a CPU, a router or a view on a network, and their
checks.

``--listen`` / ``--connect`` are zenoh endpoints (several allowed), ``--host`` the page's
address, ``--users`` the users file. Credentials on the bus (``web.bus.session``):
``--tls-ca/--tls-cert/--tls-key`` (with a certificate a node speaks mutual TLS on ``tls/``
endpoints), or ``--bus-user NAME`` with its password from ``--bus-password-file FILE`` or
``S7GRAPH_BUS_PASSWORD``, and on a listener ``--bus-users FILE`` (``user:password``
lines). The rules, checked at start (one line, exit 2):

- Without a users file everything stays on this machine: a ``--listen`` or ``--host``
  that is not loopback is refused, and so is a CPU's or a router's ``--connect`` that is
  not (names would be claimed by anyone who can reach the port, or a demo CPU commanded
  from the network).
- A CPU with a users file proves who it is and lets in only nodes that do: every endpoint
  it is given has credentials — a ``tls/`` endpoint with its certificate, or the bus
  login (``--bus-users`` where it listens). Only the private socket the CPU makes for
  itself when given no endpoint (a folder only its user may enter) needs none.
- A router with credentials relays only the CPUs named with ``--cpu``; one without stays
  on loopback.
- A CPU's identity is ``cpu.<its --cpu>``: its certificate's common name and its bus user.
"""

from __future__ import annotations

import ipaddress
import os
import re
import stat
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from s7graph.engine.text import is_unicode
from s7graph.web.bus.protocol import valid_name
from s7graph.web.bus.session import BusEnds, BusLogin, TlsFiles

__all__ = [
    "PASSWORD_ENV",
    "NetOptions",
    "edge_error",
    "is_loopback_endpoint",
    "is_loopback_host",
    "name_taken_note",
    "running_here",
]

_LOCAL_NAMES = {"localhost", "localhost.localdomain", "ip6-localhost"}
PASSWORD_ENV = "S7GRAPH_BUS_PASSWORD"
"""Where ``--bus-user``'s password comes from without ``--bus-password-file``."""
CERTS_HINT = "make certificates: s7graph certs init DIR; s7graph certs issue DIR NAME --kind KIND"
_ZENOH_PLACE = re.compile(r"\s+at \S+\.rs:\d+\.?")  # " at /…/orchestrator.rs:447."
_UNREACHED = re.compile(r"^Unable to connect to any of \[(.*)\]!?$")


def error_words(exc: BaseException) -> str:
    """What went wrong, in words: an OS error's own (``Address already in use``), zenoh's
    without the places in its Rust source (the one it quotes of a cause too), else the
    message — never a class name."""
    if isinstance(exc, OSError) and exc.strerror:
        return f"{exc.strerror}{f': {exc.filename}' if exc.filename else ''}"
    return _ZENOH_PLACE.sub("", str(exc)).strip() or "it gave no reason"


def running_here(cpu: str) -> str | None:
    """Where a CPU named ``cpu`` of this machine listens when one does (its unix socket
    takes a connection: one a killed CPU left does not, ``web.bus.local.listening``), else
    None."""
    from s7graph.web.bus import local

    endpoint = local.find(cpu)
    if endpoint is None or not endpoint.startswith("unixsock-stream/"):
        return None
    return endpoint if local.listening(endpoint) else None


def name_taken_note(net: NetOptions) -> str:
    """A warning when this run goes on the bus of this machine (no ``--listen`` or
    ``--connect``) under the name of a CPU running here: a shell then reaches only this
    one while it runs (the other writes its file again once this one ends, ``web.bus.local``);
    "" otherwise."""
    if net.listen or net.connect:
        return ""
    endpoint = running_here(net.cpu)
    if endpoint is None:
        return ""
    return (
        f"s7graph: warning: a CPU named {net.cpu} runs on this machine already ({endpoint}): "
        f"a shell reaches only this one while it runs (that one again once it ends); give "
        f"each its own name with --cpu NAME"
    )


def edge_error(exc: BaseException, net: NetOptions | None, *, web: bool) -> str:
    """Why ``s7graph run`` could not put its CPU on the bus or serve its page, in one line:
    nothing answering at ``--connect`` as any node that joins says it
    (``NetOptions.join_error``), zenoh's refusal as the bus's, anything else as the view's
    (``web``) or the bus's."""
    if NetOptions.unreached(exc):
        return (net or NetOptions()).join_error(exc)
    zenoh = type(exc).__module__.split(".", 1)[0] == "zenoh"
    what = "cannot serve the view" if web and not zenoh else "cannot put the CPU on the bus"
    return f"{what}: {error_words(exc)}"


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


def _private_file_problem(path: Path, option: str) -> str | None:
    """Why ``path`` may not hold a secret: missing, unreadable, or readable by others."""
    try:
        mode = path.stat().st_mode
        with path.open("rb"):
            pass
    except OSError as exc:
        return f"{option} {path}: cannot read it: {exc.strerror or exc}"
    if not stat.S_ISREG(mode):
        return f"{option} {path}: not a file"
    if mode & 0o077:
        return f"{option} {path}: others may read it (chmod 600 {path})"
    return None


def _dictionary_users(path: Path) -> set[str]:
    """The user names of a ``user:password`` file (as zenoh reads it: trimmed)."""
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return set()
    return {line.split(":", 1)[0].strip() for line in text.splitlines() if ":" in line}


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
    bus_user: str | None = None
    bus_password_file: Path | None = None
    bus_users: Path | None = None
    relays: Sequence[str] = ()
    """A router's ``--cpu`` names: the CPUs whose keys it lets their identity serve."""

    def problem(self, *, listening: bool = True, role: str = "client") -> str | None:
        """What is wrong with these options (one line), or None. ``listening``: the page
        is served (``--host`` checked); ``role``: ``cpu``, ``router`` or ``client`` (the
        module's rules)."""
        return (
            self._form_problem()
            or self._users_problem()
            or self._network_problem(listening=listening, role=role)
            or self._tls_problem()
            or self._login_problem()
            or self._credentials_problem(role)
        )

    def _form_problem(self) -> str | None:
        if not valid_name(self.cpu):
            return f"--cpu {self.cpu!r}: use letters, digits, _ . - (up to 64)"
        for name in self.relays:
            if not valid_name(name):
                return f"--cpu {name!r}: use letters, digits, _ . - (up to 64)"
        for ep in (*self.listen, *self.connect):
            if "/" not in ep or not ep.isprintable() or not is_unicode(ep):
                return f"endpoint {ep!r}: write it as PROTOCOL/ADDRESS, e.g. tcp/127.0.0.1:7447"
        return None

    def _users_problem(self) -> str | None:
        """A users file named is there, even where nothing reads it yet (a CPU without a
        bus or page): a mistyped path is said at start, not at the first login."""
        if self.users is not None and not self.users.is_file():
            return f"{self.users}: no such users file (s7graph users add ...)"
        return None

    def _network_problem(self, *, listening: bool, role: str) -> str | None:
        """The loopback rules: without a users file (a CPU) or credentials (a router) the
        bus and the page stay on this machine."""
        if role == "router":
            opened, what = self.has_credentials, "without credentials the router"
            way = f"give it certificates or --bus-users ({CERTS_HINT})"
        else:
            opened, what, way = self.users is not None, "without --users the bus", ""
            way = "give a users file to open it"
        if opened:
            return None
        for ep in self.listen:
            if not is_loopback_endpoint(ep):
                return f"--listen {ep} is not loopback: {what} stays on this machine ({way})"
        if role in ("cpu", "router"):
            for ep in self.connect:
                if not is_loopback_endpoint(ep):
                    return f"--connect {ep} is not loopback: {what} stays on this machine ({way})"
        if listening and role != "router" and not is_loopback_host(self.host):
            return (
                f"--host {self.host} is not loopback: without --users the page stays on "
                "this machine (give a users file to open it)"
            )
        return None

    def _tls_problem(self) -> str | None:
        tls = [ep for ep in (*self.listen, *self.connect) if ep.startswith("tls/")]
        if (tls or self.tls_cert or self.tls_key) and self.tls_ca is None:
            return "tls/ endpoints need --tls-ca (the CA that signed the certificates)"
        if bool(self.tls_cert) != bool(self.tls_key):
            return "--tls-cert and --tls-key go together (this node's certificate and its key)"
        if any(ep.startswith("tls/") for ep in self.listen) and not (
            self.tls_cert and self.tls_key
        ):
            return "listening on a tls/ endpoint needs --tls-cert and --tls-key"
        for path in (self.tls_ca, self.tls_cert, self.tls_key):
            if path is not None and not path.is_file():
                return f"{path}: no such file"
        return None

    def _login_problem(self) -> str | None:
        if self.bus_user is None:
            if self.bus_password_file is not None:
                return "--bus-password-file needs --bus-user (whose password it is)"
            if self.bus_users is not None:
                return "--bus-users needs --bus-user (this node's own name on the bus)"
            return None
        if not self.bus_user or ":" in self.bus_user or self.bus_user != self.bus_user.strip():
            return f"--bus-user {self.bus_user!r}: a name without ':' or spaces around it"
        if self.bus_password_file is not None:
            problem = _private_file_problem(self.bus_password_file, "--bus-password-file")
            if problem:
                return problem
            if not self._password():
                return f"--bus-password-file {self.bus_password_file}: the first line is empty"
        elif not os.environ.get(PASSWORD_ENV):
            return (
                f"--bus-user {self.bus_user} needs its password: --bus-password-file FILE "
                f"or {PASSWORD_ENV}"
            )
        if self.bus_users is not None:
            return _private_file_problem(self.bus_users, "--bus-users")
        return None

    def _credentials_problem(self, role: str) -> str | None:
        """A CPU with a users file, and a router with credentials or ``--users``, has
        credentials on every endpoint; a CPU's identity is ``cpu.<name>``; a router with
        credentials names its CPUs."""
        if role == "router" and self.has_credentials and not self.relays:
            return (
                "a router with credentials relays only the CPUs named with --cpu NAME "
                "(one --cpu for each)"
            )
        if role == "cpu":
            problem = self._identity_problem()
            if problem:
                return problem
        strict = self.users is not None or (role == "router" and self.has_credentials)
        if role in ("cpu", "router") and strict:
            for ep in self.listen:
                if not self._guards(ep):
                    return (
                        f"--listen {ep} would let anyone join: use a tls/ endpoint with "
                        f"--tls-cert/--tls-key, or --bus-users ({CERTS_HINT})"
                    )
            for ep in self.connect:
                if not self._proves(ep):
                    return (
                        f"--connect {ep} without credentials: prove who this node is with "
                        f"--tls-cert/--tls-key on a tls/ endpoint, or --bus-user ({CERTS_HINT})"
                    )
        return None

    def _identity_problem(self) -> str | None:
        want = f"cpu.{self.cpu}"
        if self.bus_user is not None and self.bus_user != want:
            return f"--bus-user {self.bus_user}: the bus user of CPU {self.cpu} is {want}"
        if self.bus_users is not None and want not in _dictionary_users(self.bus_users):
            return f"--bus-users {self.bus_users} has no line for {want}: its view joins as the CPU"
        if self.tls_cert is None or not self.tls_cert.is_file():
            return None
        from s7graph.web.access.certs import CertsError, read_common_name

        try:
            cn = read_common_name(self.tls_cert)
        except CertsError as exc:
            return f"--tls-cert {exc}"
        if cn != want:
            return (
                f"--tls-cert {self.tls_cert} is {cn!r}, not {want!r}: a CPU's certificate "
                f"names it (s7graph certs issue DIR {self.cpu} --kind cpu)"
            )
        return None

    def _guards(self, endpoint: str) -> bool:
        """Whether a listener on ``endpoint`` lets in only nodes with credentials."""
        mutual = self.tls_cert is not None and self.tls_key is not None
        return self.bus_users is not None or (endpoint.startswith("tls/") and mutual)

    def _proves(self, endpoint: str) -> bool:
        """Whether this node shows credentials when it connects to ``endpoint``."""
        mutual = self.tls_cert is not None and self.tls_key is not None
        return self.bus_user is not None or (endpoint.startswith("tls/") and mutual)

    @property
    def has_credentials(self) -> bool:
        """Whether this node proves who it is on the bus (a certificate, or a bus user)."""
        return bool(self.tls_cert and self.tls_key) or self.bus_user is not None

    def _password(self) -> str:
        if self.bus_password_file is not None:
            with self.bus_password_file.open(encoding="utf-8") as f:
                return f.readline().rstrip("\r\n")
        return os.environ.get(PASSWORD_ENV, "")

    @property
    def tls(self) -> TlsFiles | None:
        if self.tls_ca is None:
            return None
        cert = str(self.tls_cert) if self.tls_cert else None
        key = str(self.tls_key) if self.tls_key else None
        return TlsFiles(str(self.tls_ca), cert, key)

    @property
    def login(self) -> BusLogin | None:
        """The bus login (the password read now), or None without ``--bus-user``."""
        if self.bus_user is None:
            return None
        dictionary = str(self.bus_users) if self.bus_users is not None else None
        return BusLogin(self.bus_user, self._password(), dictionary)

    @property
    def ends(self) -> BusEnds:
        return BusEnds(
            listen=tuple(self.listen), connect=tuple(self.connect), tls=self.tls, login=self.login
        )

    @property
    def on_bus(self) -> bool:
        """Whether the CPU should be on a bus even without a page."""
        return bool(self.listen or self.connect)

    def join_hint(self) -> str:
        """What to add to "cannot join the bus" when this node showed no credentials."""
        if self.has_credentials:
            return ""
        return (
            " (a bus that lets in only nodes with credentials wants --tls-cert/--tls-key "
            "or --bus-user)"
        )

    def join_error(self, exc: BaseException) -> str:
        """Why this node could not join the bus, in one line: zenoh's own words without
        the place in its source they come from, and what to check."""
        words = error_words(exc)
        unreached = _UNREACHED.match(words)
        if unreached:
            ends = ", ".join(self.connect) or unreached.group(1)
            why = (
                "it refused this node's credentials"
                if self.has_credentials
                else "it lets in only nodes with credentials (--tls-cert/--tls-key or --bus-user)"
            )
            return (
                f"cannot join the bus: nothing answers at {ends}: nothing listens there, or {why}"
            )
        return f"cannot join the bus: {words[:300]}{self.join_hint()}"

    @staticmethod
    def unreached(exc: BaseException) -> bool:
        """Whether joining failed because nothing answered at the endpoints (nothing
        listens there yet, or it refused this node's credentials: zenoh cannot tell)."""
        return _UNREACHED.match(error_words(exc)) is not None

    def credential_args(self) -> list[str]:
        """The options that give a child process (the CPU's view) this node's credentials
        to connect with; a password from the environment reaches it there."""
        args: list[str] = []
        for option, value in (
            ("--tls-ca", self.tls_ca),
            ("--tls-cert", self.tls_cert),
            ("--tls-key", self.tls_key),
            ("--bus-user", self.bus_user),
            ("--bus-password-file", self.bus_password_file),
        ):
            if value is not None:
                args += [option, str(value)]
        return args
