"""The CPU's door: who is asking, may they, and the audit row — refusals included.

:class:`Gate` answers the bus's ``login`` (through ``web.access.login.Authenticator``),
and for every command drained at the scan boundary establishes who sent it (user and
token), checks the role table (``web.access.roles``), hands allowed commands to the FB's
``apply`` as that user — ``alice``, or ``alice (unverified)`` without a users file — with
the token stripped, and writes one audit row per command, applied or refused, with its
origin. On the bus the origin is the transport's (``web.bus.origin``: the link's identity
and remote locator, the ``source`` of a login); what the sender claims is kept as a note
in the row's detail. Rows also go to ``on_audit`` (the bus publishes them on ``audit``).
Tokens and passwords reach neither ``apply`` nor the audit nor any log.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, TypeAlias

import msgspec

from s7graph.web.access.audit import AuditRecord, AuditStore, Facts
from s7graph.web.access.login import Authenticator, Identity
from s7graph.web.access.roles import NOT_AVAILABLE, allowed, lowest_role
from s7graph.web.access.users import UsersError, UsersFile
from s7graph.web.bus.protocol import (
    AlarmEvent,
    AlarmHistory,
    AuditEntry,
    AuditList,
    Command,
    LoginReply,
    LoginRequest,
)

if TYPE_CHECKING:
    from s7graph.engine.persistence import StateStore

__all__ = ["Apply", "Gate", "audit_entry", "claimed_note", "cpu_gate", "with_note"]

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
    )


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
    """Logins, role checks and the audit of one CPU (``audit`` None: no audit kept)."""

    def __init__(
        self,
        auth: Authenticator | None = None,
        audit: AuditStore | None = None,
        *,
        wall_ns: Callable[[], int] = time.time_ns,
    ) -> None:
        self.auth = auth if auth is not None else Authenticator(None)
        self.audit = audit
        self._wall_ns = wall_ns
        self.on_audit: Callable[[AuditEntry], None] | None = None
        self._recent: list[AuditEntry] = []  # without a store: the last rows in memory
        self._count = 0

    # ------------------------------------------------------------ login

    def login(self, request: LoginRequest, source: str = "") -> LoginReply:
        """Answer a login or logout (runs on a worker thread: scrypt takes a while).

        ``source``: where it came from by the transport (``web.bus.origin``), the audit
        row's origin; the origin the request claims is then only a note. Without it (no
        bus) the claimed origin is the row's."""
        origin = source or request.origin
        note = claimed_note(request.origin) if source else ""
        if request.op == "logout":
            known = self.auth.logout(request.token)
            why = "" if known else "no such session"
            who = request.user or "?"
            self.record(Facts(who, "", origin, "logout", "", {}, known, why, note))
            return LoginReply(ok=known, reason="" if known else "no such session")
        result = self.auth.login(request.user, request.password)
        shown = request.user if result.ok or len(request.user) <= 32 else request.user[:32]
        label = Identity(shown, result.role, result.verified).label if result.ok else shown
        self.record(
            Facts(
                label or "?", result.role, origin, "login", "", {}, result.ok, result.reason, note
            )
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
        )

    # ------------------------------------------------------------ commands

    def check(self, command: Command) -> tuple[Identity | None, str]:
        """Who sent ``command`` (None: nobody we know) and why it may not be applied ("":
        it may)."""
        who = self.auth.identify(command.user, command.token)
        if isinstance(who, str):
            return None, who
        if not allowed(who.role, command.op):
            need = lowest_role(command.op) or "?"
            return who, f"role {who.role} may not {command.op} (needs {need})"
        if command.op in NOT_AVAILABLE:
            return who, f"{command.op} is not available yet on this CPU"
        return who, ""

    def apply(
        self, command: Command, apply: Apply, *, cycle: int | None = None, note: str = ""
    ) -> tuple[bool, str]:
        """Check, apply (as the established user, without the token) and audit ``command``;
        (applied, reason). ``apply`` raising refuses the command. ``note`` goes to the
        row's detail (the origin the sender claimed)."""
        who, refusal = self.check(command)
        if who is None or refusal:
            name, role = (who.label, who.role) if who is not None else (command.user or "?", "")
            self.record(_facts(command, name, role, False, refusal, note))
            return False, refusal
        as_user = msgspec.structs.replace(command, user=who.label, token="")
        try:
            result = apply(as_user)
            applied, reason = result[0], result[1]
            detail = result[2] if len(result) > 2 else ""
        except Exception as exc:  # a bad command must not stop the scan loop
            applied, reason, detail = False, f"{type(exc).__name__}: {exc}", ""
        if cycle is not None and applied:
            detail = f"cycle {cycle}" + (f": {detail}" if detail else "")
        self.record(_facts(command, who.label, who.role, applied, reason, with_note(detail, note)))
        return applied, reason

    def refuse(
        self, command: Command | None, reason: str, origin: str = "", note: str = ""
    ) -> None:
        """Audit a command refused before the scan boundary (unreadable, unknown FB, ...)."""
        if command is None:
            self.record(Facts("?", "", origin, "?", "", {}, False, reason, note))
        else:
            self.record(_facts(command, command.user or "?", "", False, reason, note))

    # ------------------------------------------------------------ audit

    def record(self, facts: Facts) -> AuditEntry:
        """One audit row (and its ``on_audit`` message)."""
        t_ns = self._wall_ns()
        if self.audit is not None:
            entry = audit_entry(self.audit.record(t_ns, facts))
        else:
            self._count += 1
            entry = audit_entry(facts.at(self._count, t_ns))
            self._recent = [*self._recent[-(AUDIT_PANEL - 1) :], entry]
        if self.on_audit is not None:
            self.on_audit(entry)
        return entry

    def audit_list(self, n: int = AUDIT_PANEL) -> AuditList:
        if self.audit is None:
            return AuditList(entries=self._recent[-n:])
        return AuditList(entries=[audit_entry(r) for r in self.audit.last(n)])

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


def cpu_gate(users: Path | None, state: StateStore) -> Gate:
    """The gate of a CPU started from the command line: reading ``users`` (None: the
    demo), auditing into the run's state file ``state`` (each row committed with the scan's
    state by its writer). A users file that is missing or cannot be read raises
    ``UsersError`` here, at start."""
    users_file = UsersFile(users) if users is not None else None
    if users_file is not None:
        if not users_file.path.is_file():
            raise UsersError(f"{users_file.path}: no such users file (s7graph users add ...)")
        users_file.load()
    return Gate(Authenticator(users_file), AuditStore(state.path, state=state))
