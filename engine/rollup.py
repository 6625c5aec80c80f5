"""Bounded logs: the oldest rows of an append-only table summed into a summary table.

The alarm log (``alarms``: every message event) and the audit (``audit``,
``web/access/audit.py``) are append-only, and would grow without end: a flapping sensor or
a flood of commands would fill the disk, and a full disk stops the CPU. When a table holds
more than its limit, its oldest rows are summed into its summary table — one row per day
(UTC) and the columns that say what happened, with a count and the first and last time —
and deleted, in the very transaction that added the rows: a count is never lost, only its
detail (docs/state-file.md, "Bounded logs").

Rolled down to :func:`low_water` (a tenth below the limit), so a roll-up, which reads the
rows it keeps once, comes once every tenth of the limit, not with every row.
"""

from __future__ import annotations

import sqlite3
from collections.abc import Callable, Mapping
from typing import Final, TypeAlias

__all__ = [
    "ALARM_ROWS",
    "ALARM_SUMMARY",
    "Job",
    "day_of",
    "low_water",
    "roll",
    "roll_alarms",
]

Job: TypeAlias = Callable[[sqlite3.Connection], None]
"""Work run in the state writer's transaction (``StateStore.queue``)."""

ALARM_ROWS: Final = 100_000
"""The alarm log's limit (rows); older events are summed into ``alarm_summary``."""
ALARM_SUMMARY: Final = """
CREATE TABLE IF NOT EXISTS alarm_summary (
    day TEXT NOT NULL, key TEXT NOT NULL, state TEXT NOT NULL, count INTEGER NOT NULL,
    first_ns INTEGER NOT NULL, last_ns INTEGER NOT NULL, PRIMARY KEY (day, key, state));
"""


def day_of(column: str) -> str:
    """SQL for the UTC day (``2026-11-22``) of a wall-clock ns column."""
    return f"ifnull(date({column} / 1000000000, 'unixepoch'), '?')"


def low_water(limit: int) -> int:
    """The rows a roll-up keeps of a table over ``limit``: a tenth fewer (at least one)."""
    return max(limit - max(limit // 10, 1), 0)


def roll(
    db: sqlite3.Connection,
    table: str,
    summary: str,
    keys: Mapping[str, str],
    *,
    count: str,
    where: str,
    params: tuple[object, ...],
) -> int:
    """Sum the rows of ``table`` matching ``where`` into ``summary`` — grouped by ``keys``
    (summary column → SQL over the row), adding ``count`` (SQL) to the count and widening
    first/last time — and delete them; how many were deleted. Call inside a transaction."""
    columns = ", ".join(keys)
    groups = ", ".join(str(i) for i in range(1, len(keys) + 1))
    db.execute(
        f"INSERT INTO {summary} ({columns}, count, first_ns, last_ns) "
        f"SELECT {', '.join(keys.values())}, SUM({count}), MIN(ifnull(t_ns, 0)), "
        f"MAX(ifnull(t_ns, 0)) FROM {table} WHERE {where} GROUP BY {groups} "
        f"ON CONFLICT ({columns}) DO UPDATE SET count = count + excluded.count, "
        "first_ns = min(first_ns, excluded.first_ns), last_ns = max(last_ns, excluded.last_ns)",
        params,
    )
    return int(db.execute(f"DELETE FROM {table} WHERE {where}", params).rowcount)


def roll_alarms(db: sqlite3.Connection, keep: int) -> int:
    """Sum all but the newest ``keep`` message events into ``alarm_summary`` (per day,
    message and came/went/acknowledged); how many rows were rolled."""
    oldest_kept = db.execute(
        "SELECT id FROM alarms ORDER BY id DESC LIMIT 1 OFFSET ?", (max(keep, 0),)
    ).fetchone()
    if oldest_kept is None:
        return 0
    keys = {"day": day_of("t_ns"), "key": "ifnull(key, '')", "state": "ifnull(state, '')"}
    return roll(
        db, "alarms", "alarm_summary", keys, count="1", where="id <= ?", params=(oldest_kept[0],)
    )
