"""Shared fixtures. Tests drive scans with the virtual clock; no sleeps in core tests."""

from __future__ import annotations

import os
import shutil
import signal
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from s7graph.engine.clock import VirtualClock

if TYPE_CHECKING:
    from s7graph.web.bus.session import TlsFiles

ROOT = Path(__file__).resolve().parent.parent
SHARED = ROOT.parent / "shared"


def pytest_configure(config: pytest.Config) -> None:
    """Ctrl-C reaches the processes the tests start: a suite started in the background by a
    shell (``pytest &``) inherits SIGINT ignored, and so would every ``s7graph`` process it
    starts — each test stopping one as a terminal does would wait for its time-out instead."""
    if signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)
    _private_endpoints(config)


def _private_endpoints(config: pytest.Config) -> None:
    """The suite's CPUs publish their endpoints (``web.bus.local``) in a folder of the
    suite's own, made fresh and removed at its end: a CPU named ``cpu1`` running elsewhere on
    the machine is never found by a test, and no test's CPU is found by a shell outside it.
    Set in the environment, so the processes the tests start inherit it; a test that needs
    another folder still sets its own."""
    runtime = tempfile.mkdtemp(prefix="s7t-")
    os.environ["XDG_RUNTIME_DIR"] = runtime
    config.add_cleanup(lambda: shutil.rmtree(runtime, ignore_errors=True))


@pytest.fixture
def clock() -> VirtualClock:
    return VirtualClock()


BUS_NODES = (
    ("cpu", "cpu1"),
    ("cpu", "line1"),
    ("cpu", "line2"),
    ("router", "hub"),
    ("view", "desk"),
    ("opcua", "scada"),
    ("client", "olga"),
    ("client", "rogue"),
)
"""The nodes ``bus_certs`` issues certificates for (``s7graph certs issue``)."""


@dataclass(frozen=True)
class BusCerts:
    """A plant's CA and one certificate per node of ``BUS_NODES``, made once per session."""

    folder: Path

    @property
    def ca(self) -> Path:
        return self.folder / "ca.pem"

    def cert(self, cn: str) -> tuple[Path, Path]:
        """The certificate and key of common name ``cn`` (``client.olga``)."""
        return self.folder / f"{cn}.pem", self.folder / f"{cn}.key"

    def tls(self, cn: str | None = None) -> TlsFiles:
        """The TLS files of node ``cn`` (None: the CA only, no certificate of its own)."""
        from s7graph.web.bus.session import TlsFiles

        if cn is None:
            return TlsFiles(str(self.ca))
        cert, key = self.cert(cn)
        return TlsFiles(str(self.ca), str(cert), str(key))

    def args(self, cn: str) -> list[str]:
        """The command-line options of node ``cn``: ``--tls-ca``, ``--tls-cert``, ``--tls-key``."""
        cert, key = self.cert(cn)
        return ["--tls-ca", str(self.ca), "--tls-cert", str(cert), "--tls-key", str(key)]


@pytest.fixture(scope="session")
def bus_certs(tmp_path_factory: pytest.TempPathFactory) -> BusCerts:
    """Certificates for the bus's mutual TLS, made with ``web.access.certs`` (EC keys: fast)."""
    from s7graph.web.access.certs import init_ca, issue

    folder = tmp_path_factory.mktemp("bus-certs")
    init_ca(folder)
    for kind, name in BUS_NODES:
        issue(folder, name, kind)
    return BusCerts(folder)
