"""A logged-in page's watch table signs its requests with the page's login, so a flood of
unsigned requests never makes it busy; a page not logged in asks unsigned and says *busy*
in words; a login the CPU no longer takes (expired, logged out) makes the page's table ask
unsigned from then on, saying so (web/view/watch_table.py, docs/view.md, "The watch
table"). Real zenoh sessions on loopback — the view's link bound to 127.0.0.2, each
flooding peer's to 127.0.0.3 on, so the CPU tells them apart — a program of blocks on the
virtual clock with a users file and real logins, the view's real viser pages opened by raw
websockets on the page's origin (no browser); a chart's page signs as a program's does."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
from websockets.sync.client import connect

from s7graph.engine import Cpu, VirtualClock
from s7graph.web.access.login import Authenticator
from s7graph.web.access.scram import MIN_ITERATIONS
from s7graph.web.access.users import UsersFile
from s7graph.web.bus.gate import Gate
from s7graph.web.bus.live import LiveGraph
from s7graph.web.bus.session import BusEnds, open_session
from s7graph.web.bus.watch import PER_SOURCE, UNPROVEN
from s7graph.web.harness.session import ChartSession, load_chart
from s7graph.web.view.edge import ViewSide
from s7graph.web.view.page_login import PageLogin
from s7graph.web.view.program_view import ProgramPage
from s7graph.web.wiring.live_edge import LiveEdge
from s7graph.web.wiring.program_edge import ProgramEdge
from tests.paths import ROOT
from tests.web.bus.test_diag_watch import program_cpu
from tests.web.bus.test_watch_proven_shares import _answers, _flood
from tests.web.helpers import PASSWORD, free_port, scanning, wait_until
from tests.web.view.test_hostile_websocket import CAMERA, PROTOCOL, Peer

pytestmark = pytest.mark.timeout(180)
VIEW_BUSY = "The CPU is busy (32 watch requests not signed by a login are waiting)"


@dataclass
class Plant:
    cpu: Cpu
    edge: ProgramEdge
    clock: VirtualClock  # the CPU's
    view: ViewSide  # the view's own session, bound to 127.0.0.2
    auth: Authenticator
    now: list[float]  # the authenticator's clock, s
    peers: list[Any]  # other zenoh sessions, each on a link of its own
    url: str

    def page(self, peer: Peer) -> ProgramPage:
        """The view's page of ``peer`` (known by the uuid of its Operands field)."""
        program = self.view.program
        assert program is not None
        uuid = peer.uuids["Operands"]

        def found() -> ProgramPage | None:
            pages = list(program.pages.values())
            mine = [p for p in pages if p.watch_table.operands._impl.uuid == uuid]
            return mine[0] if mine else None

        assert wait_until(lambda: found() is not None, 20), "the page was never kept"
        page = found()
        assert page is not None
        return page

    def scan(self) -> None:
        """One scan (10 ms of CPU time), handed to the edge as the runner would."""
        self.clock.advance(10)
        self.edge.on_record(self.cpu.scan(), stats=self.cpu.stats)

    def scan_until(self, held: Callable[[], bool], timeout: float = 30.0) -> bool:
        """Scan until ``held`` holds or ``timeout`` s passed; whether it held."""

        def scanned() -> bool:
            self.scan()
            return held()

        return wait_until(scanned, timeout, poll=0.02)


@contextmanager
def plant(tmp_path: Path, peers: int = 0) -> Iterator[Plant]:
    """A program's CPU with a users file (olga, a viewer) on TCP on 127.0.0.1, its view
    (``ViewSide``) on a link of its own, ``peers`` other sessions."""
    users = UsersFile(tmp_path / "users.json")
    users.add("olga", "viewer", PASSWORD, iterations=MIN_ITERATIONS)
    now = [1000.0]
    auth = Authenticator(users, clock=lambda: now[0])
    clock = VirtualClock()
    cpu = program_cpu(clock)
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    with (
        ProgramEdge(cpu, ends=BusEnds(listen=[endpoint]), gate=Gate(auth)) as edge,
        ExitStack() as s,
    ):
        others = [
            s.enter_context(open_session(connect=[f"{endpoint}#bind=127.0.0.{3 + i}:0"]))
            for i in range(peers)
        ]
        cpu.start()
        clock.advance(10)
        edge.on_record(cpu.scan(), stats=cpu.stats)  # a status for the view to find
        ends = BusEnds(connect=[f"{endpoint}#bind=127.0.0.2:0"])
        view = ViewSide(cpu="cpu1", fb=None, ends=ends, port=0)
        s.callback(view.close)
        assert edge.cpu_side is not None
        links = edge.cpu_side.session.info.links
        assert wait_until(lambda: len(list(links())) == peers + 1)
        made = Plant(cpu, edge, clock, view, auth, now, others, view.url)
        yield made


@contextmanager
def page(url: str) -> Iterator[Peer]:
    """A page of the view at ``url``: a raw websocket on its origin."""
    origin = url.rstrip("/")
    ws_url = url.replace("http://", "ws://")
    with connect(ws_url, origin=origin, subprotocols=[PROTOCOL], max_size=None) as ws:
        peer = Peer(ws)
        peer.send(CAMERA)
        assert peer.pump(lambda: "Operands" in peer.uuids and "Log in" in peer.uuids, 30)
        yield peer


def _log_in(peer: Peer, shown: PageLogin) -> str:
    """Log ``peer``'s page in as olga by its Login folder: the token the CPU gave it."""
    peer.update("User", value="olga")
    peer.update("Password", value=PASSWORD)
    assert wait_until(lambda: str(shown.user_field.value) == "olga")
    assert wait_until(lambda: str(shown.password.value) == PASSWORD)
    peer.update("Log in", value=True)
    assert wait_until(lambda: bool(shown.watch_token()), 20), shown.who.content
    return shown.watch_token()


def _table(shown: ProgramPage) -> str:
    return str(shown.watch_table.html.content)


def test_a_logged_in_pages_watch_waits_in_its_users_share_while_a_viewers_is_busy(
    tmp_path: Path,
) -> None:
    with plant(tmp_path, peers=9) as p, page(p.url) as olga_peer, page(p.url) as viewer_peer:
        olga, viewer = p.page(olga_peer), p.page(viewer_peer)
        _log_in(olga_peer, olga)
        answers: list[Any] = []
        for peer in p.peers:  # 9 sources × 8: the 32 unsigned places full, no boundary yet
            _answers(_flood(peer, PER_SOURCE), answers)
        assert wait_until(lambda: len(answers) == len(p.peers) * PER_SOURCE - UNPROVEN, 20)
        viewer_peer.update("Operands", value="MW0:INT")
        olga_peer.update("Operands", value="MW0:INT")
        assert wait_until(lambda: VIEW_BUSY in _table(viewer), 20), _table(viewer)
        assert "Log in: the watch of a logged-in page has places of its own" in _table(viewer)
        queue = p.edge.watching._queue  # type: ignore[union-attr]  # the CPU's own state
        assert wait_until(lambda: queue.waiting(proven=True) >= 1, 20)  # olga's, signed
        assert queue.waiting(proven=False) == UNPROVEN  # the flood's, still all there
        assert "busy" not in _table(olga).lower()
        assert p.scan_until(lambda: "cycle" in _table(olga)), _table(olga)
        assert "Watching without" not in _table(olga)


@pytest.mark.parametrize(
    ("end", "words"),
    [("expired", "the login expired"), ("logged out", "the CPU no longer knows this login")],
)
def test_a_login_that_ended_at_the_cpu_makes_the_page_watch_unsigned_saying_so(
    tmp_path: Path, end: str, words: str
) -> None:
    with plant(tmp_path) as p, page(p.url) as olga_peer:
        olga = p.page(olga_peer)
        token = _log_in(olga_peer, olga)
        olga_peer.update("Operands", value="MW0:INT")
        assert p.scan_until(lambda: "cycle" in _table(olga)), _table(olga)
        if end == "expired":
            p.now[0] += p.auth.ttl_s + 1
        else:
            assert p.auth.logout(token)
        said = f"Watching without a login from now on: {words}"
        assert p.scan_until(lambda: said in _table(olga)), _table(olga)
        assert p.scan_until(lambda: "cycle" in _table(olga) and said in _table(olga))
        assert olga.watch_token() == token  # the page still holds it: its table asks unsigned
        olga_peer.update("Log out", value=True)
        assert p.scan_until(lambda: "cycle" in _table(olga) and "Watching" not in _table(olga))


def test_a_chart_pages_watch_is_signed_by_its_login_too(tmp_path: Path) -> None:
    users = UsersFile(tmp_path / "users.json")
    users.add("olga", "operator", PASSWORD, iterations=MIN_ITERATIONS)
    auth = Authenticator(users)
    drill = ROOT / "examples" / "drill"
    cc, table = load_chart(drill / "drill.s7g", drill / "symbols.txt")
    session = ChartSession(cc, table, VirtualClock())
    live = LiveGraph(session.graph, read=session.get)
    with (
        LiveEdge(live, port=0, gate=Gate(auth), cpu_of=session.cpu) as edge,
        scanning(session, edge),
        page(edge.url) as olga_peer,
    ):
        assert edge.edge is not None
        uuid = olga_peer.uuids["Operands"]
        panels = edge.edge.view.panels

        def mine() -> list[Any]:
            found = list(panels.values())
            return [p for p in found if p.watch_table.operands._impl.uuid == uuid]

        assert wait_until(lambda: bool(mine()), 20)
        panel = mine()[0]
        token = _log_in(olga_peer, panel)
        olga_peer.update("Operands", value="MW0:INT")
        shown = panel.watch_table.html
        assert wait_until(lambda: "cycle" in str(shown.content), 30), shown.content
        assert auth.logout(token)  # only a signed request can be refused for its login
        said = "Watching without a login from now on: the CPU no longer knows this login"
        assert wait_until(lambda: said in str(shown.content) and "cycle" in str(shown.content))
