"""Each message's last comment, however old: of each message the newest applied
``ack_msg`` row that gave it a comment or emptied it (``AuditStore.acked``, ``audit/acked``
on the bus), read through an index of those rows (``audit_acked``), not a window of the
last rows — what an OPC UA face started again restores (docs/opcua.md, "Alarms and
conditions")."""

from __future__ import annotations

import contextlib
import json
import sqlite3
from pathlib import Path

from s7graph.engine.persistence import StateStore
from s7graph.web.access.audit import AuditStore, Facts
from s7graph.web.access.login import Authenticator
from s7graph.web.bus.gate import Gate

T0 = 1_795_000_000 * 10**9


def _ack(msg_id: object, comment: str | None, applied: bool = True) -> Facts:
    args: dict[str, object] = {"msg_id": msg_id}
    if comment is not None:
        args["comment"] = comment
    return Facts("olga", "operator", "opc.tcp", "ack_msg", "Seq", args, applied)


def _many(path: Path, n: int, t_ns: int) -> None:
    """``n`` rows of forces written into the closed state file ``path`` in one transaction,
    as a long run leaves them."""
    args = json.dumps({"address": "Q0.0", "value": True, "why": "x" * 150})
    rows = [(t_ns + i, "eng", "engineer", "shell", "force", "", args, "applied") for i in range(n)]
    insert = "INSERT INTO audit (t_ns, user, role, origin, action, fb, args, outcome)"
    with contextlib.closing(sqlite3.connect(path)) as db, db:
        db.executemany(f"{insert} VALUES (?, ?, ?, ?, ?, ?, ?, ?)", rows)


def test_each_message_s_newest_comment_is_read_however_many_rows_came_after(
    tmp_path: Path,
) -> None:
    path = tmp_path / "s.sqlite"
    store = AuditStore(path)
    store.record(T0 + 1, _ack("A", "first"))
    store.record(T0 + 2, _ack("A", "second"))
    store.record(T0 + 3, _ack("A", None))  # a Null comment leaves it
    store.record(T0 + 4, _ack("A", "not applied", applied=False))
    store.record(T0 + 5, _ack(7, "kept"))
    store.record(T0 + 6, _ack(7, ""))  # emptied: the row says so
    store.record(T0 + 7, _ack("B", "cut short"), text=20)  # no JSON left: passed over
    store.record(T0 + 8, Facts("olga", "operator", "page", "set_mode", "Seq", {}, True))
    store.close()
    _many(path, 20_000, T0 + 100)
    store = AuditStore(path)
    store.record(T0 + 30_000, _ack("C", "newest"))
    got = [(r.t_ns - T0, json.loads(r.args)) for r in store.acked()]
    assert got == [
        (2, {"comment": "second", "msg_id": "A"}),
        (6, {"comment": "", "msg_id": 7}),
        (30_000, {"comment": "newest", "msg_id": "C"}),
    ]
    assert [json.loads(r.args)["msg_id"] for r in store.acked(2)] == [7, "C"]  # the last 2
    plan = store._db.execute(  # the index's rows, never a scan of the table
        "EXPLAIN QUERY PLAN SELECT max(id) FROM audit WHERE action = 'ack_msg' AND outcome = "
        "'applied' AND CASE WHEN json_valid(args) THEN json_type(args, '$.comment') END = "
        "'text' GROUP BY CASE WHEN json_valid(args) THEN json_extract(args, '$.msg_id') END"
    ).fetchall()
    assert any("USING INDEX audit_acked" in str(row[-1]) for row in plan), plan
    store.close()


def test_a_state_file_from_before_gets_the_index_and_a_gate_serves_the_rows(
    tmp_path: Path,
) -> None:
    path = tmp_path / "s.sqlite"
    StateStore(path).close()  # no index yet: the engine's tables only
    db = sqlite3.connect(path)
    assert (
        db.execute("SELECT name FROM sqlite_master WHERE name = 'audit_acked'").fetchone() is None
    )
    db.close()
    store = AuditStore(path)
    store.record(T0, _ack("S2", "valve checked"))
    store.close()
    _many(path, 60, T0 + 1)  # more than audit/list's 50
    store = AuditStore(path)
    gate = Gate(Authenticator(None), store, flush_s=None)
    assert [e.args for e in gate.acked_list().entries] == [
        '{"comment": "valve checked", "msg_id": "S2"}'
    ]
    assert all(e.op == "force" for e in gate.audit_list().entries)
    store.close()
    db = sqlite3.connect(path)
    assert db.execute("SELECT name FROM sqlite_master WHERE name = 'audit_acked'").fetchone()
    db.close()
