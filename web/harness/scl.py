"""S7-SCL sources on the command line: a program of SCL blocks (``sim``/``run``
``PROGRAM.scl``) or the blocks a chart calls (``--blocks BLOCKS.scl``), compiled in the
order given and loaded into one CPU (docs/scl.md, "On the command line").

Each source is compiled with the system blocks and the FBs and FCs of the sources before
it, so a later source calls the blocks of an earlier one (``--blocks`` sources come before
the program that calls them). A block, or a DB, written in two sources is refused, naming
both places. A source with errors ends the compilation there: its diagnostics are the
refusal (``SclLoadError``), the later sources not compiled — they would only report that
the blocks it defines are missing. Warnings are kept (``warnings``) for the command to
print.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple, Protocol

from s7graph import sfb
from s7graph.engine.blocks import DB, FB, FC, OB
from s7graph.engine.errors import BlockError, S7Error
from s7graph.engine.symbols import SymbolTable
from s7graph.engine.text import NotUtf8, decode_utf8
from s7graph.sequencer.checks.interfaces import ProgramBlocks, program_blocks
from s7graph.sequencer.fb import GraphFB, cold_restart_ob, startup_obs

if TYPE_CHECKING:  # the S7-SCL compiler is imported by the functions that compile or load
    from s7graph.steps.scl import SclProgram

__all__ = [
    "BlockText",
    "ChartBlocks",
    "Loadable",
    "SclLoadError",
    "SclSources",
    "block_texts",
    "chain_obs",
    "compile_sources",
    "compile_texts",
    "load_beside",
    "load_texts",
    "read_source",
    "scl_of",
]


class Loadable(Protocol):
    """Blocks a chart's session downloads beside it: ``SclSources``, an ``SclProgram``."""

    @property
    def blocks(self) -> Sequence[Any]: ...

    def load(self, cpu: Any) -> None: ...


class SclLoadError(S7Error):
    """Sources that do not compile; ``lines`` are their diagnostics, one a line."""

    def __init__(self, lines: list[str]) -> None:
        self.lines = lines
        super().__init__("\n".join(lines))


@dataclass
class SclSources:
    """The compiled sources, in the order given, with their warnings."""

    programs: list[SclProgram] = field(default_factory=list)
    files: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    texts: list[str] = field(default_factory=list)
    """Each source's text, as ``files`` (what ``block_texts`` cuts the blocks out of)."""

    def load(self, cpu: Any) -> None:
        """Download every source's blocks into ``cpu`` (its system blocks installed)."""
        for program in self.programs:
            program.load(cpu)

    @property
    def blocks(self) -> list[Any]:
        """Every engine block of the sources: OBs, FBs, FCs and global DBs."""
        return [b for program in self.programs for b in program.blocks]

    @property
    def types(self) -> dict[str, Any]:
        """The structures of the FBs' instances and the global DBs, by label."""
        out: dict[str, Any] = {}
        for program in self.programs:
            out.update(program.types)
        return out

    @property
    def instances(self) -> dict[int, str]:
        """The instance DBs the sources name: number → FB label."""
        out: dict[int, str] = {}
        for program in self.programs:
            out.update(program.instances)
        return out

    def interfaces(self) -> ProgramBlocks:
        """The FBs' and FCs' interfaces and the DBs, for checking a chart's calls."""
        return program_blocks(self.blocks, self.instances, sources=", ".join(self.files))


class BlockText(NamedTuple):
    """One block of a source as written: its label (``FB17``), its name, the file and the
    line it starts on, its text from its first line to its ``END_`` line."""

    label: str
    name: str
    file: str
    line: int
    text: str


_END = {"FB": "END_FUNCTION_BLOCK", "FC": "END_FUNCTION", "OB": "END_ORGANIZATION_BLOCK"}
_END["DB"] = "END_DATA_BLOCK"


def block_texts(sources: SclSources) -> list[BlockText]:
    """Every OB, FB, FC and DB of ``sources`` as written, in source order: the lines from
    where the block starts to its ``END_FUNCTION_BLOCK`` (…) line — to the next block's
    start, or the end of the file, if it has none."""
    out: list[BlockText] = []
    for program, file, text in zip(sources.programs, sources.files, sources.texts, strict=False):
        lines = text.splitlines()
        names = {b.label: str(getattr(b, "name", "") or "") for b in program.blocks}
        starts = sorted((loc.line, label) for label, loc in program.places.items())
        for k, (line, label) in enumerate(starts):
            stop = starts[k + 1][0] - 1 if k + 1 < len(starts) else len(lines)
            end = re.compile(rf"^\s*{_END.get(label[:2], 'END_')}\b", re.IGNORECASE)
            last = next((n for n in range(line - 1, stop) if end.match(lines[n])), stop - 1)
            body = "\n".join(lines[max(line - 1, 0) : last + 1])
            out.append(BlockText(label, names.get(label, ""), file, line, body))
    return out


def scl_of(blocks: Sequence[object]) -> SclSources | None:
    """The compiled S7-SCL sources among a session's ``blocks``, None if none."""
    return next((b for b in blocks if isinstance(b, SclSources)), None)


def read_source(path: Path) -> str:
    """The text of a source file; ``S7Error`` naming it when it cannot be read."""
    try:
        return decode_utf8(Path(path).read_bytes(), str(path))
    except OSError as exc:
        raise S7Error(f"cannot read {path}: {exc.strerror or exc}") from None
    except NotUtf8 as exc:
        raise S7Error(str(exc)) from None


def compile_sources(paths: Sequence[Path], symbols: SymbolTable | None = None) -> SclSources:
    """Compile ``paths`` in order (see the module docstring); ``SclLoadError`` with the
    diagnostics of the first source that does not compile, ``S7Error`` for one that cannot
    be read."""
    return compile_texts([(str(path), read_source(path)) for path in paths], symbols)


class ChartBlocks:
    """The ``--blocks`` sources ``paths`` as a chart's compile takes them — ``check``,
    ``sim``, ``run`` and ``export`` alike, and from their texts (:meth:`of_texts`) a
    download's compile and the page's editor: called with the symbol table (when the
    chart's compile calls it, with the chart's ``SYMBOLS`` in: ``web.harness.session.
    compile_model``), it compiles them as :func:`compile_sources` does (its errors too)
    and gives their interfaces; ``sources`` keeps what it compiled, ``warnings`` their
    warnings, which each command prints."""

    def __init__(self, paths: Sequence[Path]) -> None:
        self.paths = list(paths)
        self.sources: SclSources | None = None
        self._named: list[tuple[str, str]] | None = None
        self._portable: list[tuple[bytes, bytes]] | None = None

    @classmethod
    def of_texts(
        cls, named: Sequence[tuple[str, str]], *, portable: list[tuple[bytes, bytes]] | None = None
    ) -> ChartBlocks:
        """The sources ``named`` (file, text) as they are, not read from their files (a
        download's, not written yet; those the page gets with the chart); ``portable`` as
        :func:`compile_texts` takes it."""
        blocks = cls([Path(file) for file, _ in named])
        blocks._named, blocks._portable = list(named), portable
        return blocks

    def __call__(self, table: SymbolTable | None) -> ProgramBlocks:
        named = self._named
        if named is None:
            named = [(str(path), read_source(path)) for path in self.paths]
        self.sources = compile_texts(named, table, portable=self._portable)
        return self.sources.interfaces()

    @property
    def warnings(self) -> list[str]:
        """The warnings of the sources compiled last (none before)."""
        return list(self.sources.warnings) if self.sources is not None else []


def compile_texts(
    named: Sequence[tuple[str, str]],
    symbols: SymbolTable | None = None,
    *,
    portable: list[tuple[bytes, bytes]] | None = None,
) -> SclSources:
    """Compile the sources ``named`` (file, text) in order as :func:`compile_sources` does;
    with ``portable`` (a list), each program's bytes are appended to it for
    :func:`load_texts` in another process (``steps.scl.portable``)."""
    from s7graph.steps.scl import SclError, compile_scl, format_diagnostic
    from s7graph.steps.scl.portable import compile_portable

    out = SclSources()
    known: list[FB | FC] = list(sfb.SYSTEM_BLOCKS)
    places: dict[str, str] = {}
    of: dict[int, str] = {}
    for file, text in named:
        try:
            if portable is None:
                program = compile_scl(text, file, blocks=known, symbols=symbols)
            else:
                program, data = compile_portable(text, file, blocks=known, symbols=symbols)
                portable.append(data)
        except SclError as exc:
            raise SclLoadError([format_diagnostic(d) for d in exc.diagnostics]) from None
        except RecursionError:
            raise SclLoadError([f"{file}: the source nests too deeply to compile"]) from None
        _no_twice(program, file, places, of)
        out.programs.append(program)
        out.files.append(file)
        out.texts.append(text)
        out.warnings += [format_diagnostic(d) for d in program.diagnostics]
        known += [b for b in program.blocks if isinstance(b, FB | FC)]
    return out


def load_texts(
    files: Sequence[str],
    portable: Sequence[tuple[bytes, bytes]],
    warnings: Sequence[str] = (),
    texts: Sequence[str] = (),
) -> SclSources:
    """The sources :func:`compile_texts` compiled (``portable``: their bytes, in order) made
    in this process without compiling anything (``steps.scl.portable``); ``texts``: their
    texts, as ``files`` (the blocks' sources the CPU serves)."""
    from s7graph.steps.scl.portable import load_portable

    out = SclSources(files=list(files), warnings=list(warnings), texts=list(texts))
    known: list[FB | FC] = list(sfb.SYSTEM_BLOCKS)
    for data in portable:
        program = load_portable(data, known)
        out.programs.append(program)
        known += [b for b in program.blocks if isinstance(b, FB | FC)]
    return out


def _no_twice(program: SclProgram, file: str, places: dict[str, str], of: dict[int, str]) -> None:
    """Refuse a block or DB another source wrote already, or a DB another source makes the
    instance of another FB; note this source's."""
    lines: list[str] = []
    for label, loc in program.places.items():
        before = places.get(label)
        if before is not None:
            lines.append(f"{loc}: error: {label} is written in {before} too")
    for number, fb in sorted(program.instances.items()):
        held, where = of.get(number), places.get(f"DB{number}")
        if held is not None and held != fb:
            why = f"DB{number} is the instance DB of {held} in another source"
            lines.append(f"{file}: error: {why}")
        elif held is None and where is not None:
            why = f"DB{number}, the instance DB of {fb}, is a DB of {where}"
            lines.append(f"{file}: error: {why}")
    if lines:
        raise SclLoadError(lines)
    places.update((label, str(loc)) for label, loc in program.places.items())
    of.update(program.instances)


def load_beside(cpu: Any, graphs: Sequence[GraphFB], programs: Sequence[Loadable]) -> list[str]:
    """Download ``programs`` into ``cpu`` beside the installed GRAPH FBs ``graphs``: their
    OB1 runs after the charts' calls, their OB100 and OB102 after the charts' startup
    calls, their other OBs as they are. Returns the problems that refuse them (nothing
    loaded then): a block or DB of the charts' own written in a source too."""
    blocks = [b for program in programs for b in program.blocks]
    ours = {g.fb.label for g in graphs} | {f"DB{g.db_number}" for g in graphs}
    theirs = {b.label for b in blocks if isinstance(b, FB | FC | DB)}
    theirs |= {f"DB{n}" for p in programs for n in getattr(p, "instances", {})}
    clash = sorted(ours & theirs)
    if clash:
        return [f"s7graph: error: {', '.join(clash)} of the chart is written in a source too"]
    try:
        for program in programs:
            program.load(cpu)
    except BlockError as exc:
        return [f"s7graph: error: the blocks cannot be loaded beside the chart: {exc}"]
    chain_obs(cpu, graphs, blocks)
    return []


def chain_obs(cpu: Any, graphs: Sequence[GraphFB], blocks: Sequence[Any]) -> None:
    """Load the charts' OB1, OB100 and OB102 calling ``graphs``, each followed by the OB of
    the same number among ``blocks`` (the sources'), if any."""
    obs = {b.number: b for b in blocks if isinstance(b, OB)}
    ob1 = obs.get(1)
    own1, own100 = startup_obs(*graphs, extra_ob1=ob1.body if ob1 is not None else None)
    own102 = cold_restart_ob(*graphs)
    cpu.load(own1, _then(own100, obs.get(100)), _then(own102, obs.get(102)))


def _then(own: OB, theirs: OB | None) -> OB:
    """The charts' startup OB ``own``, then the program's of the same number."""
    if theirs is None:
        return own

    def body(ctx: Any) -> None:
        own.body(ctx)
        theirs.body(ctx)

    return OB(own.number, own.name, body)
