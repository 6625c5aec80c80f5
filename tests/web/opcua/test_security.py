"""The OPC UA face's security (docs/opcua.md, "Security"): ``Basic256Sha256``
``SignAndEncrypt`` with certificates of a CA (made here with ``cryptography``), the
``None`` policy only on loopback and no other endpoint; anonymous sessions refused when
configured; client certificates checked against a trust folder when one is given; and
the listen address's rules, as the command line checks them."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import pytest
from asyncua import ua
from asyncua.crypto.security_policies import SecurityPolicyBasic256Sha256
from asyncua.ua.uaerrors import UaStatusCodeError

from s7graph.web.opcua.server import application_uri, listen_problem, loopback, trust_problem
from tests.web.opcua.helpers import FACE_CN, Certs, connected, face_rig, make_certs, node, run

if TYPE_CHECKING:
    from tests.conftest import BusCerts

pytestmark = pytest.mark.timeout(180)

B256 = "http://opcfoundation.org/UA/SecurityPolicy#Basic256Sha256"
NONE = "http://opcfoundation.org/UA/SecurityPolicy#None"


def _secure(
    certs: Certs, *, cert: Path | None = None, key: Path | None = None
) -> dict[str, object]:
    return {
        "policy": SecurityPolicyBasic256Sha256,
        "certificate": str(cert or certs.client_cert),
        "private_key": str(key or certs.client_key),
        "server_certificate": str(certs.server_cert),
        "mode": ua.MessageSecurityMode.SignAndEncrypt,
    }


def test_sign_and_encrypt_with_the_cas_certificates(tmp_path: Path, bus_certs: BusCerts) -> None:
    certs = make_certs(tmp_path / "pki")
    trusted = tmp_path / "trusted"  # the CA alone: what it signed is trusted
    trusted.mkdir()
    (trusted / "ca.pem").write_bytes(certs.ca.read_bytes())
    options = {"cert": certs.server_cert, "key": certs.server_key, "trust": trusted}
    stranger = make_certs(tmp_path / "stranger")  # another CA's client

    async def check(url: str) -> None:
        async with connected(url) as c:
            endpoints = await c.get_endpoints()
            shown = {(e.SecurityPolicyUri, e.SecurityMode) for e in endpoints}
            assert shown == {
                (NONE, ua.MessageSecurityMode.None_),
                (B256, ua.MessageSecurityMode.SignAndEncrypt),
            }
            server_uri = endpoints[0].Server.ApplicationUri
            assert server_uri == "urn:s7graph:opcua:cpu1"
        async with connected(url, "olga", **_secure(certs)) as c:
            assert await node(c, "cpu1/State").read_value() == "RUN"
            fb = node(c, "cpu1/Seq_mix")
            await fb.call_method(ua.NodeId("cpu1/Seq_mix/SetMode", 2), "MAN")
            await fb.call_method(ua.NodeId("cpu1/Seq_mix/SetMode", 2), "AUTO")
        with pytest.raises(ua.uaerrors.BadCertificateUntrusted):  # not of the trusted CA
            async with connected(
                url, "olga", **_secure(certs, cert=stranger.client_cert, key=stranger.client_key)
            ):
                pass

    with face_rig(tmp_path / "cpu", bus_certs, options=options) as face:
        run(check(face.url))


def test_anonymous_sessions_may_be_refused(tmp_path: Path, bus_certs: BusCerts) -> None:
    async def check(url: str) -> None:
        with pytest.raises(UaStatusCodeError) as refused:
            async with connected(url):
                pass
        assert refused.value.code in (
            ua.StatusCodes.BadIdentityTokenRejected,
            ua.StatusCodes.BadIdentityTokenInvalid,
            ua.StatusCodes.BadUserAccessDenied,
        )
        async with connected(url, "vic") as c:  # a viewer reads
            assert await node(c, "cpu1/State").read_value() == "RUN"
            tokens = {t.TokenType for e in await c.get_endpoints() for t in e.UserIdentityTokens}
            assert tokens == {ua.UserTokenType.UserName}

    with face_rig(tmp_path, bus_certs, options={"anonymous": False}) as face:
        run(check(face.url))


def test_the_listen_address_rules() -> None:
    assert listen_problem("opc.tcp://127.0.0.1:4840", users=False, cert=None, key=None) is None
    assert listen_problem("opc.tcp://[::1]:4840", users=False, cert=None, key=None) is None
    for url in ("tcp://127.0.0.1:4840", "opc.tcp://127.0.0.1", "127.0.0.1:4840", "opc.tcp://:1"):
        problem = listen_problem(url, users=False, cert=None, key=None)
        assert problem is not None and "opc.tcp://HOST:PORT" in problem, url
    beyond = "opc.tcp://0.0.0.0:4840"
    problem = listen_problem(beyond, users=False, cert=None, key=None)
    assert problem is not None and "--users" in problem
    problem = listen_problem(beyond, users=True, cert=None, key=None)
    assert problem is not None and "--cert and --key" in problem
    problem = listen_problem(beyond, users=True, cert=Path("/nonexistent.pem"), key=None)
    assert problem is not None and "together" in problem
    assert loopback("opc.tcp://localhost:4840") and not loopback("opc.tcp://10.0.0.1:4840")


def test_the_application_uri_is_the_certificates(tmp_path: Path) -> None:
    certs = make_certs(tmp_path, server_uri="urn:plant:line1:opcua")
    assert application_uri("cpu1", certs.server_cert) == "urn:plant:line1:opcua"
    assert application_uri("cpu1", None) == "urn:s7graph:opcua:cpu1"


def test_a_server_certificate_basic256sha256_cannot_use_is_refused_before_serving(
    tmp_path: Path, bus_certs: BusCerts
) -> None:
    """An EC certificate (what ``s7graph certs`` makes, for the bus) opened the face, whose
    every user login then failed: refused at the start, as a file that is no certificate,
    a key that is none, and a ``--trust`` folder with a file that is no certificate."""
    url = "opc.tcp://127.0.0.1:4840"
    rsa = make_certs(tmp_path / "rsa")
    ec_cert, ec_key = bus_certs.cert(FACE_CN)
    problem = listen_problem(url, users=True, cert=ec_cert, key=ec_key)
    assert problem == (
        f"{ec_cert}: a certificate with an EC key: Basic256Sha256 needs an RSA key "
        "(s7graph certs makes EC keys, for the bus)"
    )
    junk = tmp_path / "junk.pem"
    junk.write_text("-----BEGIN CERTIFICATE-----\nnot base64\n", encoding="utf-8")
    assert listen_problem(url, users=True, cert=junk, key=rsa.server_key) == (
        f"{junk}: not a certificate (PEM or DER)"
    )
    assert listen_problem(url, users=True, cert=rsa.server_cert, key=junk) == (
        f"{junk}: not a private key (PEM or DER, without a password)"
    )
    assert listen_problem(url, users=True, cert=rsa.server_cert, key=rsa.server_key) is None
    other = make_certs(tmp_path / "other")  # a key of another certificate: said at once
    assert listen_problem(url, users=True, cert=rsa.server_cert, key=other.server_key) == (
        f"{other.server_key}: not the private key of the certificate {rsa.server_cert}"
    )
    trusted = tmp_path / "trusted"
    trusted.mkdir()
    (trusted / "client.der").write_bytes(rsa.client_cert.read_bytes())
    assert trust_problem(trusted) is None
    (trusted / "notes.txt").write_text("who is who", encoding="utf-8")
    assert (
        trust_problem(trusted) == f"--trust {trusted}: notes.txt is not a certificate (PEM or DER)"
    )


def test_port_0_serves_on_a_free_port_and_says_which(tmp_path: Path, bus_certs: BusCerts) -> None:
    """``--listen opc.tcp://127.0.0.1:0``: the system picks the port, and the face's
    address (what ``s7graph opcua`` prints) is the one it bound."""
    with face_rig(tmp_path, bus_certs, options={"url": "opc.tcp://127.0.0.1:0"}) as face:
        assert face.url.startswith("opc.tcp://127.0.0.1:") and not face.url.endswith(":0")

        async def check() -> None:
            async with connected(face.url) as c:
                assert await node(c, "cpu1/State").read_value() == "RUN"

        run(check())
