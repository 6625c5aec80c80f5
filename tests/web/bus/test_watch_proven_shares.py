"""A watch request signed by a login waits in its user's own share, apart from every
request whose source is only a claim (web/bus/watch.py, web/bus/shares.py, docs/bus.md,
"The watch table: watch"): a peer that names a logged-in user's session id, or floods from
more sources than there are shares, fills the places of unsigned requests only, and the
user's signed watch is still answered at the next scan boundary. Real zenoh sessions on
loopback (each client's link bound to its own 127.0.0.x, so the CPU tells them apart)
against a program of blocks in this process, with a users file and real logins."""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterator
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import msgspec
import pytest
import zenoh

from s7graph.engine import VirtualClock
from s7graph.web.access.login import NOT_SIGNED, Authenticator
from s7graph.web.access.scram import MIN_ITERATIONS, Signer, log_in
from s7graph.web.access.users import UsersFile
from s7graph.web.bus.client import BusClient
from s7graph.web.bus.gate import Gate
from s7graph.web.bus.origin import stamp
from s7graph.web.bus.protocol import (
    LoginReply,
    LoginRequest,
    WatchRequest,
    WatchValues,
    decode,
    encode,
    watch_bytes,
)
from s7graph.web.bus.session import BusEnds, open_session
from s7graph.web.bus.shares import SharedQueue
from s7graph.web.bus.watch import PER_SOURCE, QUEUE, UNPROVEN
from s7graph.web.wiring.program_edge import ProgramEdge
from tests.web.bus.test_diag_watch import Rig, program_cpu
from tests.web.helpers import PASSWORD, free_port, wait_until

pytestmark = pytest.mark.timeout(120)
WATCH = "s7graph/cpu1/watch"
LOGIN = "s7graph/cpu1/login"
ASK = encode(WatchRequest(addresses=["MW0:INT"]))
UNSIGNED_FULL = (
    f"busy: {UNPROVEN} watch requests not signed by a login are waiting; ask again, or log "
    "in: a watch signed by a login has places of its own"
)
FROM_HERE = (
    f"busy: {PER_SOURCE} watch requests from here are waiting; ask again once they are answered"
)


@dataclass
class UsersBus:
    rig: Rig  # olga's client (logged in), and the scans
    token: str  # olga's login
    peers: list[zenoh.Session]  # other clients, each on a link of its own


@contextmanager
def users_bus(tmp_path: Path, peers: int) -> Iterator[UsersBus]:
    """A CPU with a users file on TCP on 127.0.0.1; olga's session bound to 127.0.0.2 and
    logged in, ``peers`` sessions bound to 127.0.0.3 on."""
    users = UsersFile(tmp_path / "users.json")
    users.add("olga", "viewer", PASSWORD, iterations=MIN_ITERATIONS)
    clock = VirtualClock()
    cpu = program_cpu(clock)
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    gate = Gate(Authenticator(users))
    with ProgramEdge(cpu, ends=BusEnds(listen=[endpoint]), gate=gate) as edge, ExitStack() as s:
        olga = s.enter_context(open_session(connect=[f"{endpoint}#bind=127.0.0.2:0"]))
        client = s.enter_context(BusClient(olga, "cpu1"))
        others = [
            s.enter_context(open_session(connect=[f"{endpoint}#bind=127.0.0.{3 + i}:0"]))
            for i in range(peers)
        ]
        cpu.start()
        rig = Rig(cpu, edge, client, olga, clock)
        rig.scan()
        assert wait_until(lambda: client.status() is not None)
        assert wait_until(lambda: len(list(edge.cpu_side.session.info.links())) == peers + 1)
        login = client.login("olga", PASSWORD)
        assert login.ok, login.reason
        yield UsersBus(rig, login.token, others)


def _flood(session: zenoh.Session, n: int, claim: zenoh.SourceInfo | None = None) -> list[Any]:
    """``n`` watch requests sent at once, in the name of ``claim`` (None: the session's own
    id): their reply handlers."""
    info = claim if claim is not None else stamp(session)
    return [session.get(WATCH, payload=ASK, timeout=20, source_info=info) for _ in range(n)]


def _answers(handlers: list[Any], got: list[WatchValues] | None = None) -> list[WatchValues]:
    """The answers as they come (into ``got``), each waited for on a thread of its own."""
    got = [] if got is None else got

    def one(handler: Any) -> None:
        for reply in handler:
            if reply.ok is not None:
                got.append(decode(reply.ok.payload.to_bytes(), WatchValues))

    for handler in handlers:
        threading.Thread(target=one, args=(handler,), daemon=True).start()
    return got


def _served(rig: Rig, ask: Callable[[], WatchValues]) -> WatchValues:
    """``ask`` on another thread, the CPU scanning until it is answered."""
    answers: list[WatchValues] = []
    asking = threading.Thread(target=lambda: answers.append(ask()))
    asking.start()
    while asking.is_alive():
        rig.scan()
        asking.join(0.01)
    return answers[0]


def test_a_peer_naming_a_logged_in_users_session_cannot_use_up_her_signed_watch(
    tmp_path: Path,
) -> None:
    with users_bus(tmp_path, peers=1) as bus:
        olga = bus.rig.session
        claim = zenoh.SourceInfo(olga.id, 1)  # the rogue names olga's session as its own
        answers = _answers(_flood(bus.peers[0], QUEUE, claim))  # no scan boundary meanwhile
        assert wait_until(lambda: len(answers) == QUEUE - PER_SOURCE)  # busy, at once
        assert {a.error for a in answers} == {FROM_HERE}
        # her unsigned request is where the claim put the rogue's: its share is used up
        assert bus.rig.client.watch(["MW0:INT"], timeout=2).error == FROM_HERE
        signed = _served(bus.rig, lambda: bus.rig.client.watch(["MW0:INT"], token=bus.token))
        assert signed.error == "" and signed.values[0].error == ""


def test_nine_flooding_sources_fill_only_the_unsigned_places_and_a_signed_watch_is_served(
    tmp_path: Path,
) -> None:
    with users_bus(tmp_path, peers=9) as bus:
        answers: list[WatchValues] = []
        for peer in bus.peers:  # 9 sources × 8: more than the 64 places of the queue
            _answers(_flood(peer, PER_SOURCE), answers)
        flood = len(bus.peers) * PER_SOURCE
        assert wait_until(lambda: len(answers) == flood - UNPROVEN)  # the rest: at once
        assert {a.error for a in answers} == {UNSIGNED_FULL}
        signed = _served(bus.rig, lambda: bus.rig.client.watch(["MW0:INT"], token=bus.token))
        assert signed.error == "" and signed.values[0].error == ""
        assert wait_until(lambda: len(answers) == flood)  # the 32 waiting answered in turn
        assert sum(not a.error for a in answers) == UNPROVEN


def test_a_signed_watch_replayed_changed_or_with_a_token_of_no_session_is_refused(
    tmp_path: Path,
) -> None:
    with users_bus(tmp_path, peers=1) as bus:
        peer = bus.peers[0]
        signer = _log_in(peer)  # olga again, from another link: her own session
        request = WatchRequest(addresses=["MW0:INT"], user="olga", token=signer.token)
        seq, mac = signer.numbered(lambda n: watch_bytes(msgspec.structs.replace(request, seq=n)))
        signed = msgspec.structs.replace(request, seq=seq, mac=mac)
        first = _served(bus.rig, lambda: _ask(peer, encode(signed)))
        assert first.error == "" and first.values[0].error == ""
        assert (
            _ask(peer, encode(signed)).error
            == f"watch refused: replayed or out of order: seq {seq}"
        )
        changed = msgspec.structs.replace(signed, addresses=["MW2:INT"], seq=seq + 1)
        assert _ask(peer, encode(changed)).error == f"watch refused: {NOT_SIGNED}"
        forged = msgspec.structs.replace(signed, token="x" * 43)
        assert _ask(peer, encode(forged)).error == "watch refused: invalid token: log in again"


def _log_in(session: zenoh.Session) -> Signer:
    """olga logged in over ``session`` by hand (the SCRAM exchange on ``login``): her
    session's signer."""

    def ask(scram: str, login_id: str) -> LoginReply:
        op: Literal["login", "proof"] = "proof" if login_id else "login"
        request = LoginRequest(op=op, user="olga", scram=scram, login_id=login_id)
        handler = session.get(
            LOGIN, payload=encode(request), timeout=10, source_info=stamp(session)
        )
        for reply in handler:
            if reply.ok is not None:
                return decode(reply.ok.payload.to_bytes(), LoginReply)
        raise AssertionError("no answer to a login")

    answer, signer = log_in("olga", PASSWORD, ask)
    assert signer is not None, answer
    return signer


def _ask(peer: zenoh.Session, payload: bytes) -> WatchValues:
    """One watch request of ``payload`` from ``peer``: its answer."""
    handler = peer.get(WATCH, payload=payload, timeout=10, source_info=stamp(peer))
    got = _answers([handler])
    assert wait_until(lambda: bool(got))
    return got[0]


def test_the_unproven_places_never_take_a_proven_place_nor_the_other_way_round() -> None:
    queue: SharedQueue[int] = SharedQueue(total=4, per_source=2, unproven=2)
    assert [queue.put(f"link {i}", i) for i in range(3)] == ["", "", "full"]
    assert queue.put("olga", 10, proven=True) == ""
    assert queue.put("link 0", 11, proven=True) == ""  # a proven name apart from a link's
    assert queue.put("olga", 12, proven=True) == ""
    assert queue.put("olga", 13, proven=True) == "source"
    assert queue.put("ivan", 14, proven=True) == ""
    assert queue.put("ivan", 15, proven=True) == "full"
    assert queue.waiting(proven=True) == 4 and queue.waiting(proven=False) == 2
    assert [queue.get() for _ in range(7)] == [0, 1, 10, 11, 12, 14, None]  # oldest first
