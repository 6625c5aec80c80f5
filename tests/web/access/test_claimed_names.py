"""An audit row names as its user only an author the CPU proved (web/bus/gate.py
``unproven_author``, docs/security.md, "Users, roles, logins and the audit"): a refusal of a
sender it did not authenticate — a forged token, a failed login, a logout of no session —
has the user ``(unauthenticated)`` and the name the sender gave only as ``claimed``, so a
listener who sends in a victim's name makes no row appear under it. ``s7graph audit``, the
bus's ``AuditEntry`` say so too; a state file from before reads as ever."""

from __future__ import annotations

import sqlite3
from pathlib import Path

import pytest

from s7graph.engine.persistence import StateStore
from s7graph.web.access.audit import UNAUTHENTICATED, AuditStore, read_audit
from s7graph.web.access.login import Authenticator
from s7graph.web.access.scram import MIN_ITERATIONS
from s7graph.web.access.users import UsersFile
from s7graph.web.bus.gate import Gate
from s7graph.web.bus.protocol import AuditEntry, Command, LoginRequest
from s7graph.web.cli.audit import audit_command
from tests.web.access.gate_login import gate_login

PASSWORD = "correct horse"


@pytest.fixture
def gate(tmp_path: Path) -> Gate:
    users = UsersFile(tmp_path / "users.json")
    users.add("olga", "operator", PASSWORD, iterations=MIN_ITERATIONS)
    users.add("vic", "viewer", PASSWORD, iterations=MIN_ITERATIONS)
    return Gate(Authenticator(users), AuditStore(tmp_path / "s.sqlite"), flush_s=None)


def _applied(command: Command) -> tuple[bool, str]:
    return True, ""


def test_a_refusal_of_an_unproven_sender_shows_the_name_it_gave_only_as_claimed(
    gate: Gate, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    published: list[AuditEntry] = []
    gate.on_audit = published.append
    forged = Command(op="init", fb="FILL", user="olga", token="forged", origin="10.0.0.66")
    assert gate.apply(forged, _applied) == (False, "invalid token: log in again")
    gate_login(gate, "olga", "not her password", origin="10.0.0.66")
    gate.login(LoginRequest(op="logout", user="olga", token="nosuch", origin="10.0.0.66"))
    vic = gate_login(gate, "vic", PASSWORD)[1]  # a proven author's refusal: his name
    assert vic is not None
    mode = vic.sign(
        Command(op="mode", fb="FILL", user="vic", token=vic.token, args={"mode": "MAN"})
    )
    assert not gate.apply(mode, _applied)[0]
    gate.flush()
    rows = read_audit(tmp_path / "s.sqlite")
    assert [(r.user, r.claimed, r.op, r.outcome) for r in rows] == [
        (UNAUTHENTICATED, "olga", "init", "refused"),
        (UNAUTHENTICATED, "olga", "login", "refused"),
        (UNAUTHENTICATED, "olga", "logout", "refused"),
        ("vic", "", "login", "applied"),
        ("vic", "", "mode", "refused"),
    ]
    assert not [r for r in rows if r.user == "olga"]  # nothing in olga's name
    assert [(e.user, e.claimed) for e in published][:3] == [(UNAUTHENTICATED, "olga")] * 3
    assert audit_command(tmp_path / "s.sqlite", None) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].endswith(
        '  (unauthenticated) claiming "olga" (unproven) from 10.0.0.66: init FILL: '
        "refused: invalid token: log in again"
    )
    assert "  vic (viewer): mode FILL" in out[4] and "claiming" not in out[4]


def test_a_state_file_from_before_the_claimed_column_reads_and_gets_it(tmp_path: Path) -> None:
    path = tmp_path / "s.sqlite"
    StateStore(path).close()
    db = sqlite3.connect(path)  # a file of the release before: no claimed column
    for column in ("role", "origin", "fb", "args", "reason"):
        db.execute(f"ALTER TABLE audit ADD COLUMN {column} TEXT NOT NULL DEFAULT ''")
    db.execute("ALTER TABLE audit ADD COLUMN outcome TEXT NOT NULL DEFAULT 'applied'")
    db.execute("ALTER TABLE audit ADD COLUMN count INTEGER NOT NULL DEFAULT 1")
    db.execute(
        "INSERT INTO audit (t_ns, user, action, detail, role, outcome, reason) "
        "VALUES (7, 'mallory', 'init', '', '', 'refused', 'invalid token')"
    )
    db.commit()
    db.close()
    assert [(r.user, r.claimed) for r in read_audit(path)] == [("mallory", "")]
    AuditStore(path).close()  # a CPU opens it: the column is added, the old row kept
    columns = {r[1] for r in sqlite3.connect(path).execute("PRAGMA table_info(audit)")}
    assert "claimed" in columns
    assert [(r.user, r.claimed) for r in read_audit(path)] == [("mallory", "")]


def test_the_audit_panel_shows_an_unproven_name_only_as_claimed() -> None:
    """The page's audit panel words a refusal of an unauthenticated sender as
    ``s7graph audit`` does: the name it gave is a claim, never the row's author."""
    from s7graph.web.view.texts import audit_html

    entry = AuditEntry(
        id=1,
        t_ms=0,
        user=UNAUTHENTICATED,
        op="off",
        outcome="refused",
        reason="bad token",
        claimed="olga",
    )
    shown = audit_html([entry])
    assert f'<b>{UNAUTHENTICATED} claiming "olga" (unproven)</b>' in shown
    proven = AuditEntry(id=2, t_ms=0, user="olga", op="off", outcome="applied")
    assert "claiming" not in audit_html([proven])
