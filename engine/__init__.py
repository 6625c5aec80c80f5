"""The soft CPU: memory, types, blocks, modes, the scan cycle and diagnostics (docs/runtime.md)."""

from __future__ import annotations

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
