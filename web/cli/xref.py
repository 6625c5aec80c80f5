"""``s7graph xref CHART [--symbols FILE] [--operand NAME] [--json] [--blocks SCL …]``: the
cross-reference list of a chart and the S7-SCL blocks beside it — where each operand is
used and how — as TIA Portal's cross-references show a tag's uses (``sequencer.xref``;
docs/cli.md, "s7graph xref"). ``CHART`` may be an S7-SCL program (``.scl``): the uses in
its blocks and those of ``--blocks``.

Text: each operand on a line of its own, then one line per use (the element, the access,
``file:line:col``), then the symbols the chart declares and never uses. ``--operand``:
that operand's uses only (a symbol with or without quotes, an address, a variable); exit
1 when it has none. ``--json``: one object, ``{"operands": {operand: [{"element",
"access", "at"}]}, "unused": [...]}``. A chart or an S7-SCL source that does not parse,
or an unreadable chart, source or symbol table, is its diagnostics on stderr and exit 2.
"""

from __future__ import annotations

import json
import sys
from collections.abc import Sequence
from pathlib import Path

from s7graph.engine.errors import S7Error
from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.checks.diagnostics import format_diagnostic
from s7graph.sequencer.text.parse import ChartSyntaxError, chart_text, parse_chart
from s7graph.sequencer.xref import CrossReferences, Use, block_references, cross_references
from s7graph.steps.scl import SclError
from s7graph.steps.scl import format_diagnostic as scl_diagnostic
from s7graph.steps.scl.parse import parse_source
from s7graph.web.harness.scl import read_source

__all__ = ["xref_command"]


def xref_command(
    chart: Path,
    *,
    symbols: Path | None = None,
    operand: str | None = None,
    as_json: bool = False,
    blocks: Sequence[Path] = (),
) -> int:
    """Print the cross-references of ``chart`` and the S7-SCL sources ``blocks``; the exit
    code (0, 1: ``operand`` unused, 2: a chart, source or symbol table that cannot be
    read)."""
    try:
        table = SymbolTable.from_file(symbols) if symbols is not None else None
        if chart.suffix.lower() == ".scl":  # a program: its source and the blocks beside it
            sources = [parse_source(read_source(p), str(p)) for p in (chart, *blocks)]
            refs = block_references(sources, table)
        else:
            parsed = parse_chart(chart_text(chart.read_bytes(), str(chart)), str(chart))
            sources = [parse_source(read_source(path), str(path)) for path in blocks]
            refs = cross_references(parsed, table, sources)
    except OSError as exc:
        name = exc.filename or chart
        print(f"s7graph: error: cannot read {name}: {exc.strerror or exc}", file=sys.stderr)
        return 2
    except ChartSyntaxError as exc:
        for d in exc.diagnostics:
            print(format_diagnostic(d), file=sys.stderr)
        return 2
    except SclError as exc:
        for e in exc.diagnostics:
            print(scl_diagnostic(e), file=sys.stderr)
        return 2
    except S7Error as exc:
        print(f"s7graph: error: {exc}", file=sys.stderr)
        return 2
    found = _chosen(refs, operand)
    if as_json:
        print(json.dumps(_as_json(found, refs.unused if operand is None else ()), indent=1))
    else:
        for line in _lines(found, refs.unused if operand is None else ()):
            print(line)
    if operand is not None and not found:
        print(f"s7graph: no use of {operand} in {chart}", file=sys.stderr)
        return 1
    return 0


def _chosen(refs: CrossReferences, operand: str | None) -> dict[str, list[Use]]:
    if operand is None:
        return refs.operands()
    out: dict[str, list[Use]] = {}
    for use in refs.of(operand):
        out.setdefault(use.operand, []).append(use)
    return out


def _lines(found: dict[str, list[Use]], unused: tuple[str, ...]) -> list[str]:
    uses = [u for us in found.values() for u in us]
    width = max((len(u.element) for u in uses), default=0)
    access = max((len(u.access) for u in uses), default=0)
    out = []
    for operand, its in found.items():
        out.append(operand)
        out += [f"  {u.element:<{width}}  {u.access:<{access}}  {u.place}" for u in its]
    if unused:
        out.append("unused symbols: " + ", ".join(f'"{name}"' for name in unused))
    return out


def _as_json(found: dict[str, list[Use]], unused: tuple[str, ...]) -> dict[str, object]:
    return {
        "operands": {
            operand: [{"element": u.element, "access": u.access, "at": u.place} for u in its]
            for operand, its in found.items()
        },
        "unused": list(unused),
    }
