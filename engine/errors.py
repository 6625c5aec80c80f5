"""Errors as values with places: every error names where it happened (docs/architecture.md,
"Seams")."""

from __future__ import annotations

from collections.abc import Callable
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
    """An S7 address that does not parse, is out of range or is misaligned (docs/runtime.md, "The
    block runtime")."""


class LiteralError(S7Error):
    """A literal that does not parse or does not fit its type (docs/runtime.md, "The block
    runtime")."""


class TypeMismatch(S7Error):
    """A value of the wrong data type for an operand or parameter."""


class SymbolError(S7Error):
    """An unknown or duplicate symbol, or a malformed symbol table line."""


class BlockError(S7Error):
    """A block that is missing, badly declared or wrongly called (docs/runtime.md, "Programs of
    blocks in Python")."""


class ProgramError(S7Error):
    """An error inside a user block during a scan (goes to OB121 / STOP, docs/runtime.md, "When a
    scan hangs or fails")."""


class ScanAborted(BaseException):
    """Raised into the scan thread by the real-time runner's monitor when a block, a plant
    or an action is still running at twice the maximum cycle time (``engine/runner.py``).

    A ``BaseException``, so that ``except Exception`` in a block does not swallow it; the
    innermost block it escapes from names itself in ``block`` (``CallContext``), and the
    CPU goes to STOP with a diagnostic entry naming it (``Cpu.abort``)."""

    block: str = ""
    """The innermost block (or ``plant``) the abort escaped from; empty until tagged."""


GENERATED_PLACES: dict[str, Callable[[int], str | None]] = {}
"""Code generated from another language: its code objects' file name → a function giving
the source place (``file:line:col``) of a generated line, or None. Filled by the compilers
above the engine (S7-SCL, ``steps/scl``), read where the engine names where a scan was
(``engine.runner``), so that a user sees the place in their source, never generated code."""


def generated_place(filename: str, line: int) -> str | None:
    """The source place of ``line`` of the generated code ``filename``; None when it is not
    generated code, or the line is not known."""
    found = GENERATED_PLACES.get(filename)
    return found(line) if found is not None else None


def internal_error(where: str, exc: BaseException | None = None) -> str:
    """One line for a defect of ours that a last-resort guard caught: that it is an internal
    error, ``where`` it happened ("in the CPU while applying ack to Seq_drill": which
    command, op or block) and, with ``exc``, what it said — never the exception's class
    name (docs/security.md, "Refusals in words"). ``exc`` None: the message stays in the
    log (an answer to a peer not yet logged in)."""
    said = ""
    if exc is not None:
        try:
            said = " ".join(str(exc).split())[:1024]
        except Exception:  # an exception that cannot even say what it is
            said = ""
        if not said:
            said = "out of memory" if isinstance(exc, MemoryError) else "it gave no message"
        said = f": {said}"
    return f"an internal error {where}{said} (please report it)"
