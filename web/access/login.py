"""Logins on the CPU side: user + password in, a random expiring token out.

:class:`Authenticator` answers the bus's ``login``/``logout`` and tells the command gate who
sent a command (:meth:`Authenticator.identify`). Tokens are 256-bit random strings, kept
only as their SHA-256 (a dump of this object shows no usable token), valid for ``ttl_s``
(8 h) until logout; five wrong passwords in a row lock that name out for a minute. The
users file is read again whenever it changes, so a removed user's tokens stop working and
a changed role acts at once.

Without a users file (the demo) any valid name logs in without a password as an
*unverified* engineer: ``alice (unverified)`` in the audit and the alarm log.

A users file that others may read (group or world bits, as ``UsersFile.load`` refuses at
start) is noticed at the next login or command, ``chmod`` included — the mode is checked
with every look at the mtime, and a chmod changes no mtime: logins are refused (``users
file is readable by others: chmod 600 FILE``) until it is fixed, sessions already open go
on, and ``on_users_file`` is called once when it happens and once when it is fixed.
"""

from __future__ import annotations

import hashlib
import secrets
import stat
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Final

from s7graph.web.access.users import (
    RESERVED_NAMES,
    User,
    UsersError,
    UsersFile,
    valid_user_name,
    verify_password,
)

__all__ = ["DEMO_ROLE", "Authenticator", "Identity", "LoginResult"]

DEMO_ROLE: Final = "engineer"
TOKEN_TTL_S: Final = 8 * 3600.0
MAX_FAILURES: Final = 5
LOCKOUT_S: Final = 60.0
MAX_TOKEN: Final = 64
_MAX_SESSIONS: Final = 4096
_MAX_TRACKED: Final = 4096
_WRONG: Final = "wrong user name or password"


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
    ok: bool
    reason: str = ""
    token: str = ""
    role: str = ""
    expires_ms: int = 0  # wall clock, ms since the epoch
    verified: bool = True


@dataclass(slots=True)
class _Session:
    user: str
    expires: float  # monotonic
    role: str  # the demo's role; with a users file the file's current role wins


def _digest(token: str) -> str:
    return hashlib.sha256(token.encode()).hexdigest()


class Authenticator:
    """Logins, tokens and lockouts of one CPU; thread-safe."""

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
        max_failures: int = MAX_FAILURES,
        clock: Callable[[], float] = time.monotonic,
        wall: Callable[[], float] = time.time,
    ) -> None:
        self.users_file = users
        self.ttl_s = ttl_s
        self.lockout_s = lockout_s
        self.max_failures = max_failures
        self._clock = clock
        self._wall = wall
        self._lock = threading.Lock()
        self._sessions: dict[str, _Session] = {}
        self._failures: dict[str, int] = {}
        self._locked_until: dict[str, float] = {}
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

    def login(self, user: str, password: str = "") -> LoginResult:
        """A token for ``user`` if the password is right (demo: any valid name)."""
        if not valid_user_name(user) or user in RESERVED_NAMES:
            return LoginResult(False, "invalid user name: use 1-32 of A-Z a-z 0-9 . _ -")
        now = self._clock()
        with self._lock:
            until = self._locked_until.get(user, 0.0)
            if until > now:
                return LoginResult(False, f"{user} is locked out for {until - now:.0f} s more")
            if user in self._locked_until:
                del self._locked_until[user]
                self._failures.pop(user, None)
            if self.users_file is not None:
                self._reload()
                if self.exposed:
                    return LoginResult(False, self.exposed)
                known = self._users.get(user)
                stored = known.password if known is not None else None
            else:
                known, stored = None, None
        if self.users_file is not None:
            # scrypt outside the lock (it releases the GIL): other logins are not held up
            ok = verify_password(password, stored) if stored else _burn(password)
            if not ok or known is None:
                return self._failed(user)
            role, verified = known.role, True
        else:
            role, verified = DEMO_ROLE, False
        token = secrets.token_urlsafe(32)
        with self._lock:
            self._failures.pop(user, None)
            self._evict(now)
            self._sessions[_digest(token)] = _Session(user, now + self.ttl_s, role)
        expires_ms = int((self._wall() + self.ttl_s) * 1000)
        return LoginResult(True, "", token, role, expires_ms, verified)

    def _failed(self, user: str) -> LoginResult:
        with self._lock:
            if len(self._failures) > _MAX_TRACKED:
                self._failures.clear()
            count = self._failures.get(user, 0) + 1
            self._failures[user] = count
            if count >= self.max_failures:
                self._locked_until[user] = self._clock() + self.lockout_s
                return LoginResult(
                    False,
                    f"{_WRONG}; {count} failures: {user} is locked out for {self.lockout_s:.0f} s",
                )
        return LoginResult(False, _WRONG)

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
        """Who sent a command with ``user`` and ``token``, or why it is refused."""
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


def _burn(password: str) -> bool:
    """As long as checking a real password, so an unknown name answers no faster."""
    verify_password(password, "scrypt$16384$8$1$AAAAAAAAAAAAAAAAAAAAAA==$" + "A" * 43 + "=")
    return False
