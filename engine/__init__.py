"""The soft CPU: memory, types, blocks, modes, the scan cycle and diagnostics (SPEC.md §1)."""

from __future__ import annotations

from engine.address import Address, Area, Width, parse_address
from engine.blocks import DB, FB, FC, OB, Decl, InstanceDB, Var, fb, fc, ob, sfb, sfc
from engine.clock import Clock, SystemClock, VirtualClock
from engine.cpu import CallContext, Cpu, Pending
from engine.diagnostics import DiagnosticBuffer, EventId
from engine.errors import (
    AddressError,
    BlockError,
    LiteralError,
    ProgramError,
    S7Error,
    SourceLocation,
    SymbolError,
    TypeMismatch,
)
from engine.memory import Memory
from engine.modes import CpuMode, KeySwitch, ModeRequest, SetKeySwitch
from engine.record import DiagEntry, ScanRecord
from engine.restart import RestartType

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
