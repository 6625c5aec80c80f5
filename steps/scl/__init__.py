"""S7-SCL: FBs, FCs, OBs, DBs and UDTs written in Siemens' structured text, compiled once to
Python code objects and run as engine blocks (docs/scl.md).

``compile_scl(text, file)`` → ``SclProgram`` (``.load(cpu)``); ``check_scl(text, file)`` →
diagnostics. The modules, in the order a source passes them: ``parse`` (the lark grammar →
``model``), ``declare`` and ``consts`` (blocks, interfaces, types of ``types``), ``places``,
``exprs``, ``builtins``, ``calls`` and ``stmts`` (the generator, over ``gen``), ``compile``
(the module), ``blocks`` (engine blocks), with ``runtime`` the helpers the generated code
calls and ``diagnostics`` the codes.
"""

from __future__ import annotations

from s7graph.steps.scl.blocks import SclProgram, compile_scl
from s7graph.steps.scl.check import check_scl
from s7graph.steps.scl.diagnostics import CODES, Diagnostic, SclError, format_diagnostic

__all__ = [
    "CODES",
    "Diagnostic",
    "SclError",
    "SclProgram",
    "check_scl",
    "compile_scl",
    "format_diagnostic",
]
