"""The CPU's door: who is asking, may they, and the audit row — refusals included.

:class:`Gate` answers the bus's ``login`` (through ``web.access.login.Authenticator``),
and for every command drained at the scan boundary establishes who sent it (user and
token), checks the role table (``web.access.roles``), hands allowed commands to the FB's
``apply`` as that user — ``alice``, or ``alice (unverified)`` without a users file — with
the token stripped, and writes one audit row per command, applied or refused, with its
origin. On the bus the origin is the transport's (``web.bus.origin``: the link's identity
and remote locator, the ``source`` of a login); what the sender claims is kept as a note
in the row's detail. With a users file a command must be signed by its session and new
to it (``seq``): a changed or replayed one is refused, and audited. Rows also go to
``on_audit`` (the bus publishes them on ``audit``). Tokens, passwords, proofs and
session keys reach neither ``apply`` nor the audit nor any log.

A refusal of a sender the gate did not authenticate — no identity: a missing, malformed,
unknown or expired token, or one of another user or of a removed one; a message nobody
could read; a failed login, whatever the name; a logout of no session — is *anonymous*:
counted per minute, source and reason by ``web.access.tally`` (one row, a count), so a
flood of them cannot fill the disk; its row's user is ``(unauthenticated)`` and the name
the sender gave only its ``claimed`` (:func:`unproven_author`). A refusal of an
authenticated sender, every applied command and every login that succeeds stay one row
each (docs/security.md, "The audit cannot fill the disk").
"""

from __future__ import annotations

import dataclasses
import functools
import time
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import TYPE_CHECKING, TypeAlias

import msgspec
from msgspec import UNSET

from s7graph.engine.errors import internal_error
from s7graph.web.access.audit import UNAUTHENTICATED, AuditRecord, AuditStore, Facts
from s7graph.web.access.login import NOT_SIGNED, Authenticator, Identity
from s7graph.web.access.roles import NOT_AVAILABLE, allowed, lowest_role
from s7graph.web.access.scram import command_bytes, logout_bytes
from s7graph.web.access.tally import FLUSH_S, MAX_KINDS, TEXT, RefusalTally
from s7graph.web.access.users import UsersError, UsersFile
from s7graph.web.bus.origin import lockout_source
from s7graph.web.bus.protocol import (
    AlarmEvent,
    AlarmHistory,
    AuditEntry,
    AuditList,
    Command,
    LoginReply,
    LoginRequest,
    Refusal,
)

if TYPE_CHECKING:
    from s7graph.engine.cpu import Cpu
    from s7graph.engine.persistence import StateStore

__all__ = [
    "Apply",
    "Gate",
    "audit_entry",
    "claimed_note",
    "cpu_gate",
    "unproven_author",
    "with_note",
]

ApplyResult: TypeAlias = tuple[bool, str] | tuple[bool, str, str]
Apply: TypeAlias = Callable[[Command], ApplyResult]
AUDIT_PANEL = 50
HISTORY = 200


def audit_entry(r: AuditRecord) -> AuditEntry:
    """An audit row as a bus message."""
    return AuditEntry(
        id=max(r.id, 0),
        t_ms=max(r.t_ns // 1_000_000, 0),
        user=r.user[:80],
        role=r.role[:16],
        origin=r.origin[:160],
        op=r.op[:256],
        fb=r.fb[:256],
        args=r.args[:4096],
        outcome="applied" if r.outcome == "applied" else "refused",
        reason=r.reason[:4096],
        count=max(r.count, 1),
        claimed=r.claimed[:80],
    )


def unproven_author(facts: Facts) -> Facts:
    """``facts`` of a sender the CPU did not authenticate: its user ``(unauthenticated)``,
    the name it gave in ``claimed`` — never in the user column, where a listener could
    make rows appear under a victim's name (docs/security.md, "Users, roles, logins and
    the audit")."""
    given = facts.claimed or ("" if facts.user in ("?", UNAUTHENTICATED) else facts.user)
    return dataclasses.replace(facts, user=UNAUTHENTICATED, claimed=given)


def claimed_note(claimed: str) -> str:
    """The note an audit row keeps of the origin its sender claimed ("" when none)."""
    return f"claimed origin: {claimed}" if claimed else ""


def with_note(detail: str, note: str) -> str:
    """``detail`` and ``note`` in one detail column ("; " between them)."""
    return "; ".join(part for part in (detail, note) if part)


def _facts(
    command: Command, user: str, role: str, applied: bool, reason: str, detail: str = ""
) -> Facts:
    return Facts(
        user,
        role,
        command.origin,
        command.op,
        command.fb,
        command.args.given(),
        applied,
        reason,
        detail,
    )


class Gate:
    """Logins, role checks and the audit of one CPU (``audit`` None: no audit kept, the
    last rows in memory); ``flush_s``, ``max_kinds``: see ``web.access.tally``."""

    def __init__(
        self,
        auth: Authenticator | None = None,
        audit: AuditStore | None = None,
        *,
        wall_ns: Callable[[], int] = time.time_ns,
        flush_s: float | None = FLUSH_S,
        max_kinds: int = MAX_KINDS,
    ) -> None:
        self.auth = auth if auth is not None else Authenticator(None)
        self.audit = audit
        self._wall_ns = wall_ns
        self.on_audit: Callable[[AuditEntry], None] | None = None
        self.tally = RefusalTally(audit, max_kinds=max_kinds, flush_s=flush_s)
        self.tally.on_flush = self.flush
        self._recent: list[AuditRecord] = []  # without a store: the last rows in memory
        self._count = 0

    # ------------------------------------------------------------ login

    def login(self, request: LoginRequest, source: str = "", *, unproven: str = "") -> LoginReply:
        """Answer one step of a login, or a logout. ``source``: where it came from by the
        transport (``web.bus.origin``), the audit row's origin — the origin the request
        claims is then only a note; without it (no bus) the claim is the row's origin.
        ``unproven``: why the transport cannot name the link it came over — the step is
        refused with it (``web.bus.origin.query_origin``: what the client must do).
        Failed logins lock out the source (``lockout_source``: the transport, and the page a
        trusted view names), never the user. One audit row per login — refused or done —
        and per logout; none for a challenge."""
        origin = source or request.origin
        note = claimed_note(request.origin) if source else ""
        if request.op == "logout":
            return self._logout(request, origin, note)
        if unproven:
            facts = Facts(request.user, "", origin, "login", "", {}, False, unproven, note)
            self.record(facts, anonymous=True)
            return LoginReply(ok=False, reason=unproven)
        lock = lockout_source(source, request.origin) if source else request.origin
        if request.op == "proof":
            result = self.auth.prove(request.login_id, request.user, request.scram, source=lock)
        else:
            result = self.auth.login(request.user, request.scram, source=lock)
        if result.challenge:
            return LoginReply(
                ok=False, user=request.user, login_id=result.login_id, scram=result.scram
            )
        label = Identity(request.user, result.role, result.verified).label if result.ok else ""
        self.record(
            Facts(
                label or request.user or "?",
                result.role,
                origin,
                "login",
                "",
                {},
                result.ok,
                result.reason,
                note,
            ),
            anonymous=not result.ok,
        )
        if not result.ok:
            return LoginReply(ok=False, reason=result.reason)
        return LoginReply(
            ok=True,
            user=request.user,
            role=result.role,
            token=result.token,
            expires_ms=result.expires_ms,
            verified=result.verified,
            scram=result.scram,
        )

    def _logout(self, request: LoginRequest, origin: str, note: str) -> LoginReply:
        """Revoke a token: with a users file only when its session key signed the logout
        (a listener who saw the token cannot end the session)."""
        why = self.auth.verify(request.token, request.mac, logout_bytes(request.token))
        known = why != NOT_SIGNED and self.auth.logout(request.token)
        why = why if why == NOT_SIGNED else "" if known else "no such session"
        facts = Facts(request.user or "?", "", origin, "logout", "", {}, known, why, note)
        self.record(facts, anonymous=not known)
        return LoginReply(ok=known, reason=why)

    # ------------------------------------------------------------ commands

    def check(self, command: Command) -> tuple[Identity | None, str]:
        """Who sent ``command`` (None: nobody we know) and why it may not be applied ("":
        it may; a :class:`Refusal` of kind ``access``, or ``refused`` for an op this CPU
        does not offer). With a users file the session key must have signed it and its
        ``seq`` must be new (it then counts as seen: a command is checked once)."""
        who = self.signed_by(
            command.user, command.token, command.mac or "", command_bytes(command), command.seq or 0
        )
        if isinstance(who, str):
            return None, Refusal("access", who)
        if not allowed(who.role, command.op):
            need = lowest_role(command.op) or "?"
            return who, Refusal("access", f"role {who.role} may not {command.op} (needs {need})")
        if command.op in NOT_AVAILABLE:
            return who, Refusal("refused", f"{command.op} is not available yet on this CPU")
        return who, ""

    def signed_by(self, user: str, token: str, mac: str, signed: bytes, seq: int) -> Identity | str:
        """Who signed ``signed`` (a command's or a watch request's bytes), else why not: the
        token a live session of ``user``, ``mac`` its session key's over ``signed``, ``seq``
        new to it (it then counts as seen)."""
        who = self.auth.identify(user, token)
        if isinstance(who, str):
            return who
        problem = self.auth.verify(token, mac, signed, seq=seq)
        return problem if problem else who

    def sender(self, command: Command) -> Identity | None:
        """Who sent ``command``, if its token says so (None: nobody authenticated)."""
        if not command.token:
            return None
        who = self.auth.identify(command.user, command.token)
        return None if isinstance(who, str) else who

    def apply(
        self, command: Command, apply: Apply, *, cycle: int | None = None, note: str = ""
    ) -> tuple[bool, str]:
        """Check, apply (as the established user, without the token) and audit ``command``;
        (applied, reason) — a :class:`Refusal` keeps the kind its site gave it (the gate's
        own are ``access``). ``apply`` raising refuses the command. ``note`` goes to the
        row's detail (the origin the sender claimed)."""
        try:
            who, refusal = self.check(command)
        except Exception as exc:  # a hostile command must not stop the scan loop either
            who, refusal = None, f"command refused: {internal_error('checking it', exc)}"
        if who is None or refusal:
            name, role = (who.label, who.role) if who is not None else (command.user or "?", "")
            self.record(_facts(command, name, role, False, refusal, note), anonymous=who is None)
            return False, refusal
        as_user = msgspec.structs.replace(command, user=who.label, token="", mac=UNSET)
        try:
            result = apply(as_user)
            applied, reason = result[0], result[1]
            detail = result[2] if len(result) > 2 else ""
        except Exception as exc:  # a bad command must not stop the scan loop
            where = f"in the CPU while applying {command.op} to {command.fb}"
            applied, reason, detail = False, f"command refused: {internal_error(where, exc)}", ""
        if cycle is not None and applied:
            detail = f"cycle {cycle}" + (f": {detail}" if detail else "")
        self.record(_facts(command, who.label, who.role, applied, reason, with_note(detail, note)))
        return applied, reason

    def refuse(
        self, command: Command | None, reason: str, origin: str = "", note: str = ""
    ) -> None:
        """Audit a command refused before the scan boundary (unreadable, unknown FB, ...):
        as its sender's if the token authenticates one, else as anonymous. A signed one's
        ``seq`` counts as seen: replayed later, it stays refused."""
        if command is None:
            self.record(Facts("?", "", origin, "?", "", {}, False, reason, note), anonymous=True)
            return
        self.consume(command)
        who = self.sender(command)
        name, role = (who.label, who.role) if who is not None else (command.user or "?", "")
        self.record(_facts(command, name, role, False, reason, note), anonymous=who is None)

    def consume(self, command: Command) -> None:
        """Count a signed command's ``seq`` as seen though it is refused before its check
        (queue full, expired, busy): sent again later, it is refused as replayed."""
        if command.mac:
            signed = command_bytes(command)
            self.auth.verify(command.token, command.mac, signed, seq=command.seq or 0)

    # ------------------------------------------------------------ audit

    def record(self, facts: Facts, *, anonymous: bool = False) -> AuditEntry | None:
        """One audit row (and its ``on_audit`` message); an ``anonymous`` refusal is
        counted in its minute's row instead when one is open (None returned)."""
        t_ns = self._wall_ns()
        if anonymous and not facts.applied:
            facts = unproven_author(facts)
            name = facts.claimed if self.auth.knows(facts.claimed) else ""
            kind = (facts.origin[:160], facts.reason[:TEXT], name)
            write = functools.partial(self._write, t_ns, text=TEXT)
            with self.tally.lock:
                row, changed = self.tally.refuse(t_ns, kind, facts, write)
            self._publish(changed)
            if row is None:
                return None
        else:
            with self.tally.lock:
                row = self._write(t_ns, facts)
        entry = audit_entry(row)
        if self.on_audit is not None:
            self.on_audit(entry)
        return entry

    def _write(self, t_ns: int, facts: Facts, *, text: int = 4096) -> AuditRecord:
        if self.audit is not None:
            return self.audit.record(t_ns, facts, text=text)
        self._count += 1
        row = facts.at(self._count, t_ns, text=text)
        self._recent = [*self._recent[-(AUDIT_PANEL - 1) :], row]
        return row

    def flush(self) -> None:
        """Close the refusal windows of past minutes, write the counts no state writer will
        and publish those that changed (the tally's timer calls it, at most every
        ``flush_s``)."""
        with self.tally.lock:
            changed = self.tally.flush(self._wall_ns())
        self._publish(changed)

    def close(self) -> None:
        """Stop the timer; counts written and published as they stand."""
        self.tally.cancel()
        self.flush()

    def _publish(self, rows: Iterable[AuditRecord]) -> None:
        """Rows whose count changed: in memory (without a store) and on ``audit``."""
        for row in rows:
            if self.audit is None:
                with self.tally.lock:
                    self._recent = [row if r.id == row.id else r for r in self._recent]
            if self.on_audit is not None:
                self.on_audit(audit_entry(row))

    def audit_list(self, n: int = AUDIT_PANEL) -> AuditList:
        rows = self.audit.last(n) if self.audit is not None else self._recent[-n:]
        with self.tally.lock:
            rows = self.tally.live(rows)
        return AuditList(entries=[audit_entry(r) for r in rows])

    def acked_list(self) -> AuditList:
        """Of each message, the newest applied acknowledgement that gave it a comment or
        emptied it, however old (``audit/acked``; ``AuditStore.acked``); without a state
        file, the rows kept in memory (the last 50)."""
        rows = self.audit.acked() if self.audit is not None else list(self._recent)
        return AuditList(entries=[audit_entry(r) for r in rows])

    def history(self, n: int = HISTORY) -> AlarmHistory:
        if self.audit is None:
            return AlarmHistory()
        return AlarmHistory(
            entries=[
                AlarmEvent(
                    id=max(r.id, 0),
                    t_ms=max(r.t_ns // 1_000_000, 0),
                    msg_id=r.msg_id[:128] or "?",
                    state=r.state[:256],
                    text=r.text[:4096],
                    user=r.user[:80],
                )
                for r in self.audit.alarm_history(n)
            ]
        )


def cpu_gate(users: Path | None, state: StateStore, *, cpu: Cpu | None = None) -> Gate:
    """The gate of a CPU started from the command line: reading ``users`` (None: the
    demo), auditing into the run's state file ``state`` (each row committed with the scan's
    state by its writer); with ``cpu``, a users file that becomes readable by others, and
    one that is fixed, are entries of its diagnostic buffer. A users file that is missing or
    cannot be read raises ``UsersError`` here, at start."""
    users_file = UsersFile(users) if users is not None else None
    if users_file is not None:
        if not users_file.path.is_file():
            raise UsersError(f"{users_file.path}: no such users file (s7graph users add ...)")
        users_file.load()
    auth = Authenticator(users_file)
    if cpu is not None:
        auth.on_users_file = users_file_diagnostics(cpu)
    return Gate(auth, AuditStore(state.path, state=state))


def users_file_diagnostics(cpu: Cpu) -> Callable[[bool, str], None]:
    """An ``Authenticator.on_users_file`` for ``cpu``: one diagnostic buffer entry when the
    users file becomes readable by others (``USERS_FILE_EXPOSED``) and one when it is fixed
    (``USERS_FILE_PROTECTED``), each added at the next scan boundary (``Cpu.submit``: the
    buffer is the scan thread's)."""
    from s7graph.engine.diagnostics import EventId

    def note(exposed: bool, text: str) -> None:
        event = EventId.USERS_FILE_EXPOSED if exposed else EventId.USERS_FILE_PROTECTED

        def add(c: Cpu) -> None:
            c.diagnostics.record(c.clock.now_ns(), event, "", text)

        cpu.submit(add)

    return note
