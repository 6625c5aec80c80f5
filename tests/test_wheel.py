"""``pip install`` puts one top-level package into site-packages: ``s7graph``.

The layers stay in their folders at the repository root (``engine/``, ``sfb/``, ``steps/``,
``sequencer/``, ``web/``) and are installed as ``s7graph.engine`` … ``s7graph.web`` by the
``package-dir`` mapping of pyproject.toml. A real wheel is built from a copy of the source
tree and installed into a fresh virtual environment.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import zipfile
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.paths import ROOT

LAYERS = ("engine", "sfb", "steps", "sequencer", "web")

pytestmark = pytest.mark.timeout(600)


def _run(*cmd: str | Path, cwd: Path | None = None) -> str:
    proc = subprocess.run(
        [str(c) for c in cmd], cwd=cwd, capture_output=True, text=True, timeout=540
    )
    assert proc.returncode == 0, f"{cmd}:\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}"
    return proc.stdout


@pytest.fixture(scope="module")
def wheel(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The wheel, built (with build isolation, as a user's pip does) from a copy of the tree."""
    src = tmp_path_factory.mktemp("src")
    for name in ("pyproject.toml", "README.md"):
        shutil.copy(ROOT / name, src / name)
    skip = shutil.ignore_patterns("__pycache__", "*.pyc")
    for folder in ("s7graph", *LAYERS):
        shutil.copytree(ROOT / folder, src / folder, ignore=skip)
    out = tmp_path_factory.mktemp("dist")
    _run(sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", out, src)
    (found,) = out.glob("s7graph-*.whl")
    return found


@pytest.fixture(scope="module")
def venv(tmp_path_factory: pytest.TempPathFactory, wheel: Path) -> Iterator[tuple[Path, set[str]]]:
    """A fresh venv (the dependencies come from the running interpreter's site-packages) with
    the wheel installed; yields its python and what the install added to its site-packages."""
    where = tmp_path_factory.mktemp("venv") / "v"
    _run(sys.executable, "-m", "venv", "--system-site-packages", where)
    python = where / "bin" / "python"
    site = Path(
        _run(python, "-c", "import sysconfig; print(sysconfig.get_path('purelib'))").strip()
    )
    before = {p.name for p in site.iterdir()}
    _run(python, "-m", "pip", "install", "--no-deps", "--no-index", "-q", wheel)
    yield python, {p.name for p in site.iterdir()} - before


def test_the_wheel_holds_only_the_s7graph_package(wheel: Path) -> None:
    with zipfile.ZipFile(wheel) as z:
        tops = {name.split("/")[0] for name in z.namelist()}
    assert tops == {"s7graph", wheel.name.split("-py")[0] + ".dist-info"}


def test_every_module_of_the_layers_is_in_the_wheel(wheel: Path) -> None:
    """A sub-package missing from pyproject's ``packages`` list would be left out silently."""
    with zipfile.ZipFile(wheel) as z:
        names = set(z.namelist())
    expected = {
        f"s7graph/{path.relative_to(ROOT).as_posix()}"
        for layer in LAYERS
        for path in (ROOT / layer).rglob("*")
        if path.suffix in (".py", ".lark") and "__pycache__" not in path.parts
    }
    assert sorted(expected - names) == []


def test_install_adds_only_s7graph_and_its_dist_info(venv: tuple[Path, set[str]]) -> None:
    _, added = venv
    assert {name for name in added if not name.endswith(".dist-info")} == {"s7graph"}
    assert len([name for name in added if name.endswith(".dist-info")]) == 1


def test_the_installed_command_and_module_run(venv: tuple[Path, set[str]]) -> None:
    python, _ = venv
    home = python.parent.parent  # run outside the source tree, whose s7graph/ would shadow it
    assert _run(python.parent / "s7graph", "--version", cwd=home).startswith("s7graph ")
    assert _run(python, "-m", "s7graph", "--version", cwd=home).startswith("s7graph ")
    code = "import s7graph.engine as e, s7graph.web.cli as c; print(e.__file__)"
    assert _run(python, "-c", code, cwd=home).startswith(str(home))
