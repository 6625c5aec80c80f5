"""The OPC UA server of the face, in a thread and an event loop of its own
(docs/opcua.md, "Running it").

:class:`OpcuaServer` starts asyncua's server for one CPU on the bus: its endpoint
(``--listen``), its security — the ``None`` policy only on a loopback address, and
``Basic256Sha256`` ``SignAndEncrypt`` with the given certificate and key; user name and
password tokens checked by the CPU, anonymous sessions read-only or refused; client
certificates checked against a trust folder when one is given — and its limits
(``web.opcua.sessions.Limits``). The face's process talks to the CPU only over the bus: an
OPC UA client, however hostile, costs this process, never a scan.
"""

from __future__ import annotations

import asyncio
import contextlib
import datetime
import gc
import ipaddress
import logging
import threading
from dataclasses import dataclass, field
from pathlib import Path
from typing import Final
from urllib.parse import urlparse

import zenoh
from asyncua import ua
from asyncua.crypto.truststore import TrustStore
from asyncua.crypto.validator import CertificateValidator, CertificateValidatorOptions
from asyncua.server.internal_session import InternalSession
from cryptography import x509
from cryptography.hazmat.primitives import serialization
from cryptography.hazmat.primitives.asymmetric import rsa
from cryptography.hazmat.primitives.asymmetric.types import PrivateKeyTypes

from s7graph.web.bus.protocol import CpuStatus
from s7graph.web.collector import GC_THRESHOLDS, quiet_collector
from s7graph.web.opcua.face import Face, FaceAttributes
from s7graph.web.opcua.framing import FaceUaServer
from s7graph.web.opcua.link import BusLink
from s7graph.web.opcua.model import NAMESPACE_URI
from s7graph.web.opcua.paging import MAX_CONTINUATIONS
from s7graph.web.opcua.sessions import BusUsers, FaceRules, FaceServer, Limits
from s7graph.web.opcua.space import Space
from s7graph.web.opcua.typed import ObjectIds, Server, ua_id

__all__ = [
    "DEFAULT_URL",
    "OpcuaOptions",
    "OpcuaServer",
    "listen_problem",
    "loopback",
    "quiet_collector",
]

DEFAULT_URL: Final = "opc.tcp://127.0.0.1:4840"
MAX_MESSAGE_BYTES: Final = 8 << 20
"""The largest request a client may send (a download's chart is up to 1 MB of text)."""
START_TIMEOUT_S: Final = 120.0


def loopback(url_or_host: str) -> bool:
    """Whether a host (a name or an address), or the host of an ``opc.tcp://`` URL, is
    this machine only."""
    host = urlparse(url_or_host).hostname if "://" in url_or_host else url_or_host
    name = (host or "").strip().strip("[]").lower()
    if name in ("localhost", "localhost.localdomain", "ip6-localhost"):
        return True
    try:
        return ipaddress.ip_address(name.split("%")[0]).is_loopback
    except ValueError:
        return False


def listen_problem(url: str, *, users: bool, cert: Path | None, key: Path | None) -> str | None:
    """What is wrong with serving OPC UA at ``url`` (one line), or None: an
    ``opc.tcp://HOST:PORT`` address; beyond loopback only with logins checked
    (``users``) and a certificate and key (``SignAndEncrypt`` only)."""
    parsed = urlparse(url)
    try:
        port = parsed.port
    except ValueError:
        port = None
    if parsed.scheme != "opc.tcp" or not parsed.hostname or port is None:
        return f"--listen {url!r}: write it as opc.tcp://HOST:PORT"
    if (cert is None) != (key is None):
        return "give the server's certificate and its key together (--cert, --key)"
    for path in (cert, key):
        if path is not None and not path.is_file():
            return f"{path}: no such file"
    if cert is not None and key is not None:
        problem = _certificate_problem(cert) or _key_problem(key) or _pair_problem(cert, key)
        if problem:
            return problem
    if not loopback(parsed.hostname):
        if not users:
            return (
                f"--listen {url} is not loopback: without --users the OPC UA server stays "
                "on this machine (give the users file the CPU checks logins against)"
            )
        if cert is None:
            return f"--listen {url} is not loopback: it needs --cert and --key (SignAndEncrypt)"
    return None


def _load_certificate(path: Path) -> x509.Certificate:
    """The certificate in ``path`` (PEM or DER); ValueError when it holds none."""
    data = path.read_bytes()
    if _format(data) == "pem":
        return x509.load_pem_x509_certificate(data)
    return x509.load_der_x509_certificate(data)


def _certificate_problem(cert: Path) -> str | None:
    """Why ``cert`` cannot be the server's certificate: not a certificate, or a key other
    than RSA (``Basic256Sha256`` signs and encrypts with RSA only)."""
    try:
        public = _load_certificate(cert).public_key()
    except (OSError, ValueError):
        return f"{cert}: not a certificate (PEM or DER)"
    if not isinstance(public, rsa.RSAPublicKey):
        kind = type(public).__name__.removesuffix("PublicKey").removeprefix("_")
        return (
            f"{cert}: a certificate with an {kind or 'other'} key: Basic256Sha256 needs an RSA "
            "key (s7graph certs makes EC keys, for the bus)"
        )
    return None


def _load_key(key: Path) -> PrivateKeyTypes:
    """The private key in ``key`` (PEM or DER, unencrypted); OSError, ValueError or
    TypeError when it holds none."""
    data = key.read_bytes()
    if _format(data) == "pem":
        return serialization.load_pem_private_key(data, None)
    return serialization.load_der_private_key(data, None)


def _key_problem(key: Path) -> str | None:
    """Why ``key`` cannot be the server's private key (PEM or DER, unencrypted)."""
    try:
        _load_key(key)
    except (OSError, ValueError, TypeError):
        return f"{key}: not a private key (PEM or DER, without a password)"
    return None


def _pair_problem(cert: Path, key: Path) -> str | None:
    """Why ``key`` is not the private key of ``cert`` (a server with a key of another
    certificate starts, then fails every secure channel without a word)."""
    fmt = serialization.PublicFormat.SubjectPublicKeyInfo
    mine = _load_key(key).public_key().public_bytes(serialization.Encoding.DER, fmt)
    theirs = _load_certificate(cert).public_key().public_bytes(serialization.Encoding.DER, fmt)
    if mine != theirs:
        return f"{key}: not the private key of the certificate {cert}"
    return None


def trust_problem(folder: Path) -> str | None:
    """Why the ``--trust`` folder cannot be read: a file in it that is no certificate."""
    for path in sorted(folder.iterdir()):
        if path.is_file():
            try:
                _load_certificate(path)
            except (OSError, ValueError):
                return f"--trust {folder}: {path.name} is not a certificate (PEM or DER)"
    return None


@dataclass(frozen=True)
class OpcuaOptions:
    """How the face serves OPC UA: ``url``; anonymous sessions read-only (``anonymous``)
    or refused; the server's certificate and key (PEM or DER); a folder of trusted client
    certificates (None: any client certificate opens a secure channel; the user token
    still decides); the limits; ``own_process``: the process is the face's alone, so its
    garbage collector may be tuned (:func:`quiet_collector`); ``writes``: what a client's
    write of a symbol sends, ``force`` or ``modify`` (``web.opcua.space.WRITES``)."""

    url: str = DEFAULT_URL
    anonymous: bool = True
    cert: Path | None = None
    key: Path | None = None
    trust: Path | None = None
    limits: Limits = field(default_factory=Limits)
    own_process: bool = False
    writes: str = "force"


def _format(data: bytes) -> str:
    """``pem`` or ``der``, by the content (whatever the file's name)."""
    return "pem" if b"-----BEGIN" in data else "der"


def application_uri(cpu: str, cert: Path | None) -> str:
    """The server's application URI: the certificate's (its subjectAltName URI), or
    ``urn:s7graph:opcua:<cpu>``."""
    if cert is not None:
        with contextlib.suppress(Exception):
            found = _load_certificate(cert)
            names = found.extensions.get_extension_for_class(x509.SubjectAlternativeName)
            uris = names.value.get_values_for_type(x509.UniformResourceIdentifier)
            if uris:
                return str(uris[0])
    return f"urn:s7graph:opcua:{cpu}"


def build_info() -> tuple[str, str, str, str, str, datetime.datetime]:
    """The server's ``BuildInfo`` (OPC UA Part 5, "BuildInfo"): product URI, manufacturer,
    product name, software version, build number and build date — s7graph's, where asyncua
    said ``FreeOpcUa Python Server`` ``1.0pre``; the date not known (1601-01-01, Part 6's
    null DateTime)."""
    from s7graph import __version__

    unknown = datetime.datetime(1601, 1, 1, tzinfo=datetime.UTC)
    return ("urn:s7graph", "s7graph", "s7graph OPC UA face", __version__, __version__, unknown)


class OpcuaServer:
    """The face of CPU ``status.cpu`` (as found on the bus) over zenoh ``session``,
    serving OPC UA as ``options`` say; :meth:`start`, then :meth:`stop`."""

    def __init__(self, session: zenoh.Session, status: CpuStatus, options: OpcuaOptions) -> None:
        self.session = session
        self.status = status
        self.options = options
        self.face: Face | None = None
        self.server: Server | None = None
        self.loop: asyncio.AbstractEventLoop | None = None
        self.error: BaseException | None = None
        self._ready = threading.Event()
        self._stop: asyncio.Event | None = None
        self._thread = threading.Thread(target=self._run, name="s7graph-opcua", daemon=True)

    @property
    def url(self) -> str:
        """The address served: the one asked for, with the port bound for port 0."""
        bound = self.server.bserver if self.server is not None else None
        parsed = urlparse(self.options.url)
        if bound is None or parsed.port != 0 or not bound.port:
            return self.options.url
        host = f"[{parsed.hostname}]" if ":" in (parsed.hostname or "") else parsed.hostname
        return f"opc.tcp://{host}:{bound.port}"

    def start(self, timeout: float = START_TIMEOUT_S) -> None:
        """Serve; raise what kept the server from starting (``RuntimeError`` when it did
        not start in ``timeout`` s)."""
        self._thread.start()
        if not self._ready.wait(timeout):
            raise RuntimeError(f"the OPC UA server did not start within {timeout:g} s")
        if self.error is not None:
            raise self.error

    def stop(self, timeout: float = 10.0) -> None:
        loop, stop = self.loop, self._stop
        if loop is not None and stop is not None:
            with contextlib.suppress(RuntimeError):
                loop.call_soon_threadsafe(stop.set)
        if self._thread.is_alive():
            self._thread.join(timeout)

    def _run(self) -> None:
        try:
            asyncio.run(self._main())
        except BaseException as exc:  # told to start(); the thread ends
            if self.error is None:
                self.error = exc
        finally:
            self._ready.set()

    async def _main(self) -> None:
        logging.getLogger("asyncua").setLevel(logging.CRITICAL)  # a line per refused request
        self.loop = asyncio.get_running_loop()
        self._stop = asyncio.Event()
        link = BusLink(self.session, self.status.cpu)
        try:
            server = await self._server(link)
            self.server = server
            ns = await server.register_namespace(NAMESPACE_URI)
            space = Space(server, ns, self.status.cpu, writes=self.options.writes)
            face = self.face = Face(server, link, space)
            server.iserver.attribute_service = FaceAttributes(server.iserver.aspace, face)
            if self.options.own_process:
                # the address space's hundreds of thousands of objects, built with the
                # default thresholds, had the collector walk them again and again: a
                # chart of 1,000 supervised steps took twice as long (docs/opcua.md)
                gc.set_threshold(*GC_THRESHOLDS)
            await face.start(self.status)
            await server.start()
            if self.options.own_process:
                # under a flood of requests a full collection stopped the loop for up to
                # 0.9 s (a step change's p99 from the bus to the address space 172 ms; 40 ms)
                quiet_collector()
                face.rebuilt = gc.freeze  # what a rebuild made stays, too
        except BaseException as exc:
            self.error = exc
            self._ready.set()
            link.close()
            raise
        self._ready.set()
        try:
            await self._stop.wait()
        finally:
            await face.stop()
            with contextlib.suppress(Exception):
                await server.stop()
            link.close()

    async def _server(self, link: BusLink) -> Server:
        options, limits = self.options, self.options.limits
        users = BusUsers(link.login, anonymous=options.anonymous)
        iserver = FaceServer(user_manager=users)
        iserver.limits = limits
        iserver.on_close = link.logout
        iserver.bind_condition_methods = True  # ConditionRefresh
        iserver.max_connections = limits.connections
        iserver.max_subscriptions = limits.sessions * limits.subscriptions
        iserver.max_pending_activation_seconds = 10.0
        iserver.max_monitored_item_queue_size = 1000
        InternalSession.max_connections = limits.sessions  # asyncua counts them there
        server = FaceUaServer(iserver=iserver)  # a chunk too large ends its connection
        await server.init()
        cpu = self.status.cpu
        server.set_endpoint(options.url)
        server.set_server_name(f"s7graph CPU {cpu}")
        server.product_uri = "urn:s7graph"
        server.manufacturer_name = "s7graph"
        await server.set_application_uri(application_uri(cpu, options.cert))
        await server.set_build_info(*build_info())
        server.allow_remote_admin(False)
        server.limits.max_message_size = MAX_MESSAGE_BYTES
        server.limits.max_chunk_count = MAX_MESSAGE_BYTES // server.limits.max_recv_buffer + 1
        tokens: list[type] = [ua.UserNameIdentityToken]
        if options.anonymous:
            tokens.insert(0, ua.AnonymousIdentityToken)
        server.set_identity_tokens(tokens)
        policies = [ua.SecurityPolicyType.Basic256Sha256_SignAndEncrypt]
        if options.cert is not None and options.key is not None:
            cert, key = options.cert.read_bytes(), options.key.read_bytes()
            await server.load_certificate(cert, _format(cert))
            await server.load_private_key(key, None, _format(key))
        else:
            policies = []
        host = urlparse(options.url).hostname or ""
        if loopback(host):
            policies.insert(0, ua.SecurityPolicyType.NoSecurity)
        server.set_security_policy(policies, permission_ruleset=FaceRules())  # type: ignore[arg-type]
        if options.trust is not None:
            store = TrustStore([options.trust], [])
            await store.load()
            checks = (
                CertificateValidatorOptions.TRUSTED_VALIDATION
                | CertificateValidatorOptions.PEER_CLIENT
            )
            server.set_certificate_validator(CertificateValidator(checks, store))
        await self._capabilities(server, limits)
        return server

    @staticmethod
    async def _capabilities(server: Server, limits: Limits) -> None:
        """The operation limits a client can read before it asks (Part 5,
        ``OperationLimits``)."""
        per_call = (
            ObjectIds.Server_ServerCapabilities_OperationLimits_MaxNodesPerRead,
            ObjectIds.Server_ServerCapabilities_OperationLimits_MaxNodesPerWrite,
            ObjectIds.Server_ServerCapabilities_OperationLimits_MaxNodesPerMethodCall,
            ObjectIds.Server_ServerCapabilities_OperationLimits_MaxNodesPerBrowse,
            ObjectIds.Server_ServerCapabilities_OperationLimits_MaxNodesPerRegisterNodes,
            ObjectIds.Server_ServerCapabilities_OperationLimits_MaxNodesPerTranslateBrowsePathsToNodeIds,
            ObjectIds.Server_ServerCapabilities_OperationLimits_MaxMonitoredItemsPerCall,
        )
        for oid in per_call:
            value = ua.DataValue(ua.Variant(limits.operations, ua.VariantType.UInt32))
            with contextlib.suppress(Exception):
                await server.write_attribute_value(ua_id(oid), value)
        points = ua.DataValue(ua.Variant(MAX_CONTINUATIONS, ua.VariantType.UInt16))
        with contextlib.suppress(Exception):  # web.opcua.paging
            oid = ObjectIds.Server_ServerCapabilities_MaxBrowseContinuationPoints
            await server.write_attribute_value(ua_id(oid), points)
