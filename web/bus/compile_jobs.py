"""What the compiler process (``web.bus.compiler``) does with one request.

``answer(request)`` parses, validates and compiles a chart (``compile``; ``preview``: the
same, only the change summary, what the chart needs of the CPU — ``Needs``, which the CPU
checks as its swap will — and the S7-SCL programs go back) — with ``blocks``, the S7-SCL
sources its calls reach too, compiled first, the calls checked against their interfaces
and the FBs' variables the chart reads by name (``"Motor_DB".Running``) read in them;
without, in the interfaces of the blocks the CPU holds (``interfaces``), the chart's calls
of those blocks checked against them — compares two
charts (``summary``: an undo), checks that a text parses (``check``: a save), or imports a
file (``open``). Every refusal is ``{"refused": reason, "lines": diagnostics}`` with one
line naming the place; nothing a request holds makes it raise.
"""

from __future__ import annotations

import hashlib
import marshal
from pathlib import Path
from typing import Any, Final

from s7graph.engine.errors import S7Error, internal_error
from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.calls import unfit_calls
from s7graph.sequencer.change.base import EditRefused
from s7graph.sequencer.change.carry import fingerprint
from s7graph.sequencer.change.diff import summarize
from s7graph.sequencer.change.online import Needs
from s7graph.sequencer.change.typed import parse_source
from s7graph.sequencer.checks.diagnostics import format_diagnostic
from s7graph.sequencer.checks.interfaces import ProgramBlocks
from s7graph.sequencer.checks.validate import validate
from s7graph.sequencer.exchange import ImportFailed, import_file
from s7graph.sequencer.text.format import format_chart
from s7graph.sequencer.text.model import Chart
from s7graph.sequencer.text.parse import parse_chart
from s7graph.web.bus.live import prepare_chart
from s7graph.web.bus.pieces import dumps_in_pieces
from s7graph.web.harness.project import CHART_CHOICE
from s7graph.web.harness.scl import ChartBlocks, SclLoadError, SclSources
from s7graph.web.harness.session import ChartLoadError, Interfaces, compile_model

__all__ = ["MAX_SUMMARY_LINES", "answer"]

MAX_SUMMARY_LINES: Final = 1000  # lines of a change summary sent back


SOURCE_PIECE: Final = 1 << 18
_KEPT: Final = 4  # running charts kept parsed (by the hash of their text)
_running: dict[str, Chart] = {}


class _Refused(Exception):
    def __init__(self, reason: str, lines: list[str] | tuple[str, ...] = ()) -> None:
        super().__init__(reason)
        self.reason = reason
        self.lines = list(lines)


def answer(request: dict[str, Any]) -> tuple[dict[str, Any], list[bytes]]:
    """The answer to one request (see the module), and the raw pieces sent after it."""
    op = str(request.get("op"))
    try:
        if op in ("compile", "preview"):
            return _compile(request, preview=op == "preview")
        if op == "summary":
            return _summary(request), []
        if op == "check":
            _parse(str(request["text"]), str(request["file"]), "not saved")
            return {}, []
        if op == "open":
            pou = request.get("pou")
            path = Path(str(request["path"]))
            symbols = str(request.get("symbols", ""))
            return _open(path, symbols, pou if isinstance(pou, str) else None), []
        return {"refused": f"the compiler has no request {op!r}"}, []
    except _Refused as exc:
        return {"refused": exc.reason, "lines": exc.lines[:MAX_SUMMARY_LINES]}, []
    except RecursionError:
        return {"refused": f"{op} refused: the chart nests too deeply to compile"}, []
    except MemoryError:
        return {"refused": f"{op} refused: the chart needs more memory than there is"}, []
    except Exception as exc:  # a bad request is refused, the process goes on
        why = internal_error(f"in the compiler while answering {op}", exc)
        return {"refused": f"{op} refused: {why}"[:4096]}, []


def _parse(text: str, file: str, refused: str) -> Chart:
    try:
        return parse_source(text, file)
    except EditRefused as exc:
        lines = [format_diagnostic(d) for d in exc.diagnostics]
        reason = exc.reason.removeprefix("the source does not parse: ")
        raise _Refused(f"{refused}: {reason}", lines) from None


def _running_chart(text: str) -> Chart:
    """The running chart parsed from its text (kept for the next request)."""
    key = hashlib.sha256(text.encode()).hexdigest()
    chart = _running.get(key)
    if chart is None:
        chart = parse_chart(text, "<running chart>")
        while len(_running) >= _KEPT:
            _running.pop(next(iter(_running)))
        _running[key] = chart
    return chart


def _compile(request: dict[str, Any], *, preview: bool) -> tuple[dict[str, Any], list[bytes]]:
    """Parse, check and compile; the change summary; for a download the compiled chart
    and the view's description of it, pickled in pieces (``web.bus.pieces``) without its
    code objects, which follow marshalled batch by batch, and its generated source, which
    follows in pieces of ``SOURCE_PIECE`` characters. The chart reads the FBs' variables of
    the S7-SCL sources sent (``blocks``, compiled first) or else of the CPU's blocks
    (``interfaces``: ``sequencer.checks.interfaces.ProgramBlocks``)."""
    chart = _parse(str(request["text"]), str(request["file"]), "the chart does not parse")
    symbols = str(request.get("symbols", ""))
    named = request.get("blocks")
    portable: list[tuple[bytes, bytes]] = []
    sources: list[SclSources] = []
    try:
        table = SymbolTable.from_text(symbols) if symbols else None
        made = _interfaces(request.get("interfaces"), named, portable, sources)
        cc, table = compile_model(chart, table, blocks=made)
    except ChartLoadError as exc:
        errors = [line for line in exc.lines if ": error[" in line] or exc.lines
        raise _Refused(
            f"the chart does not compile: {len(errors)} error(s); {errors[0] if errors else ''}",
            exc.lines,
        ) from None
    except S7Error as exc:
        raise _Refused(f"the chart does not compile: {exc}") from None
    if named is None and isinstance(held := request.get("interfaces"), ProgramBlocks):
        _held_calls(chart, table, held)
    running = _running_chart(str(request["running"]))
    same = (chart.name, chart.fb_number, chart.db_number)
    was = (running.name, running.fb_number, running.db_number)
    if same != was:
        raise _Refused(
            f"a download changes the chart of the running FB, not the block: keep "
            f'FUNCTION_BLOCK "{was[0]}" FB {was[1] or 1} DB {was[2] or was[1] or 1}'
        )
    summary = summarize(running, chart, tuple(request.get("active", ())))
    lines = summary.lines()
    out: dict[str, Any] = {
        "summary": (lines[:MAX_SUMMARY_LINES], summary.removed_active, len(summary.changes)),
        "needs": Needs.of(cc),  # what the swap checks in the CPU: its preview checks too
    }
    if sources:
        out["blocks"] = _blocks(chart, table, sources[-1])
    if preview:  # the S7-SCL programs only: the CPU says what they carry over
        return out, [blob for pair in portable for blob in pair]
    fingerprint(cc)  # kept with the chart: the scan boundary does not compute it
    code = [marshal.dumps(piece) for piece in cc.code]
    source = cc.source
    object.__setattr__(cc, "code", ())
    object.__setattr__(cc, "source", "")
    live = prepare_chart(cc, fb=str(request["fb"]), version=int(request["version"]))
    pieces = dumps_in_pieces((cc, table, live))
    out["parts"] = (len(pieces), len(code))
    step = SOURCE_PIECE
    text = [source[k : k + step].encode() for k in range(0, len(source), step)]
    return out, [*pieces, *code, *text, *(blob for pair in portable for blob in pair)]


def _interfaces(
    held: ProgramBlocks | None,
    named: list[tuple[str, str]] | None,
    portable: list[Any],
    sources: list[SclSources],
) -> Interfaces | None:
    """The interfaces the chart is compiled with, made from its symbol table: those of the
    S7-SCL sources ``named`` (compiled then, in order, as the CPU compiled its own:
    ``web.harness.scl.ChartBlocks``; their programs' bytes appended to ``portable``:
    ``steps.scl.portable``; the sources appended to ``sources``), which replace the CPU's;
    else the CPU's blocks' ``held`` (None: it has none)."""
    if named is None:
        return None if held is None else lambda table: held
    blocks = ChartBlocks.of_texts(named, portable=portable)  # as the CPU compiled its own

    def compiled(table: SymbolTable) -> ProgramBlocks:
        try:
            made = blocks(table)
        except SclLoadError as exc:
            errors = [line for line in exc.lines if ": warning[" not in line] or exc.lines
            reason = f"the S7-SCL blocks do not compile: {len(errors)} error(s); {errors[0]}"
            raise _Refused(reason, exc.lines) from None
        assert blocks.sources is not None  # made by the call
        sources.append(blocks.sources)
        return made

    return compiled


def _held_calls(chart: Chart, table: SymbolTable, held: ProgramBlocks) -> None:
    """Refuse a chart brought alone whose calls of the blocks the CPU holds do not fit them
    (E047: a parameter the block lacks, a value of another type, an output given with
    ``:=``, an FC given an instance DB …): reached, such a call would stop the CPU. A call
    of a block the CPU lacks is the swap's to judge (``sequencer.calls.plan_calls``)."""
    calls = unfit_calls(chart, table, held)
    if calls:
        lines = [format_diagnostic(d) for d in calls]
        raise _Refused(f"the chart's calls do not fit the CPU's blocks: {lines[0]}", lines)


def _blocks(
    chart: Chart, table: SymbolTable, sources: SclSources
) -> tuple[list[str], list[str], int]:
    """The chart's calls checked against the interfaces of the S7-SCL ``sources`` it was
    compiled with; (files, warnings, programs)."""
    calls = [d for d in validate(chart, table, blocks=sources.interfaces()) if d.is_error]
    if calls:
        lines = [format_diagnostic(d) for d in calls]
        raise _Refused(f"the chart's calls do not fit the new blocks: {lines[0]}", lines)
    return list(sources.files), list(sources.warnings), len(sources.programs)


def _summary(request: dict[str, Any]) -> dict[str, Any]:
    """The change summary from the ``running`` chart's text to the ``target``'s (both kept
    parsed for the next request): an undo of a download."""
    running = _running_chart(str(request["running"]))
    target = _running_chart(str(request["target"]))
    summary = summarize(running, target, tuple(request.get("active", ())))
    return {
        "summary": (
            summary.lines()[:MAX_SUMMARY_LINES],
            summary.removed_active,
            len(summary.changes),
        )
    }


def _open(path: Path, symbols: str, pou: str | None) -> dict[str, Any]:
    name = path.name
    try:
        table = SymbolTable.from_text(symbols) if symbols else None
        imported = import_file(path, symbols=table, pou=pou)
    except ImportFailed as exc:
        if exc.charts:
            shown = ", ".join(exc.charts)
            raise _Refused(
                f"{name} holds {len(exc.charts)} charts ({shown}): choose one",
                [CHART_CHOICE.format(file=name, chart=c) for c in exc.charts],
            ) from None
        lines = [format_diagnostic(d) for d in exc.diagnostics]
        raise _Refused(
            f"{name} does not import: {lines[0] if lines else 'no chart'}", lines
        ) from None
    except (OSError, S7Error) as exc:
        raise _Refused(f"cannot open {name}: {exc}") from None
    text = format_chart(imported.chart)
    return {
        "text": text,
        "lines": [format_diagnostic(d) for d in imported.problems],
        "scl": imported.blocks_scl,
        "functions": [(f.number, f.source) for f in imported.functions],
    }
