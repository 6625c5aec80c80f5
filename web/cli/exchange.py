"""``s7graph import`` and ``s7graph export``: charts to and from TIA Portal SimaticML,
PLCopen TC6 XML and IEC 61131-3 textual SFC.

``import FILE [-o OUT.s7g] [--symbols-out FILE] [--symbols FILE] [--pou NAME] [--strict]``
detects the format, writes the chart (stdout without ``-o``) — and, with ``-o``, the SCL FCs
it calls for ST bodies a row cannot hold to ``OUT.scl`` beside it — and prints every problem on
stderr, one a line (``file:line:col: warning[I021]: …``). The chart keeps its symbols in a
``SYMBOLS`` section, or in a symbol file with ``--symbols-out`` (then ``s7graph check OUT
--symbols FILE``). Exit status: 0 imported as it is, 1 imported with warnings (what was
left out or changed is listed, and noted at the top of the chart), 2 no chart (the list
says why) — with ``--strict`` also when anything was left out.

``export CHART.s7g --to plcopen|simaticml -o FILE [--symbols FILE] [--blocks BLOCKS.scl …]``
writes the chart in that format and prints, one a line, what of it the format's other
readers do not see or run otherwise (exit 1; 0 when nothing); a chart that does not
compile, or a part the format cannot hold, is its diagnostics and exit 2. ``--blocks``: the
S7-SCL sources of the user FBs whose instance DBs the chart reads by name
(``"Motor_DB".Running``), compiled with the chart by the function ``check``, ``sim`` and
``run`` use (``web.harness.scl.ChartBlocks``); their warnings come first, as ``check``
prints them, and count (exit 1).
"""

from __future__ import annotations

import dataclasses
import sys
from collections.abc import Sequence
from pathlib import Path

from s7graph.engine.errors import S7Error
from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.checks.diagnostics import format_diagnostic
from s7graph.sequencer.exchange import (
    FORMATS,
    Imported,
    ImportFailed,
    detect_format,
    export_reported,
    import_file,
)
from s7graph.sequencer.text.format import format_chart, quote
from s7graph.sequencer.text.model import Chart
from s7graph.web.cli.report import fail
from s7graph.web.harness.scl import ChartBlocks
from s7graph.web.harness.session import load_chart

__all__ = ["export_command", "import_command"]

_LEFT_OUT = ("I020", "I021", "I022", "I023", "I024")


def _symbol_file(chart: Chart, given: SymbolTable | None = None) -> str:
    """The symbol file ``--symbols-out`` writes: the tags of the table the import was
    given (``--symbols``) that the chart does not declare itself, then the chart's — all a
    ``check`` of the chart needs, in one file."""
    own = {s.name for s in chart.symbols}
    rows = [(s.name, str(s.address), s.type, s.comment) for s in given or () if s.name not in own]
    rows += [(s.name, s.address, s.type, s.comment) for s in chart.symbols]
    lines = [f"{quote(n)} ; {a} ; {t} ; {c}".rstrip(" ;") for n, a, t, c in rows]
    return "\n".join(lines) + "\n"


def _header(source: Path, result: Imported) -> str:
    head = f"Imported from {source.name} ({FORMATS[result.format]}) by s7graph import."
    if not result.problems:
        return head
    lines = [head, "What the import reports (file:line:col of the source):"]
    lines += [
        "  " + format_diagnostic(d).replace(str(source), source.name) for d in result.problems
    ]
    return "\n".join(lines)


def _os_error(doing: str, path: Path | str | None, exc: OSError) -> S7Error:
    """A file the command cannot read or write as one line naming it (``cannot write
    out.s7g: is a folder, not a file``), never Python's ``[Errno 21] …`` spelling."""
    where = path if path is not None else exc.filename or "a file"
    if isinstance(exc, IsADirectoryError) or Path(where).is_dir():
        reason = "is a folder, not a file"
    else:
        reason = exc.strerror or str(exc)
    return S7Error(f"cannot {doing} {where}: {reason}")


def _same_file(source: Path, output: Path) -> bool:
    """Whether writing ``output`` would overwrite ``source`` (the same file, whatever the
    path says): refused, the source would be lost."""
    try:
        return output.exists() and source.exists() and output.samefile(source)
    except OSError:
        return False


def _format_of(source: Path) -> str:
    """The name of the format ``source`` looks like, for a message ("a chart file" when it
    cannot be told)."""
    try:
        with source.open("rb") as f:
            fmt = detect_format(f.read(200_000))
    except OSError:
        fmt = None
    return FORMATS[fmt] if fmt is not None else "a chart file"


def _read(source: Path, symbols: Path | None, pou: str | None) -> Imported | int:
    """The import of ``source`` or, when there is none, the exit status after saying why:
    its located problems (``ImportFailed``), or one ``s7graph: error:`` line — a symbol
    file that cannot be read, or anything else the importer did not expect, said as a file
    that could not be read as its format (never a Python exception's name); exit 2."""
    table: SymbolTable | None = None
    if symbols is not None:
        try:
            table = SymbolTable.from_file(symbols)
        except OSError as exc:
            return fail(_os_error("read symbols", symbols, exc))
        except S7Error as exc:
            return fail(exc)
    try:
        return import_file(source, pou=pou, symbols=table)
    except ImportFailed as exc:
        for d in exc.diagnostics:
            print(format_diagnostic(d), file=sys.stderr)
        print(f"{source}: not imported", file=sys.stderr)
        return 2
    except OSError as exc:
        return fail(_os_error("read", exc.filename or source, exc))
    except S7Error as exc:  # placed in the file when it names no place of its own
        return fail(exc if exc.where is not None else S7Error(exc.message, str(source)))
    except RecursionError:  # elements nested (or wired) deeper than a chart can hold
        return fail(
            S7Error(
                f"{source}: not imported: its elements nest too deeply (a condition of "
                "hundreds of levels, or elements deeper than a chart holds)"
            )
        )
    except Exception:  # the last resort: a file that says so, not a traceback
        what = _format_of(source)
        return fail(S7Error(f"{source}: not imported: it cannot be read as {what}"))


def import_command(
    source: Path,
    *,
    output: Path | None = None,
    symbols_out: Path | None = None,
    symbols: Path | None = None,
    pou: str | None = None,
    strict: bool = False,
) -> int:
    """Import ``source``; return the exit status (see the module docstring). A file the
    command cannot read or write is one ``s7graph: error:`` line naming it, exit 2."""
    if output is not None and _same_file(source, output):
        return fail(S7Error(f"-o {output} is the file imported: give the chart a file of its own"))
    result = _read(source, symbols, pou)
    if isinstance(result, int):
        return result
    for d in result.problems:
        print(format_diagnostic(d), file=sys.stderr)
    left_out = [d for d in result.problems if d.code in _LEFT_OUT]
    if strict and left_out:
        print(
            f"{source}: not imported (--strict): {len(left_out)} construct(s) cannot be mapped",
            file=sys.stderr,
        )
        return 2
    chart = result.chart
    try:
        if symbols_out is not None:
            given = SymbolTable.from_file(symbols) if symbols is not None else None
            symbols_out.write_text(_symbol_file(chart, given), encoding="utf-8")
            chart = dataclasses.replace(chart, symbols=())
        text = format_chart(chart, _header(source, result))
        if output is None:
            sys.stdout.write(text)
        else:
            output.write_text(text, encoding="utf-8")
            if result.functions:
                output.with_suffix(".scl").write_text(result.blocks_scl, encoding="utf-8")
    except OSError as exc:
        return fail(_os_error("write", None, exc))
    n = len(result.problems)
    print(
        f"{source}: imported ({FORMATS[result.format]}), {n} warning{'s' * (n != 1)}",
        file=sys.stderr,
    )
    if result.functions:
        where = output.with_suffix(".scl") if output is not None else "not written (no -o)"
        print(f"{source}: the SCL FCs the chart calls: {where}", file=sys.stderr)
    return 1 if result.problems else 0


def export_command(
    chart: Path,
    *,
    to: str,
    output: Path,
    symbols: Path | None = None,
    blocks: Sequence[Path] = (),
) -> int:
    """Export ``chart`` to ``output`` in format ``to``; return the exit status. A chart that
    reads a user FB's variable by name compiles only with that FB's source (``blocks``)."""
    if to not in ("plcopen", "simaticml"):
        return fail(S7Error(f"--to must be plcopen or simaticml, not {to!r}"))
    if _same_file(chart, output):
        return fail(
            S7Error(f"-o {output} is the chart exported: give the export a file of its own")
        )
    sources = ChartBlocks(blocks)  # compiled with the chart, as check, sim and run do
    try:
        _, table = load_chart(chart, symbols, blocks=sources if blocks else None)
        from s7graph.sequencer.text.parse import parse_file

        model = parse_file(chart)
        text, problems = export_reported(model, to, table if symbols is not None else None)
    except (S7Error, ValueError, OSError) as exc:
        _say(sources.warnings)  # the sources' warnings first, as check prints them
        return fail(exc)
    _say(sources.warnings)
    try:
        output.write_text(text, encoding="utf-8")
    except OSError as exc:
        return fail(_os_error("write", output, exc))
    _say([format_diagnostic(d) for d in problems])
    n = len(problems) + len(sources.warnings)
    more = f", {n} warning{'s' * (n != 1)}" if n else ""
    print(f"{chart}: exported to {output} ({FORMATS[to]}){more}", file=sys.stderr)
    return 1 if n else 0


def _say(lines: Sequence[str]) -> None:
    """Each of ``lines`` on stderr."""
    for line in lines:
        print(line, file=sys.stderr)
