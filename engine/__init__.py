"""The soft CPU: memory, types, blocks, modes, the scan cycle and diagnostics (docs/runtime.md).

The names below are loaded when first used (PEP 562): a process that needs one module of
the engine (the supervisor of ``s7graph run`` reads only ``engine/marks.py``) does not pay
for the CPU's.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from s7graph.lazy import lazy_names

if TYPE_CHECKING:
    from s7graph.engine.address import Address, Area, Width, parse_address
    from s7graph.engine.blocks import DB, FB, FC, OB, Decl, InstanceDB, Var, fb, fc, ob, sfb, sfc
    from s7graph.engine.clock import Clock, SystemClock, VirtualClock
    from s7graph.engine.cpu import CallContext, Cpu, Pending
    from s7graph.engine.diagnostics import DiagnosticBuffer, EventId
    from s7graph.engine.errors import (
        AddressError,
        BlockError,
        LiteralError,
        ProgramError,
        S7Error,
        SourceLocation,
        SymbolError,
        TypeMismatch,
    )
    from s7graph.engine.memory import Memory
    from s7graph.engine.modes import CpuMode, KeySwitch, ModeRequest, SetKeySwitch
    from s7graph.engine.record import DiagEntry, ScanRecord
    from s7graph.engine.restart import RestartType

_EXPORTS: dict[str, tuple[str, ...]] = {
    "address": ("Address", "Area", "Width", "parse_address"),
    "blocks": ("DB", "FB", "FC", "OB", "Decl", "InstanceDB", "Var", "fb", "fc", "ob", "sfb", "sfc"),
    "clock": ("Clock", "SystemClock", "VirtualClock"),
    "cpu": ("CallContext", "Cpu", "Pending"),
    "diagnostics": ("DiagnosticBuffer", "EventId"),
    "errors": (
        "AddressError",
        "BlockError",
        "LiteralError",
        "ProgramError",
        "S7Error",
        "SourceLocation",
        "SymbolError",
        "TypeMismatch",
    ),
    "memory": ("Memory",),
    "modes": ("CpuMode", "KeySwitch", "ModeRequest", "SetKeySwitch"),
    "record": ("DiagEntry", "ScanRecord"),
    "restart": ("RestartType",),
}
"""The engine's names by the module that defines them."""
__getattr__ = lazy_names(globals(), "s7graph.engine", _EXPORTS)

__all__ = [
    "DB",
    "FB",
    "FC",
    "OB",
    "Address",
    "AddressError",
    "Area",
    "BlockError",
    "CallContext",
    "Clock",
    "Cpu",
    "CpuMode",
    "Decl",
    "DiagEntry",
    "DiagnosticBuffer",
    "EventId",
    "InstanceDB",
    "KeySwitch",
    "LiteralError",
    "Memory",
    "ModeRequest",
    "Pending",
    "ProgramError",
    "RestartType",
    "S7Error",
    "ScanRecord",
    "SetKeySwitch",
    "SourceLocation",
    "SymbolError",
    "SystemClock",
    "TypeMismatch",
    "Var",
    "VirtualClock",
    "Width",
    "fb",
    "fc",
    "ob",
    "parse_address",
    "sfb",
    "sfc",
]
