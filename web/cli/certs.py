"""``s7graph certs init DIR`` and ``s7graph certs issue DIR NAME --kind KIND``: a plant's
CA and its nodes' certificates for the bus's mutual TLS (``web.access.certs`` makes them;
the common name ``<kind>.<name>`` is the node's identity on the bus)."""

from __future__ import annotations

import sys
from collections.abc import Sequence
from pathlib import Path

from s7graph.web.access.certs import CertsError, common_name, init_ca, issue

__all__ = ["certs_init", "certs_issue"]


def _fail(message: str) -> int:
    print(f"s7graph: error: {message}", file=sys.stderr)
    return 2


def _not_a_folder(directory: Path) -> str:
    """Why the certificates cannot go into ``directory``: a file is there, or ""."""
    if directory.exists() and not directory.is_dir():
        return f"{directory}: a file, not a folder; give the folder of the plant's certificates"
    return ""


def certs_init(directory: Path, *, force: bool = False) -> int:
    """Make the CA in ``directory``; 0, or 2 with the reason."""
    if problem := _not_a_folder(directory):
        return _fail(problem)
    try:
        made = init_ca(directory, force=force)
    except CertsError as exc:
        return _fail(str(exc))
    print(f"s7graph: CA {made.cert} (copy it to every node) and its key {made.key} (keep it here)")
    return 0


def certs_issue(
    directory: Path, name: str, kind: str, hosts: Sequence[str] = (), *, force: bool = False
) -> int:
    """Issue node ``<kind>.<name>``'s certificate with the CA of ``directory``; 0, or 2."""
    if problem := _not_a_folder(directory):
        return _fail(problem)
    try:
        made = issue(directory, name, kind, hosts, force=force)
        cn = common_name(kind, name)
    except CertsError as exc:
        return _fail(str(exc))
    print(f"s7graph: {cn}: {made.cert} and its key {made.key} (copy both to that node only)")
    return 0
