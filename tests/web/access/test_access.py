"""Users, roles and logins without a network: the users file (SCRAM verifiers, 0600, the
name rule), the one role table (and that docs/security.md and docs/bus.md show it as it is),
tokens, expiry, logout and the lockout after five wrong passwords."""

from __future__ import annotations

import json
import os
import stat
import subprocess
import sys
from pathlib import Path

import pytest

from s7graph.web.access.audit import AuditStore, Facts, read_audit
from s7graph.web.access.login import Authenticator, LoginResult, password_login
from s7graph.web.access.roles import COMMANDS, ROLES, allowed, ops_of, role_table_markdown
from s7graph.web.access.scram import MIN_ITERATIONS
from s7graph.web.access.users import UsersError, UsersFile, check_name, verify_password
from s7graph.web.bus.protocol import OPS
from tests.paths import ROOT

PASSWORD = "correct horse"
pytestmark = pytest.mark.timeout(60)


class Clock:
    def __init__(self) -> None:
        self.t = 1000.0

    def __call__(self) -> float:
        return self.t


@pytest.fixture
def users(tmp_path: Path) -> UsersFile:
    f = UsersFile(tmp_path / "users.json")
    f.add("olga", "operator", PASSWORD, iterations=MIN_ITERATIONS)
    f.add("vic", "viewer", PASSWORD, iterations=MIN_ITERATIONS)
    f.add("eng", "engineer", PASSWORD, iterations=MIN_ITERATIONS)
    return f


def test_users_file_holds_salted_scram_verifiers_with_mode_0600(users: UsersFile) -> None:
    assert stat.S_IMODE(users.path.stat().st_mode) == 0o600
    data = json.loads(users.path.read_text())
    olga = data["users"]["olga"]
    assert olga["role"] == "operator" and olga["password"].startswith("SCRAM-SHA-256$4096:")
    assert data["version"] == 2
    assert PASSWORD not in users.path.read_text()
    assert olga["password"] != data["users"]["vic"]["password"]  # salted
    assert verify_password(PASSWORD, olga["password"])
    assert not verify_password("wrong one", olga["password"])
    users.passwd("olga", "another secret")
    assert verify_password("another secret", users.load()["olga"].password)
    users.remove("vic")
    assert sorted(users.load()) == ["eng", "olga"]


def test_a_users_file_others_can_read_is_refused(users: UsersFile) -> None:
    os.chmod(users.path, 0o644)
    with pytest.raises(UsersError, match="chmod 600"):
        users.load()


@pytest.mark.parametrize(
    "name", ["", "a" * 33, "program", "bob smith", "bob\r\nroot", "\x1b[31mred", "ü", "../x"]
)
def test_hostile_or_reserved_names_are_refused(users: UsersFile, name: str) -> None:
    with pytest.raises(UsersError):
        check_name(name)
    with pytest.raises(UsersError):
        users.add(name, "operator", PASSWORD)
    assert not Authenticator(users).login(name, PASSWORD).ok
    assert not Authenticator(None).login(name).ok  # not even claimed in the demo


def test_the_role_table_is_the_one_the_protocol_and_the_docs_show() -> None:
    assert set(OPS) == {c.op for c in COMMANDS}
    assert ROLES == ("viewer", "operator", "engineer")
    assert ops_of("viewer") == ()
    assert {"ack", "ack_msg", "mode", "init", "off", "halt", "t_push"} <= set(ops_of("operator"))
    assert not allowed("operator", "en_il") and allowed("engineer", "en_il")
    assert allowed("engineer", "download") and not allowed("nobody", "ack")
    table = role_table_markdown()
    for doc in ("docs/security.md", "docs/bus.md"):
        assert table in (ROOT / doc).read_text(encoding="utf-8"), f"{doc}: role table differs"


def test_login_gives_a_token_that_identifies_its_user_until_logout_or_expiry(
    users: UsersFile,
) -> None:
    clock = Clock()
    auth = Authenticator(users, clock=clock, ttl_s=60)
    result, _ = password_login(auth, "olga", PASSWORD)
    assert result.ok and result.role == "operator" and len(result.token) >= 40
    who = auth.identify("olga", result.token)
    assert not isinstance(who, str) and (who.label, who.role) == ("olga", "operator")
    assert auth.identify("eng", result.token) == "the token belongs to another user"
    assert auth.identify("olga", "forged-token") == "invalid token: log in again"
    assert auth.identify("olga", "") == "not logged in: log in first (no token)"
    assert result.token not in repr(vars(auth))  # only digests are kept
    clock.t += 61
    assert auth.identify("olga", result.token) == "token expired: log in again"
    again, _ = password_login(auth, "olga", PASSWORD)
    assert auth.logout(again.token) and auth.identify("olga", again.token) != "ok"
    assert isinstance(auth.identify("olga", again.token), str)


def test_five_wrong_passwords_lock_that_source_out_for_a_minute(users: UsersFile) -> None:
    clock = Clock()
    auth = Authenticator(users, clock=clock)

    def login(user: str, password: str) -> LoginResult:
        return password_login(auth, user, password)[0]

    for _ in range(4):
        assert login("olga", "wrong!!!").reason == "wrong user name or password"
    fifth = login("olga", "wrong!!!")
    assert not fifth.ok and "locked out for 60 s" in fifth.reason
    locked = login("olga", PASSWORD)  # even the right password
    assert not locked.ok and "locked out" in locked.reason
    assert login("eng", PASSWORD).ok  # only that user
    clock.t += 61
    assert login("olga", PASSWORD).ok


def test_a_removed_user_or_changed_role_acts_at_once(users: UsersFile) -> None:
    auth = Authenticator(users)
    token = password_login(auth, "olga", PASSWORD)[0].token
    data = json.loads(users.path.read_text())
    data["users"]["olga"]["role"] = "viewer"
    users._save(
        {n: type(u)(n, data["users"][n]["role"], u.password) for n, u in users.load().items()}
    )
    who = auth.identify("olga", token)
    assert not isinstance(who, str) and who.role == "viewer"
    users.remove("olga")
    assert auth.identify("olga", token) == "user olga no longer exists"


def test_demo_logins_are_claimed_names_recorded_unverified() -> None:
    auth = Authenticator(None)
    result = auth.login("alice")
    assert result.ok and not result.verified
    who = auth.identify("alice", result.token)
    assert not isinstance(who, str) and who.label == "alice (unverified)"


def test_audit_store_migrates_an_old_state_file(tmp_path: Path) -> None:
    from s7graph.engine.persistence import StateStore

    old = StateStore(tmp_path / "state.sqlite")
    old.log_audit(7, "ann", "ack", "FB1 S3")  # a row from before the new columns
    store = AuditStore(tmp_path / "state.sqlite")
    store.record(
        9, Facts("bob", "operator", "shell", "mode", "FB1", {"mode": "MAN"}, False, "role viewer")
    )
    rows = read_audit(tmp_path / "state.sqlite")
    assert [(r.user, r.op, r.outcome) for r in rows] == [
        ("ann", "ack", "applied"),
        ("bob", "mode", "refused"),
    ]
    assert old.audit()[0]["user"] == "ann"  # the old reader still works
    store.close()
    old.close()


def test_users_cli_adds_lists_changes_and_removes(tmp_path: Path) -> None:
    path = tmp_path / "u.json"

    def run(*args: str, stdin: str = "") -> subprocess.CompletedProcess[str]:
        cmd = [sys.executable, "-m", "s7graph", "users", *args, "--file", str(path)]
        return subprocess.run(cmd, input=stdin, capture_output=True, text=True, timeout=60)

    added = run("add", "olga", "--role", "operator", "--password-stdin", stdin=PASSWORD + "\n")
    assert added.returncode == 0, added.stderr
    assert PASSWORD not in added.stdout + added.stderr
    bad = run("add", "bad name", "--role", "operator", "--password-stdin", stdin=PASSWORD)
    assert bad.returncode == 2 and "invalid user name" in bad.stderr
    assert run("add", "x", "--role", "admin", "--password-stdin", stdin=PASSWORD).returncode == 2
    assert run("list").stdout == "olga\toperator\n"
    assert run("passwd", "olga", "--password-stdin", stdin="new secret!\n").returncode == 0
    assert verify_password("new secret!", UsersFile(path).load()["olga"].password)
    assert run("remove", "olga").returncode == 0 and run("list").stdout == ""
    assert stat.S_IMODE(path.stat().st_mode) == 0o600


def test_every_message_example_in_docs_bus_md_decodes() -> None:
    """docs/bus.md shows each message as JSON: each example is a valid message of its kind."""
    import re

    from s7graph.web.bus import protocol

    text = (ROOT / "docs" / "bus.md").read_text(encoding="utf-8")
    found = re.findall(r"#### `(\w+)[^`]*`\n```json\n(.*?)\n```", text, re.S)
    kinds = {name for name, _ in found}
    assert {
        "Command",
        "CommandReply",
        "LoginRequest",
        "LoginReply",
        "AuditEntry",
        "AlarmHistory",
        "StepStateUpdate",
        "ChartLayout",
        "CpuStatus",
    } <= kinds
    for name, body in found:
        protocol.decode(body, getattr(protocol, name))
