"""Password guessing holds up no other client of the OPC UA face (docs/opcua.md,
"Security"): asyncua activates a session without yielding, and a wrong password costs the
face its SCRAM key derivation, so a host that sent ten wrong logins is refused unchecked —
whatever user it names, from whatever port — for 10 s, then twice as long after the next
wrong one; another host logs in meanwhile, and a right login forgets the count. A login
the bus could not carry to the CPU counts for nothing."""

from __future__ import annotations

from asyncua.crypto.permission_rules import User

from s7graph.web.access.lockout import Lockout
from s7graph.web.opcua.sessions import _ACTIVATING, HOST_FAILURES, BusUsers


class _Clock:
    def __init__(self) -> None:
        self.now = 1000.0

    def __call__(self) -> float:
        return self.now


def _users() -> tuple[BusUsers, list[str], _Clock]:
    asked: list[str] = []

    def login(user: str, password: str, origin: str) -> User | str:
        asked.append(f"{user} {origin}")
        if password == "down":
            return "no answer from CPU 'cpu1' within 5 s"
        return User() if password == "right" else "wrong password"

    clock = _Clock()
    users = BusUsers(login, anonymous=False)
    users.hosts = Lockout(max_failures=HOST_FAILURES, lockout_s=10, longest_s=300, clock=clock)
    return users, asked, clock


def _try(users: BusUsers, peer: str, user: str, password: str) -> User | None:
    mark = _ACTIVATING.set(peer)
    try:
        return users.get_user(None, username=user, password=password)  # type: ignore[arg-type]
    finally:
        _ACTIVATING.reset(mark)


def test_a_host_guessing_passwords_is_refused_unchecked_and_others_are_not() -> None:
    users, asked, clock = _users()
    for k in range(2 * HOST_FAILURES):  # the CPU not answering is no guess
        assert _try(users, f"10.0.0.7:{3000 + k}", "olga", "down") is None
    assert users.hosts.locked_for("", "10.0.0.7") == 0
    asked.clear()
    for k in range(HOST_FAILURES):
        assert _try(users, f"10.0.0.7:{4000 + k}", f"user{k}", "guess") is None
    assert len(asked) == HOST_FAILURES
    assert _try(users, "10.0.0.7:5000", "olga", "right") is None  # not even asked
    assert len(asked) == HOST_FAILURES
    assert _try(users, "10.0.0.8:5000", "olga", "right") is not None  # another host
    clock.now += 10.5
    assert _try(users, "10.0.0.7:5001", "olga", "guess") is None  # asked: one more wrong
    assert len(asked) == HOST_FAILURES + 2
    clock.now += 10.5
    assert _try(users, "10.0.0.7:5002", "olga", "right") is None  # locked twice as long
    clock.now += 10
    assert _try(users, "10.0.0.7:5003", "olga", "right") is not None
    assert _try(users, "10.0.0.7:5004", "olga", "guess") is None  # the count starts anew
    assert _try(users, "10.0.0.7:5005", "olga", "right") is not None
