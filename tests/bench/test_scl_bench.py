"""``bench/scl.py`` compares like with like: each of the guide's algorithms (STEP7
comprehensive guide vol. 2, ch. 13) in S7-SCL and as hand-written Python blocks leaves the
same result in memory, and the compile benchmark's source of about 1,000 lines compiles
into the blocks it is made of."""

from __future__ import annotations

import importlib.util
import sys
from types import ModuleType

import pytest

from s7graph import sfb
from s7graph.steps.scl import compile_scl
from tests.paths import ROOT

BENCH = ROOT / "bench"


@pytest.fixture(scope="module")
def bench() -> ModuleType:
    sys.path.insert(0, str(BENCH))
    try:
        spec = importlib.util.spec_from_file_location("scl_bench_under_test", BENCH / "scl.py")
        assert spec is not None and spec.loader is not None
        module = importlib.util.module_from_spec(spec)
        sys.modules[spec.name] = module  # its dataclasses look their module up
        spec.loader.exec_module(module)
        return module
    finally:
        sys.path.remove(str(BENCH))


def test_each_algorithm_leaves_the_same_result_in_scl_and_in_python(bench: ModuleType) -> None:
    for w in bench.WORKLOADS:
        left = []
        for language in ("scl", "python"):
            cpu, clock = bench.build(w, language)
            bench.measure(cpu, clock, w.between, 3)
            assert cpu.mode.name == "RUN", (w.name, language)
            left.append(w.result(cpu))
        assert left[0] == left[1], w.name
        assert left[0] is not None, w.name


def test_the_compile_source_is_about_a_thousand_lines_of_blocks(bench: ModuleType) -> None:
    sets = bench.source_sets()
    text = bench.compile_source(sets)
    assert 900 <= len(text.splitlines()) <= 1000
    program = compile_scl(text, "bench.scl", blocks=sfb.SYSTEM_BLOCKS)
    assert program.diagnostics == []
    kinds = sorted({type(b).__name__ for b in program.blocks})
    assert kinds == ["DB", "FB", "FC", "OB"] and len(program.blocks) == 3 * sets + 1
