"""What a process imports to start: the supervisor of ``s7graph run`` neither typer nor the
CPU, a chart's CPU not the S7-SCL compiler, a CPU on the bus not the view (viser); the
packages that load their names when first used (``s7graph.lazy``) name each where it is
defined."""

from __future__ import annotations

import ast
import importlib
import subprocess
import sys
from pathlib import Path

import pytest

from tests.paths import ROOT

LAZY = {"s7graph.engine": ROOT / "engine", "s7graph.steps.scl": ROOT / "steps" / "scl"}


def _loaded_after(code: str, modules: list[str]) -> dict[str, bool]:
    """Which of ``modules`` a fresh interpreter has loaded after running ``code``."""
    probe = f"{code}\nimport sys\nprint(*[m in sys.modules for m in {modules!r}])"
    out = subprocess.run(
        [sys.executable, "-c", probe], cwd=ROOT, capture_output=True, text=True, check=True
    ).stdout.split()
    return dict(zip(modules, (word == "True" for word in out), strict=True))


def test_the_supervisor_of_run_starts_without_typer_the_cpu_or_the_commands() -> None:
    heavy = ["typer", "s7graph.engine.cpu", "s7graph.web.cli.root", "importlib.metadata"]
    code = "from s7graph.web.cli.supervisor import supervise, supervises"
    assert _loaded_after(code, heavy) == dict.fromkeys(heavy, False)


def test_a_charts_cpu_process_loads_no_scl_compiler_until_it_has_blocks() -> None:
    compiler = ["s7graph.steps.scl.compile", "s7graph.steps.scl.parse"]
    code = "import s7graph.web.cli.run_chart, s7graph.web.harness.dbvars"
    loaded = _loaded_after(code, compiler)
    assert not loaded["s7graph.steps.scl.compile"] and not loaded["s7graph.steps.scl.parse"]
    code += "\nfrom s7graph.web.harness.scl import compile_texts\ncompile_texts([])"
    assert _loaded_after(code, compiler)["s7graph.steps.scl.compile"]


def test_a_cpu_on_the_bus_loads_no_view_its_view_runs_in_a_process_of_its_own() -> None:
    code = "import s7graph.web.cli.run_chart, s7graph.web.wiring.live_edge, s7graph.web.view.port"
    assert _loaded_after(code, ["viser", "s7graph.web.view.edge"]) == {
        "viser": False,
        "s7graph.web.view.edge": False,
    }


def _type_checking_names(init: Path) -> dict[str, str]:
    """The names the ``if TYPE_CHECKING:`` block of ``init`` imports, by their module."""
    found: dict[str, str] = {}
    for node in ast.parse(init.read_text()).body:
        if isinstance(node, ast.If) and ast.unparse(node.test) == "TYPE_CHECKING":
            for imp in node.body:
                assert isinstance(imp, ast.ImportFrom) and imp.module
                found.update({a.name: imp.module.rpartition(".")[2] for a in imp.names})
    return found


@pytest.mark.parametrize("package", sorted(LAZY))
def test_a_lazy_packages_names_are_its_all_its_typed_imports_and_the_real_objects(
    package: str,
) -> None:
    module = importlib.import_module(package)
    table = {name: home for home, names in module._EXPORTS.items() for name in names}
    assert sorted(table) == sorted(module.__all__)
    assert _type_checking_names(LAZY[package] / "__init__.py") == table
    for name, home in table.items():
        assert getattr(module, name) is getattr(importlib.import_module(f"{package}.{home}"), name)
    assert not hasattr(module, "nothing_here")


def test_the_shells_commands_load_neither_the_pages_drawing_nor_the_scan_runner() -> None:
    """``s7graph status`` and the shell's ops ask a CPU and print lines: the page's drawing
    (numpy, pillow), viser and the real-time runner stay unloaded."""
    heavy = ["numpy", "PIL", "viser", "s7graph.engine.runner"]
    code = "import s7graph.web.cli.root, s7graph.web.cli.remote, s7graph.web.cli.diag"
    assert _loaded_after(code, heavy) == dict.fromkeys(heavy, False)
