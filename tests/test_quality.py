"""The code stays ruff-clean and mypy-clean, mypy strict on every package."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


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
