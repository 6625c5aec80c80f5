"""The one role table: which commands each role may send (the table is the documentation).

``COMMANDS`` lists every operation a page, a shell or a bus client can ask a CPU for, with
the lowest role allowed to, the S7-GRAPH pin it acts as and what it does. ``ROLES`` orders
the roles, each including the rights of those before it; :func:`allowed` is the only
question the CPU asks (at the scan boundary); :func:`role_table_markdown` renders the table
for docs/security.md and docs/bus.md (a test keeps both equal to it).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Final

__all__ = [
    "COMMANDS",
    "NOT_AVAILABLE",
    "ROLES",
    "CommandInfo",
    "allowed",
    "lowest_role",
    "ops_of",
    "role_table_markdown",
]

ROLES: Final = ("viewer", "operator", "engineer")


@dataclass(frozen=True, slots=True)
class CommandInfo:
    """One operation: its name on the bus, the lowest role allowed, the pin, what it does."""

    op: str
    role: str
    pin: str
    does: str
    args: str = ""


COMMANDS: Final[tuple[CommandInfo, ...]] = (
    CommandInfo("ack", "operator", "ACK_EF", "acknowledge every supervision fault of the FB"),
    CommandInfo("ack_step", "operator", "ACK_S", "acknowledge one step's fault", '{"step": n}'),
    CommandInfo(
        "ack_msg", "operator", "", "acknowledge one message of the alarm list", '{"msg_id": id}'
    ),
    CommandInfo("mode", "operator", "SW_AUTO/MAN/TAP/TOP", "switch the mode", '{"mode": "MAN"}'),
    CommandInfo("init", "operator", "INIT_SQ", "activate the initial steps"),
    CommandInfo("off", "operator", "OFF_SQ", "deactivate every step"),
    CommandInfo("halt", "operator", "HALT_SQ", "halt / resume the sequencer", '{"on": true}'),
    CommandInfo("t_push", "operator", "T_PUSH", "switch a ready transition (TAP, TOP)"),
    CommandInfo("step_on", "operator", "S_ON", "activate a step (MAN)", '{"step": n}'),
    CommandInfo("step_off", "operator", "S_OFF", "deactivate a step (MAN)", '{"step": n}'),
    CommandInfo("en_il", "engineer", "EN_IL", "enable / disable interlocks", '{"on": false}'),
    CommandInfo("en_sv", "engineer", "EN_SV", "enable / disable supervisions", '{"on": false}'),
    CommandInfo(
        "force",
        "engineer",
        "",
        "force an input, output or flag (I, Q, M) until unforced: value null unforces it, "
        '`{"all": true}` unforces every job',
        '{"address": "I0.3", "value": true}',
    ),
    CommandInfo(
        "download",
        "engineer",
        "",
        "download a changed chart into the running FB (online change)",
        '{"source": "...", "base": 1, "removed": "keep", "preview": true}',
    ),
    CommandInfo(
        "undo_download",
        "engineer",
        "",
        "put the chart before the last download back",
        '{"base": 2, "removed": "keep", "preview": true}',
    ),
    CommandInfo(
        "save",
        "engineer",
        "",
        "write a chart into the CPU's project directory",
        '{"file": "x.s7g", "source": "..."}',
    ),
    CommandInfo(
        "open",
        "engineer",
        "",
        "read a chart or importable file of the project directory",
        '{"file": "x.xml"}',
    ),
    CommandInfo("stop", "engineer", "", "the CPU's RUN/STOP switch to STOP (outputs to 0)"),
    CommandInfo(
        "start", "engineer", "", "the switch to RUN: the CPU's configured restart (`--restart`)"
    ),
)
# Ops the role table grants but this CPU does not carry out yet: refused after the role check.
NOT_AVAILABLE: Final[frozenset[str]] = frozenset()

_RANK: Final = {role: i for i, role in enumerate(ROLES)}
_LOWEST: Final = {c.op: c.role for c in COMMANDS}


def lowest_role(op: str) -> str | None:
    """The lowest role allowed ``op``; None for an unknown op."""
    return _LOWEST.get(op)


def allowed(role: str, op: str) -> bool:
    """Whether ``role`` may send ``op`` (an unknown role or op: never)."""
    need = _LOWEST.get(op)
    return need is not None and role in _RANK and _RANK[role] >= _RANK[need]


def ops_of(role: str) -> tuple[str, ...]:
    """Every op ``role`` may send, in table order."""
    return tuple(c.op for c in COMMANDS if allowed(role, c.op))


def role_table_markdown() -> str:
    """The role table as Markdown: one row per op, a ✓ per role allowed."""
    head = "| op | args | pin | does | " + " | ".join(ROLES) + " |"
    rows = [head, "|" + "---|" * (4 + len(ROLES))]
    for c in COMMANDS:
        marks = " | ".join("✓" if allowed(r, c.op) else "" for r in ROLES)
        args = f"`{c.args}`" if c.args else ""
        pin = f"`{c.pin}`" if c.pin else ""
        rows.append(f"| `{c.op}` | {args} | {pin} | {c.does} | {marks} |")
    reads = "chart, source, state, status, alarms, history, audit, project"
    rows.append(f"| *read* ({reads}) | | | | ✓ | ✓ | ✓ |")
    return "\n".join(rows) + "\n"
