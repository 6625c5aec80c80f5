"""``s7graph audit --state FILE [--since WHEN] [--summary]``: the audit trail of a CPU's
state file.

``--since`` takes a time (``2026-11-22``, ``2026-11-22T08:30``, ``08:30`` today) or an age
(``90s``, ``15m``, ``2h``, ``3d``). ``--summary`` prints the rows the bounded table rolled
into its summary instead (per UTC day, user, op and outcome: count, first and last time).
"""

from __future__ import annotations

import datetime as dt
import re
import sys
import time
from pathlib import Path

from s7graph.engine.persistence import not_a_state_file
from s7graph.web.access.audit import (
    UnreadableAudit,
    lines,
    read_audit,
    read_summary,
    summary_lines,
)

__all__ = ["audit_command", "parse_since"]

_AGE = re.compile(r"^(\d+(?:\.\d+)?)([smhd])$")
_UNIT = {"s": 1, "m": 60, "h": 3600, "d": 86400}


def parse_since(text: str, now: float | None = None) -> int:
    """Wall-clock ns of ``--since``; ValueError naming the accepted forms."""
    now = time.time() if now is None else now
    age = _AGE.match(text.strip())
    if age:  # an age past the epoch: every row
        return _ns(now - float(age[1]) * _UNIT[age[2]])
    try:
        if re.fullmatch(r"\d{1,2}:\d{2}(:\d{2})?", text.strip()):
            today = dt.datetime.fromtimestamp(now).date().isoformat()
            when = dt.datetime.fromisoformat(f"{today}T{text.strip()}")
        else:
            when = dt.datetime.fromisoformat(text.strip())
    except ValueError:
        raise ValueError(
            f"--since {text!r}: give a time (2026-11-22T08:30, 08:30) or an age (15m, 2h, 3d)"
        ) from None
    try:
        return _ns(when.timestamp())
    except (OverflowError, OSError, ValueError):  # a time the system clock cannot hold
        raise ValueError(f"--since {text!r}: a time from 1970 on") from None


def _ns(seconds: float) -> int:
    """``seconds`` since the epoch as ns within what SQLite's integers hold (1970 to 2262)."""
    return min(max(0, int(seconds * 1e9)), 2**63 - 1)


def _refused(state: Path) -> str:
    """Why ``state`` cannot be read as a state file before SQLite reads it, as ``s7graph
    run`` says it (``engine.persistence.not_a_state_file``, with its way out but a run's
    ``--fresh``), or "": a file that is not there is ``no such state file``."""
    refused = not_a_state_file(state)
    if refused is not None:
        return f"{refused}; {refused.way_out}" if refused.way_out else str(refused)
    return "" if state.exists() else f"{state}: no such state file"


def audit_command(state: Path, since: str | None, *, summary: bool = False) -> int:
    """Print the audit rows (oldest first), or with ``summary`` the summary's; exit 2 for a
    missing file, a bad --since, or a file whose audit cannot be read (one line naming it
    and what was wrong)."""
    problem = _refused(state)
    if problem:
        print(f"s7graph: error: {problem}", file=sys.stderr)
        return 2
    try:
        if summary:
            if since:
                raise ValueError("--summary takes no --since: it prints every day it holds")
            text = summary_lines(read_summary(state))
        else:
            since_ns = parse_since(since) if since else None
            text = lines(read_audit(state, since_ns=since_ns))
    except (UnreadableAudit, ValueError) as exc:
        print(f"s7graph: error: {exc}", file=sys.stderr)
        return 2
    for line in text:
        print(line)
    return 0
