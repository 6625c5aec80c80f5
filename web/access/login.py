"""Logins on the CPU side: a SCRAM-SHA-256 exchange in, a token and a session key out.

:class:`Authenticator` answers the bus's ``login`` in two steps — :meth:`~Authenticator.login`
takes the client-first message and gives a challenge (server-first) under a login id,
:meth:`~Authenticator.prove` takes the proof and gives the server's signature, a token and
the role (``web.access.scram``: the password never travels). A login not finished within
10 s is forgotten, and at most 256 wait at once. A name nobody has gets a challenge like
any other (the same salt at every try) and fails at the proof: the answers do not tell
which names exist.

A session is the token (256 random bits, kept only as its SHA-256; valid for ``ttl_s``,
8 h, until logout) and the session key both ends derived from the exchange. Every
command of the session carries a ``seq`` and a ``mac`` (``web.access.scram.Signer``):
:meth:`~Authenticator.verify` refuses one the key did not sign and one whose ``seq`` it
has seen, or that is 64 or more below the highest seen — numbers may arrive a little out
of order (a page's buttons, the engineering worker beside the scan boundary), never
twice. :meth:`~Authenticator.identify` tells who holds a token. Wrong passwords lock the
*source* that sent them out for that user, with back-off (``web.access.lockout``), never
the user. The users file is read again whenever it changes, so a removed user's tokens
stop working and a changed role acts at once.

Without a users file (the demo) any valid name logs in in one step, without a password,
as an *unverified* engineer: ``alice (unverified)`` in the audit and the alarm log;
commands are then not signed.

A users file that others may read (group or world bits, as ``UsersFile.load`` refuses at
start) is noticed at the next login or command, ``chmod`` included — the mode is checked
with every look at the mtime, and a chmod changes no mtime: logins are refused (``users
file is readable by others: chmod 600 FILE``) until it is fixed, sessions already open go
on, and ``on_users_file`` is called once when it happens and once when it is fixed.
"""

from __future__ import annotations

import collections
import dataclasses
import hashlib
import hmac
import math
import secrets
import stat
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Final

from s7graph.web.access.lockout import LOCKOUT_S, LONGEST_LOCKOUT_S, MAX_FAILURES, Lockout
from s7graph.web.access.scram import (
    LoginError,
    ServerLogin,
    Signer,
    fake_verifier,
    log_in,
    sign,
)
from s7graph.web.access.users import User, UsersError, UsersFile, name_problem

__all__ = [
    "DEMO_ROLE",
    "NOT_SIGNED",
    "Authenticator",
    "Identity",
    "LoginResult",
    "password_login",
]

DEMO_ROLE: Final = "engineer"
TOKEN_TTL_S: Final = 8 * 3600.0
MAX_TOKEN: Final = 64
LOGIN_WINDOW_S: Final = 10.0
MAX_PENDING: Final = 256
PENDING_PER_SOURCE: Final = 8
"""Unfinished logins one source may hold: a flood of first steps from one place fills its
own eight, never the table every other place's logins wait in."""
REPLAY_WINDOW: Final = 64
_MAX_SESSIONS: Final = 4096
_WRONG: Final = "wrong user name or password"
NOT_SIGNED: Final = (
    "not signed by the session: changed on the way, or a token used without its session key"
)


@dataclass(frozen=True, slots=True)
class Identity:
    """Who sent a command, as the CPU established it."""

    user: str
    role: str
    verified: bool = True

    @property
    def label(self) -> str:
        """The name written to the audit and the alarm log."""
        return self.user if self.verified else f"{self.user} (unverified)"


@dataclass(frozen=True, slots=True)
class LoginResult:
    """One step's answer: logged in (``ok``, a token), a challenge (``login_id`` and the
    server-first in ``scram``: send the proof), or a refusal and why."""

    ok: bool
    reason: str = ""
    token: str = ""
    role: str = ""
    expires_ms: int = 0  # wall clock, ms since the epoch
    verified: bool = True
    login_id: str = ""
    scram: str = ""  # server-first (a challenge) or server-final (logged in)

    @property
    def challenge(self) -> bool:
        """A first step answered: the client sends its proof under ``login_id``."""
        return bool(self.login_id) and not self.ok


@dataclass(slots=True)
class _Session:
    user: str
    expires: float  # monotonic
    role: str  # the demo's role; with a users file the file's current role wins
    key: bytes = b""  # the session key (the demo: none)
    top: int = 0  # the highest seq accepted
    seen: int = 0  # bit i: seq top - i was accepted

    def fresh(self, seq: int) -> bool:
        """Whether ``seq`` is new to this session (then it counts as seen)."""
        if seq < 1:
            return False
        if seq > self.top:
            shift = seq - self.top  # a jump past the window forgets it (never a huge shift)
            kept = self.seen << shift if shift < REPLAY_WINDOW else 0
            self.seen = (kept | 1) & ((1 << REPLAY_WINDOW) - 1)
            self.top = seq
            return True
        if self.top - seq >= REPLAY_WINDOW:  # below the window (never a huge shift)
            return False
        bit = 1 << (self.top - seq)
        if self.seen & bit:
            return False
        self.seen |= bit
        return True


@dataclass(slots=True)
class _Pending:
    user: str
    source: str
    exchange: ServerLogin
    started: float  # monotonic


def _digest(token: str) -> str:
    return hashlib.sha256(token.encode()).hexdigest()


class Authenticator:
    """Logins, sessions and lockouts of one CPU; thread-safe."""

    exposed: str = ""
    """Why logins are refused while the users file is readable by others ("": it is not)."""
    on_users_file: Callable[[bool, str], None] | None = None
    """Called (exposed, text) when the users file becomes readable by others and when it
    is fixed; under the authenticator's lock: it must not block (``web.bus.gate``'s
    queues a diagnostic buffer entry)."""

    def __init__(
        self,
        users: UsersFile | None,
        *,
        ttl_s: float = TOKEN_TTL_S,
        lockout_s: float = LOCKOUT_S,
        longest_lockout_s: float = LONGEST_LOCKOUT_S,
        max_failures: int = MAX_FAILURES,
        clock: Callable[[], float] = time.monotonic,
        wall: Callable[[], float] = time.time,
    ) -> None:
        self.users_file = users
        self.ttl_s = ttl_s
        self.lockout = Lockout(
            max_failures=max_failures,
            lockout_s=lockout_s,
            longest_s=longest_lockout_s,
            clock=clock,
        )
        self._clock = clock
        self._wall = wall
        self._lock = threading.Lock()
        self._secret = secrets.token_bytes(32)  # the unknown names' fake salts
        self._sessions: dict[str, _Session] = {}
        self._pending: dict[str, _Pending] = {}
        self._pending_from: collections.Counter[str] = collections.Counter()  # per source
        self._users: dict[str, User] = {}
        self._mtime: int | None = -1
        if users is not None:
            self._reload()

    @property
    def demo(self) -> bool:
        """No users file: names are claimed, not verified."""
        return self.users_file is None

    def _reload(self) -> None:
        """Read the users file again if it changed (a broken file keeps the last good one)."""
        assert self.users_file is not None
        mtime = self._look()
        if mtime == self._mtime:
            return
        try:
            self._users = self.users_file.load()
        except UsersError:
            return
        self._mtime = mtime

    def _user(self, name: str) -> User | None:
        with self._lock:
            self._reload()
            return self._users.get(name)

    def _look(self) -> int | None:
        """The users file's mtime (None: no file), noting a change of whether others may
        read it (one stat for both)."""
        assert self.users_file is not None
        path = self.users_file.path
        try:
            info = path.stat()
        except FileNotFoundError:
            info = None
        exposed = info is not None and bool(info.st_mode & (stat.S_IRWXG | stat.S_IRWXO))
        if exposed != bool(self.exposed):
            self.exposed = f"users file is readable by others: chmod 600 {path}" if exposed else ""
            if self.on_users_file is not None:
                fixed = f"users file {path} is no longer readable by others: logins taken again"
                self.on_users_file(exposed, self.exposed or fixed)
        return info.st_mtime_ns if info is not None else None

    def knows(self, user: str) -> bool:
        """Whether ``user`` is a user of the users file (as last read)."""
        with self._lock:
            return user in self._users

    # ------------------------------------------------------------ login / logout

    def login(self, user: str, scram: str = "", *, source: str = "") -> LoginResult:
        """The first step from ``source``: ``scram`` is the client-first message; the
        answer a challenge (or a refusal). Demo: the token at once, ``scram`` unused."""
        refused = self._refused(user, source)
        if refused is not None:
            return refused
        if self.users_file is None:
            return self._open(user, DEMO_ROLE, b"", verified=False)
        known = self._user(user)
        if self.exposed:
            return LoginResult(False, self.exposed)
        if not scram:
            return LoginResult(False, "this CPU checks passwords: log in with a password")
        if known is not None and known.legacy:
            return LoginResult(
                False,
                f"the password of {user} is stored in the old form (scrypt), which cannot "
                f"log in without sending it: set it again with s7graph users passwd {user}",
            )
        verifier = known.verifier if known is not None else None
        exchange = ServerLogin(user, verifier or fake_verifier(self._secret, user))
        try:
            server_first = exchange.first(scram)
        except LoginError as exc:
            return LoginResult(False, str(exc))
        login_id = secrets.token_urlsafe(16)
        now = self._clock()
        with self._lock:
            self._forget_pending(now)
            if self._pending_from[source] >= PENDING_PER_SOURCE:
                return LoginResult(
                    False,
                    f"{PENDING_PER_SOURCE} logins from here are unfinished: finish one, or "
                    f"log in again after {LOGIN_WINDOW_S:.0f} s",
                )
            self._pending[login_id] = _Pending(user, source, exchange, now)
            self._pending_from[source] += 1
        return LoginResult(False, login_id=login_id, scram=server_first)

    def prove(self, login_id: str, user: str, scram: str, *, source: str = "") -> LoginResult:
        """The second step from ``source``: ``scram`` is the client-final message (the
        proof) of the login ``login_id``; the answer a token and the server-final message,
        or a refusal (a wrong proof counts against ``source``)."""
        with self._lock:
            self._forget_pending(self._clock())
            pending = self._pending.pop(login_id, None)
            if pending is not None:
                self._done_pending(pending.source)
        if pending is None or (pending.user, pending.source) != (user, source):
            return LoginResult(False, "no such login (unfinished after 10 s?): log in again")
        refused = self._refused(user, source)
        if refused is not None:
            return refused
        try:
            server_final, key = pending.exchange.final(scram)
        except LoginError:
            return self._failed(user, source)
        known = self._user(user)
        if known is None or known.legacy:  # a fake challenge, or removed meanwhile
            return self._failed(user, source)
        self.lockout.succeeded(user, source)
        return dataclasses.replace(self._open(user, known.role, key), scram=server_final)

    def _refused(self, user: str, source: str) -> LoginResult | None:
        """Why ``user`` may not try from ``source`` now (None: they may)."""
        problem = name_problem(user)
        if problem:
            return LoginResult(False, problem)
        left = self.lockout.locked_for(user, source)
        if left > 0:
            return LoginResult(False, f"{user} is locked out for {math.ceil(left)} s more here")
        return None

    def _open(self, user: str, role: str, key: bytes, *, verified: bool = True) -> LoginResult:
        token = secrets.token_urlsafe(32)
        now = self._clock()
        with self._lock:
            self._evict(now)
            self._sessions[_digest(token)] = _Session(user, now + self.ttl_s, role, key)
        expires_ms = int((self._wall() + self.ttl_s) * 1000)
        return LoginResult(True, "", token, role, expires_ms, verified)

    def _failed(self, user: str, source: str) -> LoginResult:
        length = self.lockout.failed(user, source)
        if length:
            return LoginResult(False, f"{_WRONG}; {user} is locked out for {length:.0f} s here")
        return LoginResult(False, _WRONG)

    def _forget_pending(self, now: float) -> None:
        """Drop logins older than 10 s, and the oldest beyond 256 (under the lock)."""
        pending = self._pending
        while pending:
            oldest = next(iter(pending))
            if pending[oldest].started > now - LOGIN_WINDOW_S and len(pending) < MAX_PENDING:
                break
            self._done_pending(pending.pop(oldest).source)

    def _done_pending(self, source: str) -> None:
        """One unfinished login of ``source`` less (under the lock)."""
        left = self._pending_from[source] - 1
        if left > 0:
            self._pending_from[source] = left
        else:
            del self._pending_from[source]

    def logout(self, token: str) -> bool:
        """Revoke ``token``; whether it was a live one."""
        with self._lock:
            return self._sessions.pop(_digest(token), None) is not None

    def _evict(self, now: float) -> None:
        if len(self._sessions) < _MAX_SESSIONS:
            return
        for key in [k for k, s in self._sessions.items() if s.expires <= now]:
            del self._sessions[key]
        while len(self._sessions) >= _MAX_SESSIONS:  # the oldest go first
            del self._sessions[next(iter(self._sessions))]

    # ------------------------------------------------------------ commands

    def identify(self, user: str, token: str) -> Identity | str:
        """Who holds ``token`` (it must be ``user``'s), or why it is refused."""
        if not token:
            return "not logged in: log in first (no token)"
        if len(token) > MAX_TOKEN or not token.isascii():
            return "invalid token"
        now = self._clock()
        with self._lock:
            session = self._sessions.get(_digest(token))
            if session is None:
                return "invalid token: log in again"
            if session.expires <= now:
                del self._sessions[_digest(token)]
                return "token expired: log in again"
            if session.user != user:
                return "the token belongs to another user"
            if self.users_file is None:
                return Identity(user, session.role, verified=False)
            self._reload()
            known = self._users.get(user)
            if known is None:
                del self._sessions[_digest(token)]
                return f"user {user} no longer exists"
            return Identity(user, known.role)

    def verify(self, token: str, mac: str, message: bytes, *, seq: int | None = None) -> str:
        """Why a message of ``token``'s session is refused ("": it is not): ``mac`` must be
        the session key's HMAC of ``message`` and ``seq`` (if given) new to the session —
        then it counts as seen. Demo: nothing is signed, nothing refused here."""
        if self.users_file is None:
            return ""
        with self._lock:
            session = self._sessions.get(_digest(token)) if token.isascii() else None
            if session is None:
                return "invalid token: log in again"
            good = bool(session.key) and mac.isascii() and len(mac) == 64
            if not good or not hmac.compare_digest(sign(session.key, message), mac):
                return NOT_SIGNED
            if seq is not None and not session.fresh(seq):
                return f"replayed or out of order: seq {seq}"
        return ""


def password_login(
    auth: Authenticator, user: str, password: str = "", *, source: str = ""
) -> tuple[LoginResult, Signer | None]:
    """Log ``user`` in at ``auth`` in this process, as a client would over the bus (the
    whole SCRAM exchange: for tests and tools beside the CPU); the answer and, once
    logged in, the session's signer."""

    def ask(scram: str, login_id: str) -> LoginResult:
        if login_id:
            return auth.prove(login_id, user, scram, source=source)
        return auth.login(user, scram, source=source)

    problem = name_problem(user)
    if problem:
        return LoginResult(False, problem), None
    answer, signer = log_in(user, password, ask)
    if isinstance(answer, str):
        return LoginResult(False, answer), None
    return answer, signer
