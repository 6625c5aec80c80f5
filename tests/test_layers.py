"""The rules of the layers (docs/architecture.md): imports point down, never in a circle, and
the core is pure.

- Layers, bottom to top: ``engine`` → ``sfb`` and ``steps`` (siblings, neither imports the
  other) → ``sequencer`` → ``web``; inside ``web`` the roles stack ``harness`` → ``access``
  → ``bus`` → ``recorder`` → ``view`` → ``opcua`` → ``wiring`` → ``cli``. A module imports
  only from its own layer or below.
- No import cycle between modules, whether the import runs at import time, inside a
  function or only for the type checker (``TYPE_CHECKING``): every import is an edge.
- Inside ``sequencer`` the jobs keep their order: the chart's text (``text``) and its
  checking (``checks``) stand without the runtime — of the root they use only the pin
  table (``params``) and ``collector`` — and without the chart's change (``change``) or
  ``exchange``; the runtime at the root uses of ``change`` only the carry-over, and
  nothing but ``exchange`` itself imports ``exchange``.
- Every import of the project names it ``s7graph.…`` (the folders are not packages of
  their own once installed).
- Nothing under engine/ sfb/ steps/ sequencer/ imports viser, zenoh, rerun or threading,
  or reads the wall clock or sleeps; engine/clock.py, engine/runner.py and engine/writer.py
  (the state file's writer thread) are the exceptions.
"""

from __future__ import annotations

import ast
from collections.abc import Iterable, Iterator
from pathlib import Path

from tests.paths import ROOT

LAYERS = ("engine", "sfb", "steps", "sequencer", "web")
CORE = ("engine", "sfb", "steps", "sequencer")
EXEMPT = {"engine/clock.py", "engine/runner.py", "engine/writer.py"}
BANNED_MODULES = {"viser", "zenoh", "rerun", "threading"}
BANNED_CALLS = {
    "time.time",
    "time.time_ns",
    "time.sleep",
    "time.monotonic",
    "time.monotonic_ns",
    "time.perf_counter",
    "time.perf_counter_ns",
    "datetime.now",
    "datetime.utcnow",
    "datetime.today",
    "date.today",
    "datetime.datetime.now",
    "datetime.date.today",
}

# The rank of each layer (and of web's roles): an import may point to a lower rank or stay
# inside its own unit. ``s7graph`` itself (its ``__init__``) is the floor, ``__main__`` the top.
RANKS: dict[str, float] = {
    "s7graph": 0,
    "s7graph.engine": 1,
    "s7graph.sfb": 2,
    "s7graph.steps": 2,
    "s7graph.sequencer": 3,
    "s7graph.web": 4,
    "s7graph.web.commands": 4.05,  # the command vocabulary: under every role of web
    "s7graph.web.harness": 4.1,
    "s7graph.web.access": 4.15,
    "s7graph.web.bus": 4.2,
    "s7graph.web.recorder": 4.3,
    "s7graph.web.view": 4.4,
    "s7graph.web.opcua": 4.42,  # the OPC UA face: beside the view, a client of the bus
    "s7graph.web.wiring": 4.45,
    "s7graph.web.cli": 4.5,
    "s7graph.__main__": 5,
}


def _dotted(node: ast.expr) -> str:
    if isinstance(node, ast.Name):
        return node.id
    if isinstance(node, ast.Attribute):
        return f"{_dotted(node.value)}.{node.attr}"
    return ""


def violations(source: str, name: str) -> list[str]:
    """Every banned import or wall-clock call in ``source``."""
    found: list[str] = []
    for node in ast.walk(ast.parse(source, name)):
        modules: list[str] = []
        if isinstance(node, ast.Import):
            modules = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module:
            modules = [node.module]
            if node.module == "time":
                modules += [f"time.{a.name}" for a in node.names]
        for module in modules:
            if module.split(".")[0] in BANNED_MODULES or module in BANNED_CALLS:
                found.append(f"{name}:{node.lineno}: imports {module}")
        if isinstance(node, ast.Call) and _dotted(node.func) in BANNED_CALLS:
            found.append(f"{name}:{node.lineno}: calls {_dotted(node.func)}")
    return found


# ---------------------------------------------------------------- the module graph


def project_modules(root: Path = ROOT) -> dict[str, Path]:
    """Every module of the installed package by its dotted name (``s7graph.engine.cpu``)."""
    found: dict[str, Path] = {}
    for folder, prefix in [(root / "s7graph", "s7graph")] + [
        (root / layer, f"s7graph.{layer}") for layer in LAYERS
    ]:
        for path in sorted(folder.rglob("*.py")):
            parts = list(path.relative_to(folder).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts.pop()
            found[".".join([prefix, *parts])] = path
    return found


def imports_of(source: str, module: str, is_package: bool, known: set[str]) -> set[str]:
    """The project modules ``module`` imports (``from pkg import sub`` is ``pkg.sub``)."""
    out: set[str] = set()
    base = module if is_package else module.rpartition(".")[0]
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            out.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            target = node.module or ""
            if node.level:
                anchor = base.split(".")[: len(base.split(".")) - (node.level - 1)]
                target = ".".join([*anchor, target] if target else anchor)
            for alias in node.names:
                sub = f"{target}.{alias.name}"
                out.add(sub if sub in known else target)
    return {m for m in out if m.split(".")[0] in ("s7graph", *LAYERS)}


def import_graph(root: Path = ROOT) -> dict[str, set[str]]:
    modules = project_modules(root)
    known = set(modules)
    return {
        name: imports_of(path.read_text(encoding="utf-8"), name, path.name == "__init__.py", known)
        for name, path in modules.items()
    }


def rank(module: str) -> tuple[float, str]:
    """The rank of ``module`` and the unit it belongs to (its longest prefix in RANKS)."""
    parts = module.split(".")
    for n in range(len(parts), 0, -1):
        unit = ".".join(parts[:n])
        if unit in RANKS:
            return RANKS[unit], unit
    raise KeyError(module)


def upward(graph: dict[str, set[str]]) -> list[str]:
    """Imports that point up a layer, sideways between sibling layers, or at a bare folder."""
    found: list[str] = []
    for module, targets in sorted(graph.items()):
        mine, unit = rank(module)
        for target in sorted(targets):
            if not target.startswith("s7graph"):
                found.append(f"{module} imports {target}: name it s7graph.{target}")
                continue
            theirs, their_unit = rank(target)
            inside = their_unit == unit or target.startswith(unit + ".")
            if not inside and theirs >= mine:
                found.append(f"{module} ({unit}) imports {target} ({their_unit})")
    return found


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one module, or a module importing
    itself (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph.get(v, ()):
            if w not in graph:
                continue
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            scc: list[str] = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                scc.append(w)
                if w == v:
                    break
            if len(scc) > 1 or v in graph.get(v, ()):
                out.append(sorted(scc))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


SEQ = "s7graph.sequencer"
JOBS = ("text", "checks", "change", "exchange")  # sub-packages; the rest is the runtime
# what the chart's text and checking may use of the root, and the runtime of ``change``
TEXT_USES_OF_ROOT = {f"{SEQ}.params", f"{SEQ}.collector"}
ROOT_USES_OF_CHANGE = {f"{SEQ}.change.carry"}


def job(module: str) -> str | None:
    """The job of a ``sequencer`` module: its sub-package, ``root`` (the runtime), or None
    outside ``sequencer``."""
    parts = module.split(".")
    if parts[:2] != SEQ.split("."):
        return None
    return parts[2] if len(parts) > 2 and parts[2] in JOBS else "root"


def out_of_order(graph: dict[str, set[str]]) -> list[str]:
    """Imports between ``sequencer``'s jobs that break their order (module docstring)."""
    found: list[str] = []
    for module, targets in sorted(graph.items()):
        mine = job(module)
        for target in sorted(targets):
            theirs = job(target)
            if mine is None or theirs is None or theirs == mine:
                continue
            bad = (
                theirs == "exchange"
                or (mine in ("text", "checks") and theirs == "change")
                or (
                    mine in ("text", "checks")
                    and theirs == "root"
                    and target not in TEXT_USES_OF_ROOT
                )
                or (mine == "root" and theirs == "change" and target not in ROOT_USES_OF_CHANGE)
            )
            if bad:
                found.append(f"{module} ({mine}) imports {target} ({theirs})")
    return found


def _graph_of(sources: dict[str, str]) -> dict[str, set[str]]:
    known = set(sources)
    return {m: imports_of(src, m, False, known) for m, src in sources.items()}


def _walk_core() -> Iterator[tuple[str, str]]:
    for package in CORE:
        for path in sorted((ROOT / package).rglob("*.py")):
            rel = path.relative_to(ROOT).as_posix()
            if rel not in EXEMPT:
                yield rel, path.read_text(encoding="utf-8")


def _lines(items: Iterable[object]) -> str:
    return "\n".join(str(i) for i in items)


# ---------------------------------------------------------------- the checks can fail


def test_the_checker_catches_violations() -> None:
    """The purity check itself can fail."""
    bad = "import threading\nimport time\nfrom datetime import datetime\nx = datetime.now()\n"
    bad += "time.time()\nfrom zenoh import open\n"
    assert len(violations(bad, "bad.py")) == 4


def test_the_cycle_check_finds_a_two_way_tie_and_a_type_only_one() -> None:
    """A circle through a TYPE_CHECKING import is still a circle."""
    graph = _graph_of(
        {
            "s7graph.engine.a": "from s7graph.engine.b import x\n",
            "s7graph.engine.b": "from typing import TYPE_CHECKING\n"
            "if TYPE_CHECKING:\n    from s7graph.engine.a import y\n",
            "s7graph.engine.c": "from s7graph.engine import a\n",
        }
    )
    assert cycles(graph) == [["s7graph.engine.a", "s7graph.engine.b"]]


def test_the_layer_check_finds_an_upward_a_sideways_and_a_bare_import() -> None:
    graph = _graph_of(
        {
            "s7graph.steps.x": "from s7graph.sequencer.text.model import Step\n"
            "from s7graph.sfb.alarms import Message\n",
            "s7graph.web.bus.y": "from s7graph.web.view.layout import place\n",
            "s7graph.sequencer.z": "from engine.cpu import Cpu\n",
        }
    )
    assert len(upward(graph)) == 4


def test_the_job_check_finds_text_using_the_runtime_and_the_runtime_using_an_edit() -> None:
    graph = _graph_of(
        {
            "s7graph.sequencer.text.a": "from s7graph.sequencer.cycle import GraphRuntime\n"
            "from s7graph.sequencer.params import PINS\n",
            "s7graph.sequencer.fb": "from s7graph.sequencer.change.edit import apply\n"
            "from s7graph.sequencer.change.carry import carry_over\n",
            "s7graph.sequencer.change.b": "from s7graph.sequencer.exchange import import_chart\n",
        }
    )
    assert len(out_of_order(graph)) == 3


# ---------------------------------------------------------------- the rules


def test_core_packages_stay_pure() -> None:
    """No core module imports viser/zenoh/rerun/threading or reads the wall clock."""
    found: list[str] = []
    for rel, source in _walk_core():
        found += violations(source, rel)
    assert found == []


def test_no_import_cycle_between_modules() -> None:
    assert _lines(cycles(import_graph())) == ""


def test_imports_point_down_the_layers() -> None:
    assert _lines(upward(import_graph())) == ""


def test_the_jobs_of_sequencer_keep_their_order() -> None:
    assert _lines(out_of_order(import_graph())) == ""
