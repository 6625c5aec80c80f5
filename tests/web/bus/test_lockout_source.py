"""Failed logins are counted per source (web/bus/origin.py ``lockout_source``): the
transport's identity and host, never its port, and a page's name (an OPC UA client's
host) only where one link relays many pages (clients)."""

from __future__ import annotations

from pathlib import Path

import pytest
import zenoh

from s7graph.web.bus.origin import UNKNOWN, lockout_source, stamp, transport_origin
from s7graph.web.bus.session import open_session


@pytest.mark.parametrize(
    ("transport", "claimed", "source"),
    [
        # a client that connects again from another port is the same source ...
        ("client.olga@tls/10.0.0.7:38574", "shell olga@pc pid 1", "client.olga@tls/10.0.0.7"),
        ("client.olga@tls/10.0.0.7:41000", "shell olga@pc pid 2", "client.olga@tls/10.0.0.7"),
        # ... whatever it claims: a claim it may change at every try is not believed
        ("client.rogue@tls/10.0.0.9:5000", "page 1 (10.0.0.7)", "client.rogue@tls/10.0.0.9"),
        # a view (or the CPU's own view) relays many pages: the page it names counts
        (
            "view.desk@tls/10.0.0.5:6000",
            "page 3 (10.0.0.7)",
            "view.desk@tls/10.0.0.5 / page 3 (10.0.0.7)",
        ),
        ("cpu.line1@tls/[::1]:6000", "page 4 (::1)", "cpu.line1@tls/[::1] / page 4 (::1)"),
        ("unixsock-stream/6c1f", "page 2 (127.0.0.1)", "unixsock-stream / page 2 (127.0.0.1)"),
        ("this process", "page 1", "this process / page 1"),
        # an OPC UA face relays many clients: the client's host counts, not its port
        (
            "opcua.scada@tls/10.0.0.5:40112",
            "opcua 10.0.0.7:51422",
            "opcua.scada@tls/10.0.0.5 / opcua 10.0.0.7",
        ),
        ("cpu.cpu1@tls/127.0.0.1:6000", "opcua ::1:5000", "cpu.cpu1@tls/127.0.0.1 / opcua ::1"),
        # behind a router every client is the router's link
        ("router.hub@tls/10.0.0.1:7447 (relayed)", "shell", "router.hub@tls/10.0.0.1 (relayed)"),
        ("tcp/127.0.0.1:4545", "shell", "tcp/127.0.0.1"),
        ("unknown transport", "shell", "unknown transport"),
    ],
)
def test_failed_logins_count_against_the_transport_and_a_relayed_page(
    transport: str, claimed: str, source: str
) -> None:
    assert lockout_source(transport, claimed) == source


def test_a_peer_that_copies_the_cpus_id_is_not_this_process(tmp_path: Path) -> None:
    """Every reply shows the CPU's zenoh id; a query naming it is "this process" (whose
    failed logins count per page it claims) only with this process's own stamp."""
    with open_session(listen=[f"unixsock-stream/{tmp_path}/bus.sock"]) as session:
        assert transport_origin(session, stamp(session)) == "this process"
        copied = zenoh.SourceInfo(session.id, stamp(session).source_sn ^ 1)
        assert transport_origin(session, copied) == UNKNOWN
        assert lockout_source(UNKNOWN, "page 1") == UNKNOWN  # the claimed page not believed
