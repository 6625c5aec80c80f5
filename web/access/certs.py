"""A plant's certificates for the bus: one CA, and a certificate per node (``s7graph certs``).

The rule of names: a node's certificate says what it is and which one in its common name,
``<kind>.<name>`` — ``cpu.line1``, ``router.hub``, ``view.desk``, ``opcua.scada``,
``client.olga`` — with the kinds of :data:`KINDS` and a name as a CPU's (letters, digits,
``_ . -``, up to 64, not starting with a digit). The bus's access control (``web.bus.acl``)
grants a CPU's keys to the common name ``cpu.<its --cpu>`` and nothing to the others, so
the name is the identity.

Files, all in one folder: ``ca.pem`` (the CA's certificate, copied to every node) and
``ca.key`` (its key: keep it on the machine that issues, never copy it to a node), and for
each node ``<kind>.<name>.pem`` and ``<kind>.<name>.key``. Keys are EC P-256, written with
mode 0600 and never printed. A node's certificate is valid for serverAuth and clientAuth
(a node both listens and connects), names ``localhost``, ``127.0.0.1`` and ``::1`` and
each host given (an address or a DNS name) as subject alternative names, for 825 days; the
CA for ten years. Existing files are never overwritten unless asked (``force``).
"""

from __future__ import annotations

import datetime as dt
import ipaddress
import os
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Final

from s7graph.web.commands import NAME_PATTERN

if TYPE_CHECKING:
    from cryptography import x509
    from cryptography.hazmat.primitives.asymmetric import ec

__all__ = [
    "CA_CERT",
    "CA_KEY",
    "KINDS",
    "CertsError",
    "Issued",
    "common_name",
    "init_ca",
    "issue",
    "node_files",
    "read_common_name",
]

KINDS: Final = ("cpu", "router", "view", "opcua", "client")
"""What a node is: a CPU, a router, a browser view, an OPC UA server (``s7graph opcua``),
or a client (a shell, watch, a tool)."""
CA_CERT: Final = "ca.pem"
CA_KEY: Final = "ca.key"
CA_DAYS: Final = 3650
NODE_DAYS: Final = 825
LOOPBACK_HOSTS: Final = ("localhost", "127.0.0.1", "::1")
_NAME = re.compile(NAME_PATTERN)
_HOST = re.compile(r"^(?=.{1,253}$)[A-Za-z0-9*]([A-Za-z0-9-]*[A-Za-z0-9])?(\.[A-Za-z0-9-]+)*$")


class CertsError(ValueError):
    """A certificate that cannot be made or read; the text names the file and the way out."""


@dataclass(frozen=True, slots=True)
class Issued:
    """The files written: a certificate and its key."""

    cert: Path
    key: Path


def common_name(kind: str, name: str) -> str:
    """``<kind>.<name>``, the common name of a node's certificate; CertsError for a kind
    not in :data:`KINDS` or a name that is not a CPU-like name."""
    if kind not in KINDS:
        raise CertsError(f"--kind {kind!r}: use one of {', '.join(KINDS)}")
    if not _NAME.match(name):
        raise CertsError(
            f"name {name!r}: use letters, digits, _ . - (up to 64, not starting with a digit)"
        )
    return f"{kind}.{name}"


def node_files(directory: Path, cn: str) -> Issued:
    """Where the certificate and key of common name ``cn`` live in ``directory``."""
    return Issued(directory / f"{cn}.pem", directory / f"{cn}.key")


def _refuse_existing(paths: Iterable[Path], force: bool) -> None:
    if force:
        return
    for path in paths:
        if path.exists():
            raise CertsError(f"{path}: already there (give --force to replace it)")


def _write(path: Path, data: bytes, *, secret: bool) -> None:
    """Write ``data`` to ``path``; a secret is created with mode 0600 from the start."""
    try:
        path.parent.mkdir(mode=0o700, parents=True, exist_ok=True)
        if path.exists():
            path.unlink()
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600 if secret else 0o644)
        with os.fdopen(fd, "wb") as out:
            out.write(data)
    except OSError as exc:
        raise CertsError(f"{path}: cannot write: {exc.strerror or exc}") from None


def _name(cn: str) -> x509.Name:
    from cryptography import x509
    from cryptography.x509.oid import NameOID

    return x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, cn)])


def _pem_key(key: ec.EllipticCurvePrivateKey) -> bytes:
    from cryptography.hazmat.primitives import serialization

    return key.private_bytes(
        serialization.Encoding.PEM,
        serialization.PrivateFormat.PKCS8,
        serialization.NoEncryption(),
    )


def init_ca(directory: Path, *, force: bool = False, name: str = "s7graph CA") -> Issued:
    """Make the plant's CA in ``directory``: ``ca.pem`` and ``ca.key`` (0600)."""
    from cryptography import x509
    from cryptography.hazmat.primitives import hashes, serialization
    from cryptography.hazmat.primitives.asymmetric import ec

    files = Issued(directory / CA_CERT, directory / CA_KEY)
    _refuse_existing((files.cert, files.key), force)
    key = ec.generate_private_key(ec.SECP256R1())
    now = dt.datetime.now(dt.UTC)
    usage = x509.KeyUsage(
        digital_signature=True,
        key_cert_sign=True,
        crl_sign=True,
        content_commitment=False,
        key_encipherment=False,
        data_encipherment=False,
        key_agreement=False,
        encipher_only=False,
        decipher_only=False,
    )
    cert = (
        x509.CertificateBuilder()
        .subject_name(_name(name))
        .issuer_name(_name(name))
        .public_key(key.public_key())
        .serial_number(x509.random_serial_number())
        .not_valid_before(now - dt.timedelta(minutes=5))
        .not_valid_after(now + dt.timedelta(days=CA_DAYS))
        .add_extension(x509.BasicConstraints(ca=True, path_length=0), critical=True)
        .add_extension(usage, critical=True)
        .add_extension(x509.SubjectKeyIdentifier.from_public_key(key.public_key()), critical=False)
        .sign(key, hashes.SHA256())
    )
    _write(files.key, _pem_key(key), secret=True)
    _write(files.cert, cert.public_bytes(serialization.Encoding.PEM), secret=False)
    return files


def _load_ca(directory: Path) -> tuple[x509.Certificate, ec.EllipticCurvePrivateKey]:
    from cryptography import x509
    from cryptography.hazmat.primitives import serialization
    from cryptography.hazmat.primitives.asymmetric import ec

    cert_path, key_path = directory / CA_CERT, directory / CA_KEY
    hint = f"make it with: s7graph certs init {directory}"
    for path in (cert_path, key_path):
        if not path.is_file():
            raise CertsError(f"{path}: no such file ({hint})")
    try:
        cert = x509.load_pem_x509_certificate(cert_path.read_bytes())
    except (OSError, ValueError) as exc:
        raise CertsError(f"{cert_path}: cannot read the CA's certificate: {exc}") from None
    try:
        key = serialization.load_pem_private_key(key_path.read_bytes(), password=None)
    except (OSError, ValueError, TypeError) as exc:
        raise CertsError(f"{key_path}: cannot read the CA's key: {exc}") from None
    if not isinstance(key, ec.EllipticCurvePrivateKey) or key.public_key() != cert.public_key():
        raise CertsError(f"{key_path}: not the key of {cert_path} ({hint} --force)")
    return cert, key


def _alt_names(hosts: Sequence[str]) -> list[x509.GeneralName]:
    from cryptography import x509

    names: list[x509.GeneralName] = []
    for host in (*LOOPBACK_HOSTS, *hosts):
        text = host.strip().strip("[]")
        try:
            general: x509.GeneralName = x509.IPAddress(ipaddress.ip_address(text))
        except ValueError:
            if not _HOST.match(text):
                raise CertsError(f"--host {host!r}: not an IP address or a DNS name") from None
            general = x509.DNSName(text.lower())
        if general not in names:
            names.append(general)
    return names


def issue(
    directory: Path,
    name: str,
    kind: str,
    hosts: Sequence[str] = (),
    *,
    force: bool = False,
) -> Issued:
    """Issue the certificate of node ``<kind>.<name>`` with the CA of ``directory``, for
    ``localhost``, 127.0.0.1, ::1 and ``hosts``: ``<kind>.<name>.pem`` and ``.key`` (0600)."""
    from cryptography import x509
    from cryptography.hazmat.primitives import hashes, serialization
    from cryptography.hazmat.primitives.asymmetric import ec
    from cryptography.x509.oid import ExtendedKeyUsageOID

    cn = common_name(kind, name)
    alt = _alt_names(hosts)
    files = node_files(directory, cn)
    _refuse_existing((files.cert, files.key), force)
    ca_cert, ca_key = _load_ca(directory)
    key = ec.generate_private_key(ec.SECP256R1())
    now = dt.datetime.now(dt.UTC)
    eku = [ExtendedKeyUsageOID.SERVER_AUTH, ExtendedKeyUsageOID.CLIENT_AUTH]
    cert = (
        x509.CertificateBuilder()
        .subject_name(_name(cn))
        .issuer_name(ca_cert.subject)
        .public_key(key.public_key())
        .serial_number(x509.random_serial_number())
        .not_valid_before(now - dt.timedelta(minutes=5))
        .not_valid_after(now + dt.timedelta(days=NODE_DAYS))
        .add_extension(x509.SubjectAlternativeName(alt), critical=False)
        .add_extension(x509.BasicConstraints(ca=False, path_length=None), critical=True)
        .add_extension(x509.ExtendedKeyUsage(eku), critical=False)
        .add_extension(
            x509.AuthorityKeyIdentifier.from_issuer_public_key(ca_key.public_key()),
            critical=False,
        )
        .sign(ca_key, hashes.SHA256())
    )
    _write(files.key, _pem_key(key), secret=True)
    _write(files.cert, cert.public_bytes(serialization.Encoding.PEM), secret=False)
    return files


def read_common_name(path: Path) -> str:
    """The common name of the certificate in ``path``; CertsError naming the file."""
    from cryptography import x509
    from cryptography.x509.oid import NameOID

    try:
        cert = x509.load_pem_x509_certificate(path.read_bytes())
    except OSError as exc:
        raise CertsError(f"{path}: cannot read: {exc.strerror or exc}") from None
    except ValueError as exc:
        raise CertsError(f"{path}: not a PEM certificate: {exc}") from None
    names = cert.subject.get_attributes_for_oid(NameOID.COMMON_NAME)
    if not names:
        raise CertsError(f"{path}: the certificate has no common name")
    value = names[0].value
    return value.decode() if isinstance(value, bytes) else value
