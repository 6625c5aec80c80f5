"""The one rule of the layers (docs/contracts.md, DESIGN.md): the core is pure.

Nothing under engine/ sfb/ steps/ sequencer/ imports viser, zenoh, rerun or threading, or
reads the wall clock or sleeps; engine/clock.py and engine/runner.py are the exceptions.
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
CORE = ("engine", "sfb", "steps", "sequencer")
EXEMPT = {"engine/clock.py", "engine/runner.py"}
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


def test_the_checker_catches_violations() -> None:
    """The check itself can fail."""
    bad = "import threading\nimport time\nfrom datetime import datetime\nx = datetime.now()\n"
    bad += "time.time()\nfrom zenoh import open\n"
    assert len(violations(bad, "bad.py")) == 4


def test_core_packages_stay_pure() -> None:
    """No core module imports viser/zenoh/rerun/threading or reads the wall clock."""
    found: list[str] = []
    for package in CORE:
        for path in sorted((ROOT / package).rglob("*.py")):
            rel = path.relative_to(ROOT).as_posix()
            if rel not in EXEMPT:
                found += violations(path.read_text(encoding="utf-8"), rel)
    assert found == []
