"""A users file made readable by others while the CPU runs: logins are refused, naming the
fix, until it is fixed; sessions already open go on; the diagnostic buffer gets one entry
when it happens and one when it is fixed, not one a login."""

from __future__ import annotations

import json
import os
from pathlib import Path

from s7graph.engine import CallContext, Cpu, EventId, VirtualClock, ob
from s7graph.engine.persistence import StateStore
from s7graph.web.access.audit import read_audit
from s7graph.web.access.login import Authenticator, password_login
from s7graph.web.access.scram import MIN_ITERATIONS
from s7graph.web.access.users import UsersFile
from s7graph.web.bus.gate import cpu_gate
from s7graph.web.bus.protocol import Command
from tests.web.access.gate_login import gate_login

PASSWORD = "correct horse"
WATCHED = (EventId.USERS_FILE_EXPOSED, EventId.USERS_FILE_PROTECTED)


@ob(1)
def idle(ctx: CallContext) -> None:
    pass


def entries(cpu: Cpu) -> list[tuple[int, str]]:
    cpu.scan()  # the entry is added at the scan boundary, by the scan thread
    return [(e.event_id, e.message) for e in cpu.diagnostics if e.event_id in WATCHED]


def test_chmod_644_refuses_logins_with_the_fix_and_chmod_600_takes_them_again(
    tmp_path: Path, clock: VirtualClock
) -> None:
    users = UsersFile(tmp_path / "users.json")
    users.add("olga", "operator", PASSWORD, iterations=MIN_ITERATIONS)
    cpu = Cpu(clock)
    cpu.load(idle)  # type: ignore[arg-type]
    cpu.start()
    state = StateStore(tmp_path / "s.sqlite")
    gate = cpu_gate(users.path, state, cpu=cpu)  # as s7graph run wires it
    session, signer = gate_login(gate, "olga", PASSWORD)
    assert session.ok and signer is not None
    mtime = users.path.stat().st_mtime_ns

    os.chmod(users.path, 0o644)  # no new mtime: the mode is looked at every time
    assert users.path.stat().st_mtime_ns == mtime
    exposed = f"users file is readable by others: chmod 600 {users.path}"
    for _ in range(3):
        refused = gate_login(gate, "olga", PASSWORD)[0]
        assert (refused.ok, refused.reason) == (False, exposed)
    command = signer.sign(Command(op="init", fb="FILL", user="olga", token=session.token))
    assert gate.apply(command, lambda c: (True, "")) == (True, "")  # an open session goes on
    assert entries(cpu) == [(EventId.USERS_FILE_EXPOSED, exposed)]

    os.chmod(users.path, 0o600)
    assert gate_login(gate, "olga", PASSWORD)[0].ok
    assert gate_login(gate, "olga", PASSWORD)[0].ok
    fixed = f"users file {users.path} is no longer readable by others: logins taken again"
    assert entries(cpu) == [
        (EventId.USERS_FILE_EXPOSED, exposed),
        (EventId.USERS_FILE_PROTECTED, fixed),
    ]
    gate.flush()
    logins = [(r.outcome, r.reason, r.count) for r in read_audit(state.path)]
    assert ("refused", exposed, 3) in logins
    state.close()


def test_a_users_file_changed_while_readable_is_read_once_it_is_fixed(tmp_path: Path) -> None:
    users = UsersFile(tmp_path / "users.json")
    users.add("olga", "operator", PASSWORD, iterations=MIN_ITERATIONS)
    users.add("vic", "viewer", PASSWORD, iterations=MIN_ITERATIONS)
    auth = Authenticator(users)
    data = json.loads(users.path.read_text())
    del data["users"]["vic"]
    os.chmod(users.path, 0o644)
    users.path.write_text(json.dumps(data))  # an editor that keeps the wrong mode
    assert auth.login("vic", PASSWORD).reason.startswith("users file is readable by others")
    os.chmod(users.path, 0o600)
    olga, vic = (password_login(auth, name, PASSWORD)[0] for name in ("olga", "vic"))
    assert olga.ok and not vic.ok
