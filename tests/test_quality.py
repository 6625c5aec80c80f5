"""The code stays ruff-clean and mypy-clean, mypy strict on every package; the tests are
laid out like the packages they test."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

from tests.paths import ROOT


@pytest.mark.timeout(300)
def test_ruff_finds_nothing_to_complain_about() -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "ruff", "check", "."], cwd=ROOT, capture_output=True, text=True
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr


@pytest.mark.timeout(300)
def test_ruff_format_leaves_every_file_as_it_is() -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "ruff", "format", "--check", "."],
        cwd=ROOT,
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr


def test_no_format_exceptions_and_no_unit_a_reader_cannot_hold() -> None:
    """No ``fmt: skip``; no class over 500 lines and no function over 100 in the package."""
    skips, large = [], []
    for path in sorted(ROOT.glob("**/*.py")):
        rel = path.relative_to(ROOT)
        if rel.parts[0] in (".git", "build") or "site-packages" in rel.parts:
            continue
        text = path.read_text(encoding="utf-8")
        if "# fmt: " + "skip" in text:
            skips.append(str(rel))
        if rel.parts[0] not in LAYERS and rel.parts[0] != "s7graph":
            continue
        for node in ast.walk(ast.parse(text)):
            limit = 500 if isinstance(node, ast.ClassDef) else 100
            if isinstance(node, ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef):
                size = (node.end_lineno or node.lineno) - node.lineno + 1
                if size > limit:
                    large.append(f"{rel}:{node.lineno} {node.name} ({size} lines)")
    assert skips == [] and large == [], (skips, large)


LAYERS = ("engine", "sfb", "steps", "sequencer", "web")


def package_tree(into: Path) -> Path:
    """The installed shape of the package, ``s7graph/<layer>``, as links into the source tree.

    mypy cannot follow setuptools' editable-install finder (the layers are mapped from the
    repository root by ``package-dir``), so it reads the package through these links."""
    top = into / "s7graph"
    top.mkdir()
    for module in (ROOT / "s7graph").glob("*.py"):
        (top / module.name).symlink_to(module)
    for layer in LAYERS:
        (top / layer).symlink_to(ROOT / layer, target_is_directory=True)
    return into


@pytest.mark.timeout(600)
def test_mypy_is_clean_and_strict_on_every_package(tmp_path: Path) -> None:
    where = package_tree(tmp_path)
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "mypy",
            "--config-file",
            str(ROOT / "pyproject.toml"),
            "--cache-dir",
            str(ROOT / ".mypy_cache"),
            "-p",
            "s7graph",
        ],
        cwd=where,
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 0, proc.stdout[-5000:] + proc.stderr[-2000:]


# ---- the tests are laid out like the packages ---------------------------------------------
# A test module of one package sits in tests/ at the package's path: tests/engine/ for
# engine/, tests/sequencer/change/ for sequencer/change/, tests/web/ for web/commands.py
# and web/recorder.py. One that covers every layer or the project (the layer rules, the
# wheel, the docs, this file) sits in tests/ itself. The folders that mirror no package:
ELSEWHERE = {
    "examples": "the examples' commands run as docs/cli.md describes them (examples/)",
    "bench": "what the benchmarks' measurements rest on (bench/)",
}
DATA = {  # the charts the tests read, named in tests/sequencer/helpers.py; no test modules
    "sequencer/charts",
    "sequencer/broken",
    "sequencer/scenarios",
}


def test_the_tests_are_laid_out_like_the_packages() -> None:
    """Every folder under ``tests/`` is a package's (``tests/<layer>/<sub>/`` with
    ``<layer>/<sub>/__init__.py`` in the source), one of ``ELSEWHERE`` or a data folder;
    a data folder holds no Python, so a test module cannot hide there."""
    tests = ROOT / "tests"
    wrong = []
    for folder in sorted(p for p in tests.rglob("*") if p.is_dir()):
        rel = folder.relative_to(tests)
        if any(part == "__pycache__" or part.startswith(".") for part in rel.parts):
            continue
        if all("__pycache__" in f.parts for f in folder.rglob("*") if f.is_file()):
            continue  # left behind by a module that moved: only bytecode, or nothing
        name = rel.as_posix()
        if name in DATA:
            modules = sorted(folder.glob("*.py"))
            wrong += [f"tests/{name}/{p.name}: Python in a data folder" for p in modules]
        elif rel.parts[0] in ELSEWHERE:
            if len(rel.parts) > 1:
                wrong.append(f"tests/{name}: a folder inside tests/{rel.parts[0]}/")
        elif not (ROOT / rel / "__init__.py").is_file():
            wrong.append(f"tests/{name}: no package {name}/ in the source")
    assert wrong == [], "\n".join(wrong)
    assert set(ELSEWHERE) <= {p.name for p in tests.iterdir() if p.is_dir()}
    assert all((tests / name).is_dir() for name in DATA)
