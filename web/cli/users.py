"""``s7graph users add|list|remove|passwd``: the users file of a plant.

Passwords come from a prompt (asked twice) or, with ``--password-stdin``, from the first
line of standard input; they are never arguments (a command line is visible to every
user of the machine) and never printed.
"""

from __future__ import annotations

import getpass
import sys
from pathlib import Path

from s7graph.web.access.users import UsersError, UsersFile

__all__ = ["users_add", "users_list", "users_passwd", "users_remove"]


def _fail(message: str) -> int:
    print(f"s7graph: error: {message}", file=sys.stderr)
    return 2


def _password(stdin: bool) -> str:
    if stdin:
        return sys.stdin.readline().rstrip("\r\n")
    first = getpass.getpass("Password: ")
    if getpass.getpass("Again: ") != first:
        raise UsersError("the two passwords differ")
    return first


def _not_a_users_file(path: Path, *, made: bool = False) -> str:
    """Why ``path`` cannot be the users file (a folder; none there, unless ``made`` — ``add``
    makes it), as ``s7graph run --users`` says it, or ""."""
    if path.is_dir():
        return f"{path}: a folder, not a users file; give --file the path of a file"
    if not made and not path.exists():
        return f"{path}: no such users file (s7graph users add NAME --role ROLE --file {path})"
    return ""


def users_add(path: Path, name: str, role: str, *, password_stdin: bool) -> int:
    if problem := _not_a_users_file(path, made=True):
        return _fail(problem)
    try:
        user = UsersFile(path).add(name, role, _password(password_stdin))
    except UsersError as exc:
        return _fail(str(exc))
    print(f"s7graph: added {user.name} ({user.role}) to {path}")
    return 0


def users_list(path: Path) -> int:
    if problem := _not_a_users_file(path):
        return _fail(problem)
    try:
        users = UsersFile(path).load()
    except UsersError as exc:
        return _fail(str(exc))
    for user in sorted(users.values(), key=lambda u: u.name):
        old = f"\tcannot log in: s7graph users passwd {user.name}" if user.legacy else ""
        print(f"{user.name}\t{user.role}{old}")
    return 0


def users_remove(path: Path, name: str) -> int:
    if problem := _not_a_users_file(path):
        return _fail(problem)
    try:
        UsersFile(path).remove(name)
    except UsersError as exc:
        return _fail(str(exc))
    print(f"s7graph: removed {name} from {path}")
    return 0


def users_passwd(path: Path, name: str, *, password_stdin: bool) -> int:
    if problem := _not_a_users_file(path):
        return _fail(problem)
    try:
        UsersFile(path).passwd(name, _password(password_stdin))
    except UsersError as exc:
        return _fail(str(exc))
    print(f"s7graph: changed the password of {name}")
    return 0
