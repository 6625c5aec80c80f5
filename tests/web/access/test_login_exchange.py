"""The CPU's side of a login without a network: the SCRAM-SHA-256 exchange (the password
never reaches the CPU; a fake CPU is found out; unknown names look like known ones), the
session key that signs commands (a changed, replayed or unsigned one is refused), the
lockout per source with back-off, the name rule as a whole string, and the users file's
old scrypt entries."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import msgspec
import pytest

from s7graph.web.access.lockout import Lockout
from s7graph.web.access.login import (
    LOGIN_WINDOW_S,
    MAX_PENDING,
    NOT_SIGNED,
    PENDING_PER_SOURCE,
    Authenticator,
    LoginResult,
    password_login,
)
from s7graph.web.access.scram import (
    MIN_ITERATIONS,
    ClientLogin,
    LoginError,
    Signer,
    Verifier,
    command_bytes,
    sign,
)
from s7graph.web.access.users import UsersError, UsersFile, name_problem
from s7graph.web.bus.gate import Gate
from s7graph.web.commands import Command

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
    f.add("eng", "engineer", PASSWORD, iterations=MIN_ITERATIONS)
    return f


def _signed(auth: Authenticator, user: str = "olga") -> tuple[Signer, Command]:
    result, signer = password_login(auth, user, PASSWORD)
    assert result.ok and signer is not None, result.reason
    return signer, Command(op="init", fb="FILL", user=user, token=result.token)


def _verify(auth: Authenticator, command: Command) -> str:
    return auth.verify(
        command.token, command.mac or "", command_bytes(command), seq=command.seq or 0
    )


# ---------------------------------------------------------------- the exchange


def test_the_users_file_holds_a_verifier_from_which_no_login_follows(users: UsersFile) -> None:
    text = users.path.read_text()
    assert PASSWORD not in text
    olga = Verifier.parse(json.loads(text)["users"]["olga"]["password"])
    assert olga.iterations == MIN_ITERATIONS and len(olga.salt) >= 16
    # what the file holds, offered as the password, is no way in
    auth = Authenticator(users)
    for guess in (olga.text, olga.text.split("$")[2]):
        assert not password_login(auth, "olga", guess[:1024])[0].ok


def test_the_password_never_reaches_the_cpu_only_a_proof_bound_to_its_nonces(
    users: UsersFile,
) -> None:
    auth = Authenticator(users)
    seen: list[str] = []

    def login(user: str, scram: str = "", *, source: str = "") -> LoginResult:
        seen.append(scram)
        return Authenticator.login(auth, user, scram, source=source)

    def prove(login_id: str, user: str, scram: str, *, source: str = "") -> LoginResult:
        seen.append(scram)
        return Authenticator.prove(auth, login_id, user, scram, source=source)

    auth.login = login  # type: ignore[method-assign]
    auth.prove = prove  # type: ignore[method-assign]
    result, _ = password_login(auth, "olga", PASSWORD)
    assert result.ok and len(seen) == 2
    assert all(PASSWORD not in m and "correct" not in m for m in seen)
    assert seen[0].startswith("n,,n=olga,r=") and ",p=" in seen[1]
    # the proof answers one challenge only: sent again for a new login, it fails
    again = auth.login("olga", seen[0])
    assert again.challenge
    replayed = auth.prove(again.login_id, "olga", seen[1])
    assert (replayed.ok, replayed.reason) == (False, "wrong user name or password")
    # and a login id is good once
    assert not auth.prove(again.login_id, "olga", seen[1]).ok


def test_the_client_detects_a_wrong_server_signature(users: UsersFile) -> None:
    auth = Authenticator(users)
    client = ClientLogin("olga", PASSWORD)
    challenge = auth.login("olga", client.first())
    answer = auth.prove(challenge.login_id, "olga", client.final(challenge.scram))
    assert answer.ok and answer.scram.startswith("v=")
    forged = "v=" + "A" * 43 + "="
    with pytest.raises(LoginError, match="did not prove it knows the password"):
        client.verify(forged)


def test_an_unknown_name_gets_a_consistent_challenge_and_fails_at_the_proof(
    users: UsersFile,
) -> None:
    auth = Authenticator(users)

    def salt_and_count(user: str) -> tuple[str, str]:
        challenge = auth.login(user, ClientLogin(user, "whatever1").first())
        assert challenge.challenge and challenge.reason == ""
        fields = dict(p.split("=", 1) for p in challenge.scram.split(","))
        return fields["s"], fields["i"]

    assert salt_and_count("nobody") == salt_and_count("nobody")  # the same at every try
    assert salt_and_count("nobody") != salt_and_count("someone")
    assert salt_and_count("olga") == salt_and_count("olga")
    assert password_login(auth, "nobody", PASSWORD)[0].reason == "wrong user name or password"
    assert password_login(auth, "olga", "not it!!")[0].reason == "wrong user name or password"


def test_unfinished_logins_expire_after_10_s_and_are_bounded(users: UsersFile) -> None:
    clock = Clock()
    auth = Authenticator(users, clock=clock)
    client = ClientLogin("olga", PASSWORD)
    challenge = auth.login("olga", client.first())
    clock.t += LOGIN_WINDOW_S + 0.1
    late = auth.prove(challenge.login_id, "olga", client.final(challenge.scram))
    assert not late.ok and "no such login" in late.reason
    for n in range(MAX_PENDING + 50):
        auth.login("eng", ClientLogin("eng", PASSWORD).first(), source=f"pc{n}")
    assert len(auth._pending) == MAX_PENDING


def test_a_flood_of_first_steps_from_one_source_fills_only_its_own_eight(
    users: UsersFile,
) -> None:
    """Unfinished logins evict the oldest beyond 256: one source sending only first steps
    made every other login fail ("no such login"). It holds 8 at most; the ninth is refused
    with the reason, and another source's login goes through meanwhile."""
    clock = Clock()
    auth = Authenticator(users, clock=clock)
    honest = ClientLogin("olga", PASSWORD)
    challenge = auth.login("olga", honest.first(), source="client.olga@tls/10.0.0.7")
    flood = [auth.login("eng", ClientLogin("eng", "x").first(), source="rogue") for _ in range(300)]
    assert all(r.challenge for r in flood[:PENDING_PER_SOURCE])
    refused = flood[PENDING_PER_SOURCE:]
    assert {r.reason for r in refused} == {
        "8 logins from here are unfinished: finish one, or log in again after 10 s"
    }
    done = auth.prove(
        challenge.login_id, "olga", honest.final(challenge.scram), source="client.olga@tls/10.0.0.7"
    )
    assert done.ok, done.reason
    clock.t += LOGIN_WINDOW_S + 0.1  # the rogue's eight expire: it may start again
    assert auth.login("eng", ClientLogin("eng", "x").first(), source="rogue").challenge


# ---------------------------------------------------------------- session binding, replay


def test_a_command_signed_by_the_session_passes_once(users: UsersFile) -> None:
    auth = Authenticator(users)
    signer, command = _signed(auth)
    first = signer.sign(command)
    assert first.seq == 1 and first.mac and len(first.mac) == 64
    assert _verify(auth, first) == ""
    assert _verify(auth, first) == "replayed or out of order: seq 1"
    assert _verify(auth, signer.sign(command)) == ""  # seq 2


def test_commands_and_watches_of_one_session_share_one_numbering_and_one_mac(
    users: UsersFile,
) -> None:
    """``Signer.sign`` is ``Signer.numbered`` with the command's bytes: one sequence, one
    way to the mac, and a stale ``mac`` on the command is replaced, never kept."""
    auth = Authenticator(users)
    signer, command = _signed(auth)
    first = signer.sign(msgspec.structs.replace(command, mac="f" * 64))
    seq, mac = signer.numbered(lambda n: b"watch %d" % n)
    third = signer.sign(command)
    assert (first.seq, seq, third.seq) == (1, 2, 3)
    assert _verify(auth, first) == "" and _verify(auth, third) == ""
    assert auth.verify(signer.token, mac, b"watch 2", seq=seq) == ""
    demo = Signer("alice", "t")
    assert demo.numbered(lambda n: b"x") == (1, "") and demo.sign(command).mac is msgspec.UNSET


def test_a_command_with_a_tampered_argument_is_refused(users: UsersFile) -> None:
    auth = Authenticator(users)
    signer, _ = _signed(auth)
    token = signer.token
    mode = signer.sign(
        Command(op="mode", fb="FILL", user="olga", token=token, args={"mode": "AUTO"})
    )
    given = {"user": "olga", "token": token, "seq": mode.seq, "mac": mode.mac}
    changed = Command(op="mode", fb="FILL", args={"mode": "MAN"}, **given)
    assert _verify(auth, changed) == NOT_SIGNED
    other_fb = Command(op="mode", fb="OTHER", args={"mode": "AUTO"}, **given)
    assert _verify(auth, other_fb) == NOT_SIGNED
    assert _verify(auth, mode) == ""  # the original still passes: the changes took nothing


def test_a_token_used_without_the_session_key_is_refused(users: UsersFile) -> None:
    auth = Authenticator(users)
    signer, command = _signed(auth)
    assert _verify(auth, command) == NOT_SIGNED  # no mac at all
    stranger = Signer("olga", signer.token, b"\x00" * 32)  # the token, another key
    assert _verify(auth, stranger.sign(command)) == NOT_SIGNED
    assert _verify(auth, Signer("olga", signer.token).sign(command)) == NOT_SIGNED  # no key


def test_commands_of_one_session_may_arrive_out_of_order_within_64_never_twice(
    users: UsersFile,
) -> None:
    auth = Authenticator(users)
    signer, command = _signed(auth)
    sent = [signer.sign(command) for _ in range(70)]
    for c in [sent[5], sent[3], sent[4], sent[0], sent[69]]:
        assert _verify(auth, c) == "", c.seq
    assert _verify(auth, sent[3]) == "replayed or out of order: seq 4"
    assert _verify(auth, sent[6]) == ""  # seq 7: 63 below 70, still in the window
    assert _verify(auth, sent[5]) == "replayed or out of order: seq 6"  # 64 below: out
    assert _verify(auth, sent[1]) == "replayed or out of order: seq 2"


def test_a_seq_far_ahead_only_moves_the_window_and_the_gate_audits_it(
    users: UsersFile,
) -> None:
    """A signed command numbered 2**62 (a logged-in viewer's reach) moved the window by a
    shift of 2**62 bits: the CPU ran out of memory, the scan stalled. The window now starts
    again at that number; the command is checked, applied and audited as any other."""
    auth = Authenticator(users)
    signer, command = _signed(auth)
    first = signer.sign(command)
    key = signer._key
    far = msgspec.structs.replace(first, seq=2**62)
    far = msgspec.structs.replace(far, mac=sign(key, command_bytes(far)))
    assert _verify(auth, first) == ""
    assert _verify(auth, far) == ""
    assert _verify(auth, far) == f"replayed or out of order: seq {2**62}"
    top = msgspec.structs.replace(far, seq=2**63 - 1)
    top = msgspec.structs.replace(top, mac=sign(key, command_bytes(top)))
    assert _verify(auth, top) == ""
    assert _verify(auth, first) == "replayed or out of order: seq 1"


def test_a_check_that_fails_inside_refuses_the_command_with_an_audit_row(
    users: UsersFile,
) -> None:
    auth = Authenticator(users)
    gate = Gate(auth)
    signer, command = _signed(auth)

    def broken(*args: object, **kwargs: object) -> str:
        raise MemoryError

    auth.verify = broken  # type: ignore[method-assign]
    applied, reason = gate.apply(signer.sign(command), lambda c: (True, ""))
    assert not applied and reason.startswith("command refused: an internal error")
    rows = gate.audit_list().entries
    assert rows and (rows[-1].reason, rows[-1].outcome) == (reason, "refused")
    gate.close()


def test_the_sequence_lives_with_the_session_for_its_8_hours(users: UsersFile) -> None:
    clock = Clock()
    auth = Authenticator(users, clock=clock)
    signer, command = _signed(auth)
    early = signer.sign(command)
    assert _verify(auth, early) == ""
    clock.t += 7.9 * 3600
    assert _verify(auth, early) == "replayed or out of order: seq 1"
    assert auth.identify("olga", early.token) != "token expired: log in again"
    clock.t += 0.2 * 3600
    assert auth.identify("olga", early.token) == "token expired: log in again"


def test_a_command_refused_before_its_check_stays_refused_when_sent_again(
    users: UsersFile,
) -> None:
    gate = Gate(Authenticator(users))
    signer, command = _signed(gate.auth)
    expired = signer.sign(command)
    gate.refuse(expired, "expired before the scan boundary")  # never checked, never applied
    assert gate.check(expired) == (None, "replayed or out of order: seq 1")
    assert gate.check(signer.sign(command))[1] == ""


def test_the_demo_signs_nothing_and_refuses_nothing_for_it() -> None:
    auth = Authenticator(None)
    result, signer = password_login(auth, "alice")
    assert result.ok and not result.verified and signer is not None
    command = signer.sign(Command(op="init", fb="FILL", user="alice", token=result.token))
    assert command.seq == 1 and not command.mac
    assert _verify(auth, command) == "" and _verify(auth, command) == ""


# ---------------------------------------------------------------- lockout per source


def test_lockout_per_source_leaves_another_source_able_to_log_in(users: UsersFile) -> None:
    clock = Clock()
    auth = Authenticator(users, clock=clock)
    for _ in range(5):
        rogue = password_login(auth, "olga", "guessing", source="peer rogue")[0]
    assert "locked out for 60 s" in rogue.reason
    assert "locked out" in password_login(auth, "olga", PASSWORD, source="peer rogue")[0].reason
    own = password_login(auth, "olga", PASSWORD, source="page 1 (10.0.0.7)")[0]
    assert own.ok, own.reason  # the real operator, at her own client


def test_back_off_doubles_up_to_an_hour_and_a_success_resets_it() -> None:
    clock = Clock()
    lockout = Lockout(clock=clock)
    assert [lockout.failed("olga", "x") for _ in range(5)] == [0, 0, 0, 0, 60]
    lengths = []
    for _ in range(8):
        clock.t += lockout.locked_for("olga", "x") + 1
        lengths.append(lockout.failed("olga", "x"))
    assert lengths == [120, 240, 480, 960, 1920, 3600, 3600, 3600]
    assert lockout.locked_for("olga", "y") == 0 and lockout.locked_for("eng", "x") == 0
    clock.t += 3601
    lockout.succeeded("olga", "x")
    assert [lockout.failed("olga", "x") for _ in range(5)] == [0, 0, 0, 0, 60]


def test_the_lockout_table_is_bounded_and_keeps_the_locks_longest() -> None:
    clock = Clock()
    lockout = Lockout(clock=clock, capacity=100)
    for _ in range(5):
        lockout.failed("olga", "rogue")
    for n in range(500):
        lockout.failed("olga", f"spoofed {n}")
    assert len(lockout) <= 100
    assert lockout.locked_for("olga", "rogue") > 0  # a flood does not lift a lock


# ---------------------------------------------------------------- names


HOSTILE = ["olga\n", "olga ", " olga", "olga\r", "ol\tga", "olga\x00", "\x1b[31molga", "olga\u200b"]


@pytest.mark.parametrize("name", HOSTILE)
def test_names_with_control_characters_or_whitespace_are_refused(
    users: UsersFile, name: str
) -> None:
    with pytest.raises(UsersError, match="invalid user name"):
        users.add(name, "operator", PASSWORD, iterations=MIN_ITERATIONS)
    assert "olga" in users.load() and name not in users.load()
    refused, signer = password_login(Authenticator(users), name, PASSWORD)
    assert not refused.ok and refused.reason.startswith("invalid user name") and signer is None
    assert not Authenticator(None).login(name).ok  # not even claimed in the demo
    with pytest.raises(ValueError, match="invalid user name"):
        Command(op="init", fb="FILL", user=name)


def test_a_name_with_a_trailing_newline_says_why(users: UsersFile) -> None:
    with pytest.raises(UsersError, match="control character"):
        users.add("olga\n", "operator", PASSWORD)
    with pytest.raises(UsersError, match="whitespace around it"):
        users.add("olga ", "operator", PASSWORD)


# ---------------------------------------------------------------- the old scrypt entries


def _version_1(path: Path) -> None:
    legacy = "scrypt$16384$8$1$AAAAAAAAAAAAAAAAAAAAAA==$" + "A" * 43 + "="
    data = {"version": 1, "users": {"olga": {"role": "operator", "password": legacy}}}
    path.write_text(json.dumps(data))
    os.chmod(path, 0o600)


def test_a_version_1_scrypt_user_gets_the_clear_reason_until_passwd(tmp_path: Path) -> None:
    users = UsersFile(tmp_path / "users.json")
    _version_1(users.path)
    assert users.load()["olga"].legacy  # the file still loads
    auth = Authenticator(users)
    refused = password_login(auth, "olga", PASSWORD)[0]
    assert not refused.ok
    assert "old form (scrypt)" in refused.reason
    assert "s7graph users passwd olga" in refused.reason
    assert auth.lockout.locked_for("olga", "") == 0 and len(auth.lockout) == 0  # no failure
    users.passwd("olga", PASSWORD, iterations=MIN_ITERATIONS)
    assert json.loads(users.path.read_text())["version"] == 2
    assert password_login(auth, "olga", PASSWORD)[0].ok


def test_users_cli_refuses_hostile_names_and_shows_old_entries(tmp_path: Path) -> None:
    path = tmp_path / "u.json"

    def run(*args: str, stdin: str = "") -> subprocess.CompletedProcess[str]:
        cmd = [sys.executable, "-m", "s7graph", "users", *args, "--file", str(path)]
        return subprocess.run(cmd, input=stdin, capture_output=True, text=True, timeout=60)

    for name in ("olga\n", "olga ", "ol\x07ga"):
        bad = run("add", name, "--role", "operator", "--password-stdin", stdin=PASSWORD)
        assert bad.returncode == 2 and "invalid user name" in bad.stderr, bad.stderr
    _version_1(path)
    assert run("list").stdout == "olga\toperator\tcannot log in: s7graph users passwd olga\n"
    assert run("passwd", "olga", "--password-stdin", stdin=PASSWORD + "\n").returncode == 0
    assert run("list").stdout == "olga\toperator\n"


def test_a_refused_name_is_shown_as_written_its_control_characters_escaped() -> None:
    """The page shows why a name is refused: ``ölga`` as ``ölga`` (not ``\\xf6lga``), a
    long one cut whole characters short, a control or direction character escaped."""
    assert name_problem("ölga").startswith("invalid user name 'ölga': ")
    assert name_problem("😀" * 50).startswith(f"invalid user name '{'😀' * 32}'…: ")
    assert name_problem("a\u202eb").startswith("invalid user name 'a\\u202eb': it holds a control")


def test_a_password_longer_than_a_users_file_holds_is_refused_before_any_work(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A login with a megabyte of password held an OPC UA face's loop for seconds (its
    key derivation grows with the length): it is refused before the SCRAM client is even
    made, and the same length is a users file's limit."""
    import s7graph.web.access.scram as scram

    def never(*_: object) -> None:
        raise AssertionError("the SCRAM client was made")

    monkeypatch.setattr(scram, "ScramClient", never)
    with pytest.raises(LoginError, match="a password has at most 1,024 characters"):
        ClientLogin("olga", "x" * 1_000_000)
    said, signer = scram.log_in("olga", "x" * 1025, lambda *_: pytest.fail("sent"))
    assert said == "a password has at most 1,024 characters" and signer is None
