"""What the OPC UA tests share: a CPU on the virtual clock on a real zenoh bus (mutual TLS,
as a CPU with a users file insists) with its OPC UA face in this process joining it as
``opcua.scada`` (``face_rig``), an asyncua client logged in or not, the certificates of a
test CA made with ``cryptography`` for OPC UA, and a free port."""

from __future__ import annotations

import asyncio
import datetime as dt
import socket
from collections.abc import AsyncIterator, Awaitable, Callable, Iterator
from contextlib import asynccontextmanager, contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

from asyncua import Client, ua

from s7graph.web.bus.client import find_cpus
from s7graph.web.bus.session import open_session
from s7graph.web.opcua.server import OpcuaOptions, OpcuaServer
from tests.web.helpers import OnlineRig, online_cpu, wait_until

if TYPE_CHECKING:
    from tests.conftest import BusCerts

T = TypeVar("T")

CHART = """FUNCTION_BLOCK "Seq_mix" FB 1 DB 1
  PARAMETERS := STANDARD;
  ACK_REQUIRED := TRUE; MESSAGES := TRUE;
VAR
  count : INT := 0;
  dwell : TIME := T#2S;
END_VAR
SYMBOLS
  "Start" : I0.0 : BOOL;
  "Guard" : I0.1 : BOOL;
  "Valve" : Q1.0 : BOOL;
  "Level" : MW20 : INT;
  "Flow"  : MD24 : REAL;
  "Total" : DB1.DBW30 : INT;
END_SYMBOLS
SEQUENCE 1 "Mix"
  INITIAL_STEP S1 "Idle":
  END_STEP
  STEP S2 "Fill" "Tank not filled in time":
    INTERLOCK := "Guard";
    SUPERVISION := S2.U > T#400MS;
    N "Valve";
    S1 N count := count + 1;
  END_STEP
  STEP S3 "Drain":
  END_STEP
  TRANSITION T1 "Go" FROM S1 TO S2 := "Start";
  TRANSITION T2 "Full" FROM S2 TO S3 := "Level" > 100;
  TRANSITION T3 "Empty" FROM S3 TO S1 := NOT "Start";
END_SEQUENCE
END_FUNCTION_BLOCK
"""
USERS = {"olga": "operator", "eng": "engineer", "vic": "viewer"}
PASSWORD = "correct horse"
NS_URI = "urn:s7graph:plc"
CLIENT_URI = "urn:s7graph:test:client"
FACE_CN = "opcua.scada"
"""The common name of the face's bus certificate (``s7graph certs issue … --kind opcua``)."""


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@dataclass
class FaceRig:
    """The CPU (``rig``) and its face (``server``) serving ``url``."""

    rig: OnlineRig
    server: OpcuaServer
    url: str

    def set(self, name: str, value: object) -> None:
        self.rig.session.set(name, value)

    def active(self) -> list[int]:
        g = self.rig.session.graph
        return sorted(g.cc.step_numbers[i] for i in g.state.active)


@contextmanager
def face_rig(
    tmp_path: Path,
    certs: BusCerts,
    *,
    chart: str = CHART,
    options: dict[str, Any] | None = None,
    blocks: dict[str, str] | None = None,
) -> Iterator[FaceRig]:
    """``chart`` running with ``USERS`` (password ``PASSWORD``) on a TLS bus with the
    certificates ``certs``, its operands published, and the OPC UA face of it in this
    process (joining as ``FACE_CN``) on a free loopback port (``options["url"]``: that
    address); ``blocks``: S7-SCL sources run beside the chart (``--blocks``)."""
    tmp_path.mkdir(parents=True, exist_ok=True)
    with (
        online_cpu(
            tmp_path,
            chart,
            serve=False,
            users=USERS,
            certs=certs,
            name="mix.s7g",
            operands=True,
            messages=True,
            blocks=blocks,
        ) as rig,
        open_session(connect=[rig.endpoint], tls=certs.tls(FACE_CN)) as session,
    ):
        assert wait_until(lambda: bool(find_cpus(session, timeout=1.0)), 20)
        status = find_cpus(session)[0]
        given = dict(options or {})
        url = str(given.pop("url", f"opc.tcp://127.0.0.1:{free_port()}"))
        server = OpcuaServer(session, status, OpcuaOptions(url=url, **given))
        server.start()
        try:
            yield FaceRig(rig, server, server.url)
        finally:
            server.stop()


@asynccontextmanager
async def connected(
    url: str, user: str | None = None, password: str = PASSWORD, **security: Any
) -> AsyncIterator[Client]:
    """An asyncua client of ``url``, logged in as ``user`` (None: anonymous). Its health
    probe (a read of the server's state every ``watchdog_intervall`` s, given as long to
    answer) waits 5 s: the face may hold a paced request up to 1 s, and a loaded machine
    adds to it — asyncua's 1 s would take that for a lost connection."""
    client = Client(url, timeout=10, watchdog_intervall=5.0)
    if user is not None:
        client.set_user(user)
        client.set_password(password)
    if security:
        client.application_uri = CLIENT_URI  # as its certificate says
        await client.set_security(**security)
    async with client:
        yield client


def node(client: Client, path: str) -> Any:
    """The node ``path`` (``cpu1/Seq_mix/S2/Active``) of the face's namespace (index 2)."""
    return client.get_node(ua.NodeId(path, 2))


def run(coro: Awaitable[T]) -> T:
    return asyncio.run(coro)  # type: ignore[arg-type]


async def eventually(check: Callable[[], Awaitable[bool]], timeout: float = 10.0) -> bool:
    """Await ``check()`` every 50 ms until it holds or ``timeout`` s passed."""
    loop = asyncio.get_running_loop()
    deadline = loop.time() + timeout
    while loop.time() < deadline:
        if await check():
            return True
        await asyncio.sleep(0.05)
    return await check()


@dataclass
class Certs:
    """A test CA and, signed by it, the server's and a client's certificate and key (PEM)."""

    ca: Path
    server_cert: Path
    server_key: Path
    client_cert: Path
    client_key: Path


def make_certs(where: Path, *, server_uri: str = "urn:s7graph:opcua:cpu1") -> Certs:
    """A CA and two certificates for OPC UA applications (their URI in subjectAltName)."""
    from cryptography import x509
    from cryptography.hazmat.primitives import hashes, serialization
    from cryptography.hazmat.primitives.asymmetric import rsa
    from cryptography.x509.oid import ExtendedKeyUsageOID, NameOID

    now = dt.datetime.now(dt.UTC)

    def key() -> rsa.RSAPrivateKey:
        return rsa.generate_private_key(public_exponent=65537, key_size=2048)

    def name(text: str) -> x509.Name:
        return x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, text)])

    ca_key = key()
    ca = (
        x509.CertificateBuilder()
        .subject_name(name("s7graph test CA"))
        .issuer_name(name("s7graph test CA"))
        .public_key(ca_key.public_key())
        .serial_number(x509.random_serial_number())
        .not_valid_before(now - dt.timedelta(days=1))
        .not_valid_after(now + dt.timedelta(days=30))
        .add_extension(x509.BasicConstraints(ca=True, path_length=None), critical=True)
        .sign(ca_key, hashes.SHA256())
    )

    def leaf(cn: str, uri: str, usage: Any) -> tuple[x509.Certificate, rsa.RSAPrivateKey]:
        k = key()
        cert = (
            x509.CertificateBuilder()
            .subject_name(name(cn))
            .issuer_name(ca.subject)
            .public_key(k.public_key())
            .serial_number(x509.random_serial_number())
            .not_valid_before(now - dt.timedelta(days=1))
            .not_valid_after(now + dt.timedelta(days=30))
            .add_extension(
                x509.SubjectAlternativeName(
                    [x509.UniformResourceIdentifier(uri), x509.DNSName("localhost")]
                ),
                critical=False,
            )
            .add_extension(
                x509.KeyUsage(
                    digital_signature=True,
                    content_commitment=True,
                    key_encipherment=True,
                    data_encipherment=True,
                    key_agreement=False,
                    key_cert_sign=False,
                    crl_sign=False,
                    encipher_only=False,
                    decipher_only=False,
                ),
                critical=False,
            )
            .add_extension(x509.ExtendedKeyUsage([usage]), critical=False)
            .sign(ca_key, hashes.SHA256())
        )
        return cert, k

    def write(path: Path, cert: x509.Certificate, k: rsa.RSAPrivateKey | None = None) -> None:
        path.write_bytes(cert.public_bytes(serialization.Encoding.PEM))
        if k is not None:
            path.with_name(path.stem + "-key.pem").write_bytes(
                k.private_bytes(
                    serialization.Encoding.PEM,
                    serialization.PrivateFormat.PKCS8,
                    serialization.NoEncryption(),
                )
            )

    where.mkdir(parents=True, exist_ok=True)
    server, server_key = leaf("s7graph opcua", server_uri, ExtendedKeyUsageOID.SERVER_AUTH)
    client, client_key = leaf(
        "test client", "urn:s7graph:test:client", ExtendedKeyUsageOID.CLIENT_AUTH
    )
    write(where / "ca.pem", ca)
    write(where / "server.pem", server, server_key)
    write(where / "client.pem", client, client_key)
    return Certs(
        where / "ca.pem",
        where / "server.pem",
        where / "server-key.pem",
        where / "client.pem",
        where / "client-key.pem",
    )
