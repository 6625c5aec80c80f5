"""Which program a state file belongs to (docs/state-file.md, "Whose state it is").

A run records its program in the file's ``meta`` — ``program_kind`` (``chart``, ``scl``:
an S7-SCL program, ``python``: a Python program) and ``program_source``, the name of the
file it was run from (its name only: a program moved to another folder with its state
file is the same program) — when it takes the file. A file recording another program is
refused (``foreign``): a chart warm-restarting from an S7-SCL program's memory image and
DBs would run on data that is not its own. A changed version of the same program (same
kind, same file name) is not another program: its state is carried over as before.

A file written before the program was recorded is judged by what it holds: a chart's own
instance DB is a GRAPH FB's (fingerprint ``chart:``), so a file holding a state without
one is not a chart's, and one holding one is not a program's without GRAPH FBs. What is
taken is stamped with the program when it is opened for writing.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import PurePath
from typing import Final

__all__ = [
    "CHART",
    "KINDS",
    "KIND_KEY",
    "SOURCE_KEY",
    "Program",
    "foreign",
    "malformed",
    "recorded",
    "way_out",
]

KINDS: Final = {
    "chart": "the chart",
    "scl": "the S7-SCL program",
    "python": "the Python program",
    "program": "the program",
}
"""The kinds of program a state file records, in words."""
_SUFFIXES: Final = {".s7g": "chart", ".scl": "scl", ".py": "python"}
KIND_KEY: Final = "program_kind"
SOURCE_KEY: Final = "program_source"
CHART: Final = "chart:"
"""The fingerprint prefix of a GRAPH FB's instance row (``sequencer/change/carry.py``)."""


@dataclass(frozen=True, slots=True)
class Program:
    """A program a state file belongs to: its kind (a key of ``KINDS``) and the name of its
    source file."""

    kind: str
    source: str

    @classmethod
    def of(cls, path: PurePath) -> Program:
        """The program run from ``path``, its kind by the file's suffix (``program`` for a
        suffix a loader plugged in)."""
        return cls(_SUFFIXES.get(path.suffix.lower(), "program"), path.name)

    def __str__(self) -> str:
        return f"{KINDS.get(self.kind, 'the program')} {self.source}"


def malformed(kind: str | None, source: str | None) -> str | None:
    """The problem of a recorded identity this code never writes (None: fine): a kind not
    in ``KINDS``, a source that is not a file's name, one without the other."""
    if kind is None and source is None:
        return None
    if kind not in KINDS:
        return f"malformed meta {KIND_KEY!r}: {(kind or '')[:40]!r}"
    if not source or "/" in source or "\0" in source or len(source) > 255:
        return f"malformed meta {SOURCE_KEY!r}: {(source or '')[:40]!r}"
    return None


def recorded(meta: Callable[[str], str | None]) -> Program | None:
    """The program a file records (None: a file from before it recorded one); call
    ``malformed`` first."""
    kind, source = meta(KIND_KEY), meta(SOURCE_KEY)
    if kind is None or source is None:
        return None
    return Program(kind, source)


def foreign(
    mine: Program,
    saved: Program | None,
    *,
    holds_state: bool,
    charts: Sequence[str],
    has_chart: bool,
) -> str | None:
    """Why a file is another program's than ``mine`` (None: it is not known to be):
    ``saved`` the program it records; for a file that records none, whether it holds a
    state, ``charts`` the GRAPH FB instances it holds (``DB1 FB1 'Seq'``), and whether
    ``mine`` has a GRAPH FB of its own."""
    if saved is not None:
        if saved == mine:
            return None
        return f"the state of another program: {saved}'s, not {mine}'s"
    older = "written by an s7graph that did not record its program, and"
    if mine.kind == "chart" and holds_state and not charts:
        return (
            f"{older} it holds no chart's sequencer (no GRAPH FB's instance DB): another "
            f"program's (an S7-SCL or Python program of the same name?), not {mine}'s"
        )
    if mine.kind != "chart" and charts and not has_chart:
        return f"{older} it holds a chart's sequencer ({charts[0]}): a chart's, not {mine}'s"
    return None


def way_out(path: PurePath, mine: Program) -> str:
    """What to do about a file that is another program's."""
    return (
        f"run {mine.source} with a state file of its own (--state FILE), or start anew with "
        f"--fresh (keeps this file, the other program's state, as {path}.old-N)"
    )
