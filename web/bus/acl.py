"""Who may do what on the bus: zenoh's access control, generated from one table.

The rule: only a CPU's own identity may serve and publish on that CPU's keys
(``s7graph/<cpu>/**``: declare queryables, put, reply, liveliness tokens — login, cmd,
chart, state, status, delta, alarms, audit, alive, …); every other node may only ask
(query, subscribe, liveliness subscriptions and queries) on ``s7graph/**``; anything may
go out to everyone on ``s7graph/**``; everything else is refused by zenoh itself
(``default_permission: deny``). A CPU's identity is the common name of its certificate or
its usrpwd user name, ``cpu.<name>`` (``web.access.certs``).

:data:`GRANTS` is that table; :func:`acl_config` turns it into the ``access_control``
section of the zenoh config of a node that others connect to — the CPU (for itself) and
``s7graph router`` (for the CPUs named with ``--cpu``) — and :func:`grants_markdown` into
the table of docs/security.md (a test keeps the two equal).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Final

from s7graph.web.bus.keys import ROOT

__all__ = ["ALL_MESSAGES", "ASK_MESSAGES", "GRANTS", "Grant", "acl_config", "grants_markdown"]

ALL_MESSAGES: Final = (
    "put",
    "delete",
    "declare_subscriber",
    "query",
    "reply",
    "declare_queryable",
    "liveliness_token",
    "declare_liveliness_subscriber",
    "liveliness_query",
)
"""Every kind of message zenoh's access control tells apart."""
ASK_MESSAGES: Final = (
    "query",
    "declare_subscriber",
    "declare_liveliness_subscriber",
    "liveliness_query",
)
"""What a node that is not the CPU may send towards it: it asks and listens, never serves."""


@dataclass(frozen=True, slots=True)
class Grant:
    """One line of the table: ``who`` may send ``messages`` in ``flows`` on ``keys``
    (``{cpu}``: each CPU's name). ``who`` is ``"cpu"`` (the CPU's own identity) or
    ``"anyone"`` (every node, with or without credentials)."""

    who: str
    flows: tuple[str, ...]
    messages: tuple[str, ...]
    keys: str
    why: str


GRANTS: Final = (
    Grant(
        "cpu",
        ("ingress", "egress"),
        ALL_MESSAGES,
        f"{ROOT}/{{cpu}}/**",
        "serves and publishes its own keys, nobody else's",
    ),
    Grant(
        "anyone",
        ("ingress",),
        ASK_MESSAGES,
        f"{ROOT}/**",
        "asks and listens: logins, commands, reads, subscriptions",
    ),
    Grant(
        "anyone",
        ("egress",),
        ALL_MESSAGES,
        f"{ROOT}/**",
        "receives what the CPUs serve and publish",
    ),
)

_WHO = {"cpu": "the CPU (`cpu.<name>`: certificate or bus user)", "anyone": "every node"}


def _identity_subjects(cpu: str) -> list[dict[str, Any]]:
    """The subjects of CPU ``cpu``: its certificate's common name, or its usrpwd name
    (two subjects: zenoh combines the fields of one subject with *and*)."""
    name = f"cpu.{cpu}"
    return [
        {"id": f"{name} by certificate", "cert_common_names": [name]},
        {"id": f"{name} by user name", "usernames": [name]},
    ]


def acl_config(cpus: Sequence[str]) -> dict[str, Any]:
    """The zenoh ``access_control`` section giving each of ``cpus`` its own keys and every
    other node only :data:`ASK_MESSAGES` (the table :data:`GRANTS`); nothing else passes."""
    rules: list[dict[str, Any]] = []
    subjects: list[dict[str, Any]] = [{"id": "anyone"}]  # no field: every node matches
    policies: list[dict[str, Any]] = []
    anyone: list[str] = []
    own = {cpu: _identity_subjects(cpu) for cpu in dict.fromkeys(cpus)}
    for cpu_subjects in own.values():
        subjects.extend(cpu_subjects)
    for n, grant in enumerate(GRANTS):
        base = {
            "messages": list(grant.messages),
            "flows": list(grant.flows),
            "permission": "allow",
        }
        if grant.who == "anyone":
            rule_id = f"anyone {n}"
            rules.append({"id": rule_id, **base, "key_exprs": [grant.keys.format(cpu="*")]})
            anyone.append(rule_id)
            continue
        for cpu, cpu_subjects in own.items():
            rule_id = f"cpu.{cpu} {n}"
            rules.append({"id": rule_id, **base, "key_exprs": [grant.keys.format(cpu=cpu)]})
            policies.append({"rules": [rule_id], "subjects": [s["id"] for s in cpu_subjects]})
    policies.append({"rules": anyone, "subjects": ["anyone"]})
    return {
        "enabled": True,
        "default_permission": "deny",
        "rules": rules,
        "subjects": subjects,
        "policies": policies,
    }


def grants_markdown() -> str:
    """:data:`GRANTS` as the Markdown table of docs/security.md."""
    lines = ["| who | flow | messages | keys | why |", "|---|---|---|---|---|"]
    for g in GRANTS:
        messages = ", ".join(f"`{m}`" for m in g.messages)
        keys = g.keys.format(cpu="<name>")
        lines.append(f"| {_WHO[g.who]} | {', '.join(g.flows)} | {messages} | `{keys}` | {g.why} |")
    lines.append("| every node | ingress, egress | anything else | any other key | refused |")
    return "\n".join(lines)
