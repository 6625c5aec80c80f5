"""S7-SCL: FBs, FCs, OBs, DBs and UDTs written in Siemens' structured text, compiled once to
Python code objects and run as engine blocks (docs/scl.md).

``compile_scl(text, file)`` → ``SclProgram`` (``.load(cpu)``); ``check_scl(text, file)`` →
diagnostics. The modules, in the order a source passes them: ``parse`` (the lark grammar →
``model``), ``declare`` and ``consts`` (blocks, interfaces, types of ``types``), ``places``,
``exprs``, ``builtins``, ``calls`` and ``stmts`` (the generator, over ``gen``), ``compile``
(the module), ``blocks`` (engine blocks), with ``runtime`` the helpers the generated code
calls and ``diagnostics`` the codes.

The names below are loaded when first used: a process that reads DB variables through
``types`` and ``access`` does not pay for the compiler.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from s7graph.lazy import lazy_names

if TYPE_CHECKING:
    from s7graph.steps.scl.blocks import SclProgram, compile_scl
    from s7graph.steps.scl.check import check_scl
    from s7graph.steps.scl.diagnostics import CODES, Diagnostic, SclError, format_diagnostic

_EXPORTS: dict[str, tuple[str, ...]] = {
    "blocks": ("SclProgram", "compile_scl"),
    "check": ("check_scl",),
    "diagnostics": ("CODES", "Diagnostic", "SclError", "format_diagnostic"),
}
"""The package's names by the module that defines them."""
__getattr__ = lazy_names(globals(), "s7graph.steps.scl", _EXPORTS)

__all__ = [
    "CODES",
    "Diagnostic",
    "SclError",
    "SclProgram",
    "check_scl",
    "compile_scl",
    "format_diagnostic",
]
