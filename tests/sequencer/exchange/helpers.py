"""Shared drivers of the import/export tests, imported as
``tests.sequencer.exchange.helpers``: the corpus (read in place from ``../shared/corpus``,
skipped when absent), the synthetic files beside the tests (one per construct an import or
export fix is about), ``s7graph import`` and ``s7graph sim`` run through the command line."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from s7graph.engine import VirtualClock
from s7graph.sequencer.checks.diagnostics import Diagnostic
from s7graph.sequencer.exchange import Imported, import_file
from s7graph.steps.scl import compile_scl
from s7graph.web.cli import main
from s7graph.web.harness.session import ChartSession, compile_model
from tests.paths import ROOT

CORPUS = ROOT.parent / "shared" / "corpus"
HERE = Path(__file__).resolve().parent


def corpus(relative: str) -> Path:
    """A corpus file; the test is skipped when the corpus is not there."""
    path = CORPUS / relative
    if not path.is_file():
        pytest.skip(f"corpus file {relative} not present")
    return path


def imported(relative: str) -> Imported:
    return import_file(corpus(relative))


def synthetic(name: str) -> Path:
    """A synthetic file of the tests (``tests/sequencer/exchange/<name>``)."""
    path = HERE / name
    assert path.is_file(), path
    return path


def codes(problems: list[Diagnostic]) -> list[tuple[str, int]]:
    """(code, line) of each problem, in order."""
    return [(d.code, d.loc.line) for d in problems]


def import_to(tmp_path: Path, source: Path, *extra: str) -> tuple[int, Path]:
    """``s7graph import SOURCE -o chart.s7g``: (exit status, chart path)."""
    out = tmp_path / "chart.s7g"
    return main(["import", str(source), "-o", str(out), *extra]), out


def sim(
    tmp_path: Path,
    chart: Path,
    *,
    watch: list[str],
    stimulus: list[dict] = (),  # type: ignore[assignment]
    cycles: int,
    cycle_ms: int = 10,
) -> list[dict]:
    """``s7graph sim`` on ``chart``: one record a cycle."""
    stim = tmp_path / "stimulus.jsonl"
    stim.write_text("".join(json.dumps(s) + "\n" for s in stimulus))
    trace = tmp_path / "trace.jsonl"
    args = [
        "sim",
        str(chart),
        "--stimulus",
        str(stim),
        "--cycles",
        str(cycles),
        "--cycle-ms",
        str(cycle_ms),
        "--trace",
        str(trace),
    ]
    if watch:
        args += ["--watch", ",".join(watch)]
    assert main(args) == 0
    records = [json.loads(line) for line in trace.read_text().splitlines()]
    assert len(records) == cycles
    return records


def scl_session(result: Imported) -> ChartSession:
    """The imported chart in a CPU on the virtual clock with the SCL FCs of its ST bodies
    loaded (``Imported.blocks_scl``), started."""
    cc, table = compile_model(result.chart)
    session = ChartSession(cc, table, VirtualClock())
    compile_scl(result.blocks_scl, "blocks.scl").load(session.cpu)
    session.start()
    return session


def changes(records: list[dict], *names: str) -> list[tuple[int, list[str], list[str]]]:
    """(t_ms, active steps, watched names that are TRUE) each time one of them changes."""
    out: list[tuple[int, list[str], list[str]]] = []
    for r in records:
        item = (r["t_ms"], r["active"], [n for n in names if r["values"].get(n) is True])
        if not out or out[-1][1:] != item[1:]:
            out.append(item)
    return out
