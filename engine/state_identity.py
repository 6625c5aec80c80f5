"""Which program a state file belongs to (docs/state-file.md, "Whose state it is").

A run records its program in the file's ``meta`` — ``program_kind`` (``chart``, ``scl``:
an S7-SCL program, ``python``: a Python program) and ``program_source``, the name of the
file it was run from (its name only: a program moved to another folder with its state
file is the same program) — when it takes the file. A file recording another program is
refused (``foreign``): a chart warm-restarting from an S7-SCL program's memory image and
DBs would run on data that is not its own. A changed version of the same program (same
kind, same file name) is not another program: its state is carried over as before. Nor
is a renamed source of the same kind the file's content recognises (``recognised``: every
FB instance DB it holds is the program's, by DB number, FB number and FB name; for a
chart, a GRAPH FB's among them): carried over the same way, said in a note
(``renamed``), and recorded under its new name once taken. A run of a renamed source
without a state file of its own names such a file beside it (``beside``), never taking it.

A file written before the program was recorded is judged by what it holds: a chart's own
instance DB is a GRAPH FB's (fingerprint ``chart:``), so a file holding a state without
one is not a chart's, and one holding one is not a program's without GRAPH FBs. What is
taken is stamped with the program when it is opened for writing.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Sequence
from dataclasses import dataclass
from pathlib import PurePath
from typing import Final, NamedTuple

__all__ = [
    "CHART",
    "KINDS",
    "KIND_KEY",
    "SOURCE_KEY",
    "Evidence",
    "Held",
    "Program",
    "beside",
    "foreign",
    "malformed",
    "recognised",
    "recorded",
    "renamed",
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


class Held(NamedTuple):
    """An instance DB a state file holds: its number, its FB's label and name, and whether
    the FB is a GRAPH FB (fingerprint ``chart:``)."""

    number: int
    label: str
    name: str
    chart: bool

    def __str__(self) -> str:
        return f"DB{self.number} {self.label} {self.name!r}"


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


@dataclass(frozen=True, slots=True)
class Evidence:
    """What a file is judged by for a program to run (``foreign``, ``beside``): what the
    file records and holds — ``saved`` the program it records (None: none), ``holds_state``
    whether it holds a state, ``held`` its instance DBs — and what the program has: ``own``
    its instance DBs (DB number, FB label, FB name), ``has_chart`` whether it has a GRAPH
    FB. Gathered once from the file and the CPU (``engine/persistence.py``)."""

    saved: Program | None
    holds_state: bool
    held: tuple[Held, ...]
    own: frozenset[tuple[int, str, str]]
    has_chart: bool


def foreign(mine: Program, seen: Evidence) -> str | None:
    """Why a file is another program's than ``mine`` (None: it is not known to be). A file
    recording another source of the same kind is ``mine``'s when ``recognised``; one that
    records none is judged by whether it holds a state and a GRAPH FB's instance DB."""
    saved = seen.saved
    charts = [str(h) for h in seen.held if h.chart]
    if saved is not None:
        if saved == mine or (saved.kind == mine.kind and recognised(mine, seen.held, seen.own)):
            return None
        return f"the state of another program: {saved}'s, not {mine}'s"
    older = "written by an s7graph that did not record its program, and"
    if mine.kind == "chart" and seen.holds_state and not charts:
        return (
            f"{older} it holds no chart's sequencer (no GRAPH FB's instance DB): another "
            f"program's (an S7-SCL or Python program of the same name?), not {mine}'s"
        )
    if mine.kind != "chart" and charts and not seen.has_chart:
        return f"{older} it holds a chart's sequencer ({charts[0]}): a chart's, not {mine}'s"
    return None


def beside(mine: Program, seen: Evidence) -> str | None:
    """Whose state a file holds that ``mine`` would carry over given it (``foreign`` finds
    nothing against it) and whose instance DBs are ``mine``'s (``recognised``): a file of
    ``mine`` under another name, or of a renamed source; None for any other file."""
    if foreign(mine, seen) is not None or not recognised(mine, seen.held, seen.own):
        return None
    return (
        f"the state of {seen.saved}"
        if seen.saved is not None
        else "a state that records no program"
    )


def recognised(mine: Program, held: Sequence[Held], own: Collection[tuple[int, str, str]]) -> bool:
    """Whether a file holds recognisably ``mine``'s state though it records another source
    of its kind (a renamed file): it holds FB instance DBs (a system block's aside: any
    program may call one), every one ``mine`` has at the same DB number with the same FB
    number and name, and for a chart a GRAPH FB's among them. A program without instance
    DBs is never recognised."""
    rows = [h for h in held if not h.label.startswith("SFB")]
    if not rows or any((h.number, h.label, h.name) not in own for h in rows):
        return False
    return mine.kind != "chart" or any(h.chart for h in rows)


def renamed(mine: Program, saved: Program | None) -> str | None:
    """The note of a file taken though it records another source (``recognised``); None
    when it records ``mine`` or nothing."""
    if saved is None or saved == mine:
        return None
    return (
        f"the file was the state of {saved} and now records {mine} (a renamed source: "
        "its instance DBs are this program's)"
    )


def way_out(path: PurePath, mine: Program) -> str:
    """What to do about a file that is another program's."""
    return (
        f"run {mine.source} with a state file of its own (--state FILE), or start anew with "
        f"--fresh (keeps this file, the other program's state, as {path}.old-N)"
    )
