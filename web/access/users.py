"""The users file: names, roles and salted scrypt password hashes, JSON, mode 0600.

``{"version": 1, "users": {"alice": {"role": "operator", "password": "scrypt$…"}}}``, the
hash as ``scrypt$n$r$p$<salt>$<hash>`` (base64).

A name is 1-32 of ``A-Z a-z 0-9 . _ -`` (safe in a log line, a key expression and a
page); the name ``program`` is reserved for the FB's own acknowledgement pins. The file is
written atomically (a temporary file in the same folder, renamed) with mode 0600 and
refused when others may read it, as ssh refuses a readable key. Passwords are hashed with
``hashlib.scrypt`` (n=2^14, r=8, p=1, 16-byte salt) and compared in constant time.
"""

from __future__ import annotations

import base64
import contextlib
import hashlib
import hmac
import json
import os
import re
import secrets
import stat
from dataclasses import dataclass
from pathlib import Path
from typing import Final

from s7graph.web.access.roles import ROLES

__all__ = [
    "RESERVED_NAMES",
    "USER_PATTERN",
    "User",
    "UsersError",
    "UsersFile",
    "check_name",
    "hash_password",
    "valid_user_name",
    "verify_password",
]

USER_PATTERN: Final = r"^[A-Za-z0-9._-]{1,32}$"
_USER_RE: Final = re.compile(USER_PATTERN)
RESERVED_NAMES: Final = frozenset({"program"})
_N, _R, _P = 2**14, 8, 1
MIN_PASSWORD: Final = 8
MAX_PASSWORD: Final = 1024
VERSION: Final = 1


class UsersError(ValueError):
    """A bad name, role, password or users file; the text says which and why."""


def valid_user_name(name: object) -> bool:
    """Whether ``name`` follows the name rule (reserved names included)."""
    return isinstance(name, str) and bool(_USER_RE.match(name))


def check_name(name: str) -> str:
    """``name`` if it may be a user's name, else :class:`UsersError` saying why."""
    if not valid_user_name(name):
        shown = ascii(name)[:40]
        raise UsersError(f"invalid user name {shown}: use 1-32 of A-Z a-z 0-9 . _ -")
    if name in RESERVED_NAMES:
        raise UsersError(f"the name {name!r} is reserved (the FB's own acknowledgement)")
    return name


def _b64(data: bytes) -> str:
    return base64.b64encode(data).decode()


def hash_password(password: str, *, salt: bytes | None = None) -> str:
    """A salted scrypt hash of ``password`` as ``scrypt$n$r$p$salt$hash``."""
    if not MIN_PASSWORD <= len(password) <= MAX_PASSWORD:
        raise UsersError(f"a password has {MIN_PASSWORD} to {MAX_PASSWORD} characters")
    salt = salt or secrets.token_bytes(16)
    digest = hashlib.scrypt(password.encode(), salt=salt, n=_N, r=_R, p=_P, dklen=32)
    return f"scrypt${_N}${_R}${_P}${_b64(salt)}${_b64(digest)}"


def verify_password(password: str, stored: str) -> bool:
    """Whether ``password`` matches ``stored`` (constant-time; a malformed hash: never)."""
    try:
        scheme, n, r, p, salt, digest = stored.split("$")
        if scheme != "scrypt" or len(password) > MAX_PASSWORD:
            return False
        want = base64.b64decode(digest, validate=True)
        got = hashlib.scrypt(
            password.encode(),
            salt=base64.b64decode(salt, validate=True),
            n=int(n),
            r=int(r),
            p=int(p),
            dklen=len(want),
            maxmem=64 * 1024 * 1024,
        )
    except (ValueError, TypeError):
        return False
    return hmac.compare_digest(got, want)


@dataclass(frozen=True, slots=True)
class User:
    name: str
    role: str
    password: str  # the hash, never the password


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
            raw = data["users"]
            if data.get("version") != VERSION or not isinstance(raw, dict):
                raise ValueError("unknown version")
            users = {}
            for name, entry in raw.items():
                check_name(name)
                role, password = entry["role"], entry["password"]
                if role not in ROLES or not isinstance(password, str):
                    raise ValueError(f"bad entry for {name!r}")
                users[name] = User(name, role, password)
        except UsersError:
            raise
        except (OSError, ValueError, KeyError, TypeError) as exc:
            raise UsersError(f"{self.path}: not a users file ({exc})") from None
        return users

    def mtime_ns(self) -> int | None:
        """When the file last changed (None: no file): a reader reloads on a change."""
        try:
            return self.path.stat().st_mtime_ns
        except FileNotFoundError:
            return None

    # ------------------------------------------------------------ changing

    def add(self, name: str, role: str, password: str) -> User:
        users = self.load()
        check_name(name)
        if name in users:
            raise UsersError(f"user {name!r} exists (users passwd changes the password)")
        user = User(name, _check_role(role), hash_password(password))
        users[name] = user
        self._save(users)
        return user

    def remove(self, name: str) -> None:
        users = self.load()
        if users.pop(name, None) is None:
            raise UsersError(f"no user {name!r} in {self.path}")
        self._save(users)

    def passwd(self, name: str, password: str) -> None:
        users = self.load()
        user = users.get(name)
        if user is None:
            raise UsersError(f"no user {name!r} in {self.path}")
        users[name] = User(name, user.role, hash_password(password))
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


def _check_role(role: str) -> str:
    if role not in ROLES:
        raise UsersError(f"unknown role {role!r}; one of {', '.join(ROLES)}")
    return role
