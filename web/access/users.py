"""The users file: names, roles and SCRAM-SHA-256 verifiers, JSON, mode 0600.

``{"version": 2, "users": {"alice": {"role": "operator", "password":
"SCRAM-SHA-256$100000:<salt>$<StoredKey>:<ServerKey>"}}}`` — the verifier in PostgreSQL's
form (``web.access.scram``): enough to check a login and to prove the CPU to the client,
never enough to log in. A version-1 file (salted scrypt hashes, ``scrypt$n$r$p$salt$hash``)
still loads, unchanged: its users keep their roles but cannot log in — a scrypt check
needs the password on the wire — until ``s7graph users passwd NAME`` sets the password
again (in the new form; the file is then version 2).

A name is 1-32 of ``A-Z a-z 0-9 . _ -`` (safe in a log line, a key expression and a
page), the whole string: no whitespace around it, no control character in it (a name
``olga\\n`` is refused, not read as ``olga``). The name ``program`` is reserved for the
FB's own acknowledgement pins. The file is written atomically (a temporary file in the
same folder, renamed) with mode 0600 and refused when others may read it, as ssh refuses a
readable key.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import secrets
import stat
from dataclasses import dataclass
from pathlib import Path
from typing import Final

from s7graph.web.access.roles import ROLES
from s7graph.web.access.scram import (
    DEFAULT_ITERATIONS,
    MAX_PASSWORD,
    LoginError,
    Verifier,
    make_verifier,
    password_matches,
)

__all__ = [
    "LEGACY_PREFIX",
    "RESERVED_NAMES",
    "USER_PATTERN",
    "User",
    "UsersError",
    "UsersFile",
    "check_name",
    "hash_password",
    "name_problem",
    "valid_user_name",
    "verify_password",
]

USER_PATTERN: Final = r"[A-Za-z0-9._-]{1,32}"  # the whole name (``re.fullmatch``)
_USER_RE: Final = re.compile(USER_PATTERN)
NAME_RULE: Final = "use 1-32 of A-Z a-z 0-9 . _ -"
RESERVED_NAMES: Final = frozenset({"program"})
LEGACY_PREFIX: Final = "scrypt$"
MIN_PASSWORD: Final = 8
VERSION: Final = 2
_READS: Final = (1, 2)


class UsersError(ValueError):
    """A bad name, role, password or users file; the text says which and why."""


def valid_user_name(name: object) -> bool:
    """Whether ``name`` follows the name rule, as a whole (reserved names included)."""
    return isinstance(name, str) and _USER_RE.fullmatch(name) is not None


def name_problem(name: object) -> str:
    """Why ``name`` may not be a user's name ("": it may), in one line."""
    if not isinstance(name, str):
        return "invalid user name: not text"
    shown = repr(name[:32]) + ("…" if len(name) > 32 else "")  # control characters escaped
    if any(not c.isprintable() for c in name):
        return f"invalid user name {shown}: it holds a control character; {NAME_RULE}"
    if name != name.strip():
        return f"invalid user name {shown}: whitespace around it; {NAME_RULE}"
    if not valid_user_name(name):
        return f"invalid user name {shown}: {NAME_RULE}"
    if name in RESERVED_NAMES:
        return f"the name {name!r} is reserved (the FB's own acknowledgement)"
    return ""


def check_name(name: str) -> str:
    """``name`` if it may be a user's name, else :class:`UsersError` saying why."""
    problem = name_problem(name)
    if problem:
        raise UsersError(problem)
    return name


def hash_password(password: str, *, iterations: int = DEFAULT_ITERATIONS) -> str:
    """The SCRAM-SHA-256 verifier of ``password`` in PostgreSQL's form (a fresh salt)."""
    if not MIN_PASSWORD <= len(password) <= MAX_PASSWORD:
        raise UsersError(f"a password has {MIN_PASSWORD} to {MAX_PASSWORD} characters")
    try:
        return make_verifier(password, iterations=iterations).text
    except LoginError as exc:
        raise UsersError(str(exc)) from None


def verify_password(password: str, stored: str) -> bool:
    """Whether ``password`` gives the verifier ``stored`` (a local check, constant-time;
    an old scrypt hash or a malformed entry: never)."""
    try:
        verifier = Verifier.parse(stored)
    except ValueError:
        return False
    return len(password) <= MAX_PASSWORD and password_matches(password, verifier)


@dataclass(frozen=True, slots=True)
class User:
    name: str
    role: str
    password: str  # the verifier (or a version-1 scrypt hash), never the password

    @property
    def legacy(self) -> bool:
        """A version-1 scrypt hash: this user cannot log in until ``users passwd``."""
        return self.password.startswith(LEGACY_PREFIX)

    @property
    def verifier(self) -> Verifier | None:
        """The SCRAM verifier (None: a legacy hash)."""
        return None if self.legacy else Verifier.parse(self.password)


class UsersFile:
    """The users of one plant, read from and written to ``path``."""

    def __init__(self, path: Path | str) -> None:
        self.path = Path(path)

    # ------------------------------------------------------------ reading

    def load(self) -> dict[str, User]:
        """Every user; an absent file is no users. A file others may read is refused."""
        try:
            info = self.path.stat()
        except FileNotFoundError:
            return {}
        if info.st_mode & (stat.S_IRWXG | stat.S_IRWXO):
            raise UsersError(
                f"{self.path}: others may read it (mode {stat.S_IMODE(info.st_mode):o}); "
                f"run chmod 600 {self.path}"
            )
        try:
            data = json.loads(self.path.read_text(encoding="utf-8"))
        except OSError as exc:
            raise UsersError(f"{self.path}: cannot read it: {exc.strerror or exc}") from None
        except RecursionError:
            raise UsersError(f"{self.path}: not a users file (nested too deep)") from None
        except ValueError as exc:  # not UTF-8, not JSON
            raise UsersError(f"{self.path}: not a users file ({exc})") from None
        raw = data.get("users") if isinstance(data, dict) else None
        if not isinstance(raw, dict) or data.get("version") not in _READS:
            why = "no table of users" if not isinstance(raw, dict) else "unknown version"
            raise UsersError(f"{self.path}: not a users file ({why})")
        try:
            return {name: _entry(name, entry) for name, entry in raw.items()}
        except (ValueError, KeyError, TypeError) as exc:
            raise UsersError(f"{self.path}: not a users file ({exc})") from None

    def mtime_ns(self) -> int | None:
        """When the file last changed (None: no file): a reader reloads on a change."""
        try:
            return self.path.stat().st_mtime_ns
        except FileNotFoundError:
            return None

    # ------------------------------------------------------------ changing

    def add(
        self, name: str, role: str, password: str, *, iterations: int = DEFAULT_ITERATIONS
    ) -> User:
        """Add ``name`` with ``role``; ``iterations`` of PBKDF2 (fewer only for tests)."""
        users = self.load()
        check_name(name)
        if name in users:
            raise UsersError(f"user {name!r} exists (users passwd changes the password)")
        user = User(name, _check_role(role), hash_password(password, iterations=iterations))
        users[name] = user
        self._save(users)
        return user

    def remove(self, name: str) -> None:
        users = self.load()
        if users.pop(name, None) is None:
            raise UsersError(f"no user {name!r} in {self.path}")
        self._save(users)

    def passwd(self, name: str, password: str, *, iterations: int = DEFAULT_ITERATIONS) -> None:
        """Set ``name``'s password (in the SCRAM form, whatever form it had)."""
        users = self.load()
        user = users.get(name)
        if user is None:
            raise UsersError(f"no user {name!r} in {self.path}")
        users[name] = User(name, user.role, hash_password(password, iterations=iterations))
        self._save(users)

    def _save(self, users: dict[str, User]) -> None:
        data = {
            "version": VERSION,
            "users": {u.name: {"role": u.role, "password": u.password} for u in users.values()},
        }
        text = json.dumps(data, indent=2, sort_keys=True) + "\n"
        self.path.parent.mkdir(parents=True, exist_ok=True)
        tmp = self.path.with_name(f".{self.path.name}.{secrets.token_hex(4)}.tmp")
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
        try:
            with os.fdopen(fd, "w", encoding="utf-8") as f:
                f.write(text)
                f.flush()
                os.fsync(f.fileno())
            os.chmod(tmp, 0o600)
            os.replace(tmp, self.path)
        except BaseException:
            with contextlib.suppress(OSError):
                os.unlink(tmp)
            raise


def _entry(name: str, entry: object) -> User:
    """One user of the file: a valid name and role, a verifier or a legacy scrypt hash."""
    check_name(name)
    if not isinstance(entry, dict):
        raise ValueError(f"bad entry for {name!r}")
    role, password = entry["role"], entry["password"]
    if role not in ROLES or not isinstance(password, str):
        raise ValueError(f"bad entry for {name!r}")
    user = User(name, role, password)
    if not user.legacy:
        try:
            Verifier.parse(password)
        except ValueError as exc:
            raise ValueError(f"bad password entry for {name!r}: {exc}") from None
    return user


def _check_role(role: str) -> str:
    if role not in ROLES:
        raise UsersError(f"unknown role {role!r}; one of {', '.join(ROLES)}")
    return role
