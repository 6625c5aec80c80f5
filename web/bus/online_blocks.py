"""The S7-SCL blocks of an online change (docs/online-change.md, "S7-SCL blocks"): the
sources a download brings, their files, and their swap at the chart's scan boundary.

A CPU that runs a chart with ``--blocks A.scl B.scl`` takes changed versions of those
sources with a download (``blocks``: file name → text). :class:`BlockFiles` keeps the text
each file holds now: a download's sources replace the files of the same name (a name the
CPU does not run is refused), the others are compiled with them as they are, in the CPU's
order. A download writes the changed files (each old one kept as a numbered backup, as the
chart's) and puts them back when the swap is refused.

:func:`swap_blocks`, at the scan boundary before the chart's swap, refuses a change whose
instance DBs cannot carry their values (``web.harness.scl_reload.refusals``) and otherwise
downloads the new blocks (``ChartSession.reload_blocks``); it returns the notes and a
function that puts the CPU's program back as it was — blocks, OBs, instance DBs and DBs —
for a chart swap that is refused after it. Nothing here compiles: the blocks come compiled.

:func:`chart_refusal` is what the chart's swap would refuse (``sequencer.change.online.
refusal``) once those blocks are in: what a download's preview says first, and the download
checks before it writes a file. :func:`held_interfaces` are the interfaces of the blocks
the CPU holds, which a download's chart reads the FBs' variables of by name when it brings
no sources; :class:`HeldInterfaces` keeps them, built again only after the blocks change.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from s7graph.engine.blocks import DB
from s7graph.engine.errors import BlockError, S7Error
from s7graph.sequencer.change.online import Needs, refusal
from s7graph.sequencer.checks.interfaces import ProgramBlocks, program_blocks
from s7graph.steps.operands import area_buffer
from s7graph.web.harness.project import ProjectError, restore_backup, write_chart
from s7graph.web.harness.scl import SclSources
from s7graph.web.harness.scl_reload import refusals
from s7graph.web.harness.session import ChartSession

__all__ = [
    "BlockFiles",
    "BlocksRefused",
    "HeldInterfaces",
    "chart_refusal",
    "held_interfaces",
    "swap_blocks",
]


class BlocksRefused(S7Error):
    """S7-SCL blocks a download cannot bring: the reason."""


class BlockFiles:
    """The S7-SCL source files ``paths`` the chart's calls reach, in the CPU's order, with
    the text each holds now (read at the start; what the CPU runs)."""

    def __init__(self, paths: Sequence[Path]) -> None:
        self.paths = [Path(p) for p in paths]
        self.texts: dict[str, str] = {}
        for p in self.paths:
            with contextlib.suppress(OSError, UnicodeDecodeError):
                self.texts[p.name] = p.read_text(encoding="utf-8")

    def merged(self, sent: Mapping[str, str]) -> list[tuple[str, str]]:
        """Every source as it would be after the download of ``sent`` (file, text), in the
        CPU's order; ``BlocksRefused`` for a file the CPU does not run."""
        names = [p.name for p in self.paths]
        unknown = sorted(set(sent) - set(names))
        if unknown:
            runs = ", ".join(names) or "no S7-SCL blocks (run without --blocks)"
            raise BlocksRefused(
                f"the CPU runs no S7-SCL source {', '.join(unknown)}: it runs {runs}; a "
                "download brings changed versions of those files"
            )
        missing = [n for n in names if n not in sent and n not in self.texts]
        if missing:
            raise BlocksRefused(f"cannot read the CPU's source {missing[0]}: send it too")
        return [(str(p), sent.get(p.name, self.texts.get(p.name, ""))) for p in self.paths]

    def changes(self, sent: Mapping[str, str]) -> dict[str, str]:
        """The sources of ``sent`` whose text differs from the CPU's."""
        return {n: t for n, t in sent.items() if self.texts.get(n) != t}

    def write(self, texts: Mapping[str, str]) -> list[tuple[Path, Path | None]]:
        """Write ``texts`` into their files (each flushed to the disk, the old one kept as a
        numbered backup); the files written with their backups. ``BlocksRefused`` when one
        cannot be written (the ones before it put back)."""
        done: list[tuple[Path, Path | None]] = []
        for p in self.paths:
            if p.name not in texts:
                continue
            try:
                done.append((p, write_chart(p, texts[p.name])))
            except ProjectError as exc:
                self.restore(done)
                raise BlocksRefused(f"{exc}; the CPU keeps the old blocks") from None
        return done

    def restore(self, written: list[tuple[Path, Path | None]]) -> str:
        """Put the files ``written`` back from their backups; what could not be."""
        problems = []
        for path, backup in written:
            try:
                restore_backup(path, backup)
            except ProjectError as exc:
                problems.append(str(exc))
        return "; ".join(problems)

    def adopt(self, texts: Mapping[str, str]) -> None:
        """The CPU runs ``texts`` now."""
        self.texts.update(texts)


def swap_blocks(session: ChartSession, new: SclSources) -> tuple[list[str], Callable[[], None]]:
    """Download ``new`` into the session's CPU in place of its S7-SCL sources (between two
    scans): the notes of what the DBs dropped or start afresh, and the way back.
    ``BlocksRefused`` (nothing changed) when an instance DB cannot carry its values or the
    blocks do not load."""
    refused = refusals(session.cpu, new)
    if refused:
        raise BlocksRefused("; ".join(refused))
    back = _program_of(session)
    try:
        notes = session.reload_blocks(new)
    except S7Error as exc:
        back()
        raise BlocksRefused(f"the blocks cannot be loaded: {exc}") from None
    return notes, back


def _program_of(session: ChartSession) -> Callable[[], None]:
    """A function that puts the CPU's program — blocks, OBs, instance DBs, DBs — and the
    session's sources back as they are now (the dicts' contents, the objects themselves:
    a reload makes new ones and never changes these)."""
    cpu: Any = session.cpu
    held = [
        (cpu.blocks, dict(cpu.blocks)),
        (cpu.obs, dict(cpu.obs)),
        (cpu.instance_dbs, dict(cpu.instance_dbs)),
        (cpu.mem.dbs, dict(cpu.mem.dbs)),
    ]
    blocks, types = list(session.blocks), session.dbvars.types

    def back() -> None:
        for live, was in held:
            live.clear()
            live.update(was)
        session.blocks, session.dbvars.types = blocks, types

    return back


def held_interfaces(session: ChartSession) -> ProgramBlocks | None:
    """The interfaces of the user blocks the session's CPU holds (its ``blocks``: S7-SCL
    sources, a program of blocks) as the chart's compile reads them, None without any."""
    return _interfaces(tuple(session.blocks))


def _interfaces(programs: tuple[Any, ...]) -> ProgramBlocks | None:
    if not programs:
        return None
    blocks = [b for p in programs for b in p.blocks]
    instances = {n: fb for p in programs for n, fb in getattr(p, "instances", {}).items()}
    files = [str(f) for p in programs for f in getattr(p, "files", ())]
    return program_blocks(blocks, instances, sources=", ".join(files))


class HeldInterfaces:
    """:func:`held_interfaces` of one session, kept: built again only when the session
    holds other programs than the ones they were built from (a block download, its undo,
    a refused swap put back; a reload makes new program objects and never changes one),
    not for every download that brings no sources. ``builds`` counts the builds."""

    def __init__(self, session: ChartSession) -> None:
        self._session = session
        self._kept: tuple[tuple[Any, ...], ProgramBlocks | None] = ((), None)
        self.builds = 0

    def __call__(self) -> ProgramBlocks | None:
        programs = tuple(self._session.blocks)  # one read: a swap may replace the list
        of, made = self._kept
        if len(of) != len(programs) or any(a is not b for a, b in zip(of, programs, strict=True)):
            made = _interfaces(programs)
            self._kept = (programs, made)  # one assignment: read whole from another thread
            self.builds += 1
        return made


def chart_refusal(session: ChartSession, needs: Needs, new: SclSources | None) -> str | None:
    """Why the swap of a chart that needs ``needs`` would be refused in the session's CPU
    once the S7-SCL sources ``new`` (None: none) are in — the swap's own reason — or None.
    Read from a thread beside the scan: the CPU's tables changing meanwhile is no refusal
    (the scan boundary checks again)."""
    cpu: Any = session.cpu
    find, mem = None, None
    if new is not None:
        find, mem = _after(cpu, new)
    try:
        return refusal(cpu, session.graph.cc.chart, needs, find=find, mem=mem)
    except RuntimeError:  # a table changed while read
        return None


def _after(cpu: Any, new: SclSources) -> tuple[Callable[[str], Any], Any]:
    """The blocks and the memory of ``cpu`` as loading ``new`` leaves them (its blocks
    loaded over the CPU's, its global DBs in memory), without loading it."""
    mine: dict[str, Any] = {}
    for b in new.blocks:
        mine[b.label.upper()] = b
        name = getattr(b, "name", "")
        if name:
            mine.setdefault(name.upper(), b)

    def find(label: str) -> Any:
        block = mine.get(label.upper())
        if block is not None:
            return block
        try:
            return cpu.block(label)
        except BlockError:
            return None

    dbs = {b.number: b.size for b in new.blocks if isinstance(b, DB)}
    return find, _MemAfter(cpu.mem, dbs)


class _MemAfter:
    """``mem`` with the global DBs of new sources (number → size) as they would be."""

    def __init__(self, mem: Any, dbs: dict[int, int]) -> None:
        self._mem = mem
        self._dbs = dbs
        self.timers, self.counters = mem.timers, mem.counters

    def area_bytes(self, area: str, db: int | None = None) -> bytearray:
        if area == "DB" and db in self._dbs:
            return bytearray(self._dbs[db])
        return area_buffer(self._mem, area, db)
