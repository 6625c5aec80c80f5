"""Drivers of the S7-SCL tests, imported as ``tests.steps.scl.helpers``.

- ``build``: compile a source with the system blocks of ``sfb`` known (``STP``,
  ``TIME_TCK`` …); ``run``: compile, load into a real ``Cpu`` on a ``VirtualClock`` with the
  system blocks installed, warm restart, and scan ``scans`` times ``ms`` apart.
- ``codes``: the ``(code, line, col)`` of each diagnostic of a source.
- ``value``: one expression evaluated by an FB — its value and the OK flag after it.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

from s7graph import sfb
from s7graph.engine import Cpu, VirtualClock
from s7graph.steps.scl import SclProgram, check_scl, compile_scl


def build(
    src: str, *, names: Mapping[str, str] | None = None, blocks: Any = (), **kw: Any
) -> SclProgram:
    every = (*sfb.SYSTEM_BLOCKS, *blocks)
    return compile_scl(src, "t.scl", blocks=every, names=names, **kw)


def cpu_with(program: SclProgram, **kw: Any) -> tuple[Cpu, VirtualClock]:
    clock = VirtualClock()
    cpu = Cpu(clock, **kw)
    sfb.install(cpu)
    program.load(cpu)
    return cpu, clock


def run(
    src: str,
    scans: int = 1,
    *,
    ms: float = 10,
    before: Callable[[Cpu], None] | None = None,
    names: Mapping[str, str] | None = None,
    cpu_options: Mapping[str, Any] | None = None,
    **kw: Any,
) -> Cpu:
    """Compile and load ``src``, start the CPU, call ``before(cpu)``, scan ``scans`` times."""
    cpu, clock = cpu_with(build(src, names=names, **kw), **dict(cpu_options or {}))
    cpu.start()
    if before is not None:
        before(cpu)
    for _ in range(scans):
        cpu.scan()
        clock.advance(ms)
    return cpu


def codes(src: str, **kw: Any) -> list[tuple[str, int, int]]:
    """Each diagnostic of ``src`` as (code, line, column), in source order."""
    found = check_scl(src, "t.scl", blocks=sfb.SYSTEM_BLOCKS, **kw)
    return [(d.code, d.loc.line, d.loc.col) for d in found]


def errors(src: str, **kw: Any) -> list[str]:
    return [c for c, _, _ in codes(src, **kw) if c.startswith("E")]


def value(expr: str, rtype: str = "INT", decls: str = "") -> tuple[Any, bool]:
    """``expr`` evaluated into a variable of ``rtype`` by FB1 in OB1; (value, OK)."""
    src = f"""
FUNCTION_BLOCK FB1
VAR r : {rtype}; okay : BOOL; {decls} END_VAR
  r := {expr};
  okay := OK;
END_FUNCTION_BLOCK
ORGANIZATION_BLOCK OB1
  FB1.DB1();
END_ORGANIZATION_BLOCK
"""
    cpu = run(src)
    db = cpu.instance_db(1)
    return db["r"], bool(db["okay"])
