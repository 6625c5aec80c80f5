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

from s7graph.web.commands import COMMAND_TYPES, op_of

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


COMMANDS: Final[tuple[CommandInfo, ...]] = tuple(
    CommandInfo(op_of(c), c.role, c.pin, c.does, c.example) for c in COMMAND_TYPES
)
"""Read from the command vocabulary (``web.commands``): each op's struct says its role."""
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
    reads = "chart, source, state, status, alarms, history, audit, project, diag, watch"
    rows.append(f"| *read* ({reads}) | | | | ✓ | ✓ | ✓ |")
    return "\n".join(rows) + "\n"
