"""Shared drivers of the example tests (``tests/examples/test_*.py``), imported as
``tests.examples.helpers``: run an example's ``s7graph sim`` command (docs/cli.md, "s7graph sim")
and read edges and paths out of its trace records."""

from __future__ import annotations

import json
from collections.abc import Callable, Iterable
from pathlib import Path

from s7graph.web.cli import main
from tests.paths import EXAMPLES

Predicate = Callable[[dict], bool]


def sim_example(
    tmp_path: Path,
    example: str,
    *,
    watch: Iterable[str],
    stimulus: Path,
    cycles: int,
    cycle_ms: int = 10,
    plant: Path | None = None,
    every_cycle: bool = True,
) -> list[dict]:
    """Run ``s7graph sim`` on ``examples/<example>/<example>.s7g`` with its
    ``symbols.txt`` and ``plant`` (default: its ``plant.py``); assert it exits 0 and —
    with ``every_cycle`` — that the trace has one record a cycle; return the records."""
    folder = EXAMPLES / example
    trace = tmp_path / "trace.jsonl"
    rc = main(
        [
            "sim",
            str(folder / f"{example}.s7g"),
            "--symbols",
            str(folder / "symbols.txt"),
            "--plant",
            str(plant or folder / "plant.py"),
            "--stimulus",
            str(stimulus),
            "--cycle-ms",
            str(cycle_ms),
            "--cycles",
            str(cycles),
            "--watch",
            ",".join(watch),
            "--trace",
            str(trace),
        ]
    )
    assert rc == 0
    records = [json.loads(line) for line in trace.read_text().splitlines()]
    if every_cycle:
        assert len(records) == cycles
    return records


def stimulus_file(tmp_path: Path, *lines: dict) -> Path:
    """``stimulus.jsonl`` in ``tmp_path``, one stimulus a line."""
    path = tmp_path / "stimulus.jsonl"
    path.write_text("".join(json.dumps(line) + "\n" for line in lines))
    return path


def plant_variant(tmp_path: Path, example: str, **attrs: object) -> Path:
    """A plant file subclassing ``examples/<example>/plant.py``'s ``Plant`` with other class
    attributes."""
    body = "".join(f"    {name} = {value!r}\n" for name, value in attrs.items())
    base = str(EXAMPLES / example / "plant.py")
    path = tmp_path / "plant_variant.py"
    path.write_text(
        "import importlib.util\n"
        f"_spec = importlib.util.spec_from_file_location('{example}_plant', {base!r})\n"
        "_mod = importlib.util.module_from_spec(_spec)\n"
        "_spec.loader.exec_module(_mod)\n"
        f"class Plant(_mod.Plant):\n{body}"
    )
    return path


def path_of(records: list[dict]) -> list[list[str]]:
    """The successive sets of active steps, repeated sets collapsed."""
    path: list[list[str]] = []
    for rec in records:
        if not path or rec["active"] != path[-1]:
            path.append(rec["active"])
    return path


def edge_times(
    records: list[dict], predicate: Predicate, *, rising: bool = True, before: bool | None = None
) -> list[int]:
    """The times (ms) at which ``predicate(record)`` rose (or fell). ``before`` is its value
    ahead of the first record; ``None``: the first record is no edge."""
    times: list[int] = []
    for rec in records:
        now = bool(predicate(rec))
        if before is not None and now == rising and before != rising:
            times.append(rec["t_ms"])
        before = now
    return times


def edges(records: list[dict], name: str, rising: bool = True) -> list[int]:
    """The times (ms) at which the watched ``name`` rose (or fell)."""
    return edge_times(records, on(name), rising=rising)


def entered(records: list[dict], step: str) -> list[int]:
    """The times (ms) of every cycle in which ``step`` became active."""
    return edge_times(records, lambda rec: step in rec["active"], before=False)


def first(records: list[dict], predicate: Predicate) -> int:
    """The time (ms) of the first record for which ``predicate(record)`` holds."""
    return next(rec["t_ms"] for rec in records if predicate(rec))


def on(name: str) -> Predicate:
    return lambda rec: bool(rec["values"][name])
