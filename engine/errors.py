"""Errors as values with places: every error names where it happened (DESIGN.md "Errors")."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True, slots=True)
class SourceLocation:
    """A place in a source text: ``file:line:col`` (1-based line and column)."""

    file: str = "<input>"
    line: int = 0
    col: int = 0

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.col}"


class S7Error(Exception):
    """Base of every error the runtime raises on purpose; ``where`` names the place."""

    def __init__(self, message: str, where: SourceLocation | str | None = None) -> None:
        self.message = message
        self.where = where
        super().__init__(f"{where}: {message}" if where is not None else message)


class AddressError(S7Error):
    """An S7 address that does not parse, is out of range or is misaligned (SPEC §1.1)."""


class LiteralError(S7Error):
    """A literal that does not parse or does not fit its type (SPEC §1.2)."""


class TypeMismatch(S7Error):
    """A value of the wrong data type for an operand or parameter."""


class SymbolError(S7Error):
    """An unknown or duplicate symbol, or a malformed symbol table line."""


class BlockError(S7Error):
    """A block that is missing, badly declared or wrongly called (SPEC §1.3)."""


class ProgramError(S7Error):
    """An error inside a user block during a scan (goes to OB121 / STOP, SPEC §1.5)."""
