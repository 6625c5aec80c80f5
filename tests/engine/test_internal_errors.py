"""Errors in words (docs/security.md, "Refusals in words"): a defect of ours caught by a
last-resort guard is one line saying that it is an internal error, where and what it said;
Python's own limits reached by a block are said in words; a write failure the state store
did not name is the disk's words. Never an exception's class name."""

from __future__ import annotations

import errno

from s7graph.engine import CallContext, Cpu, VirtualClock, ob
from s7graph.engine.errors import BlockError, internal_error
from s7graph.engine.writer import _disk_words


def test_an_internal_error_says_where_and_what_never_the_class_name() -> None:
    said = internal_error("in the CPU while applying ack to Seq_drill", KeyError("x"))
    assert said == (
        "an internal error in the CPU while applying ack to Seq_drill: 'x' (please report it)"
    )
    assert "KeyError" not in said


def test_an_internal_error_is_one_line_and_says_so_when_there_is_no_message() -> None:
    assert internal_error("in the editor", ValueError("two\nlines")) == (
        "an internal error in the editor: two lines (please report it)"
    )
    assert internal_error("in the editor", ValueError()) == (
        "an internal error in the editor: it gave no message (please report it)"
    )
    assert internal_error("in the editor", MemoryError()) == (
        "an internal error in the editor: out of memory (please report it)"
    )
    assert internal_error("while answering a login request") == (
        "an internal error while answering a login request (please report it)"
    )


def test_a_block_past_pythons_recursion_limit_is_diagnosed_in_words(
    clock: VirtualClock,
) -> None:
    def deeper(n: int) -> int:
        return deeper(n + 1) + 1

    @ob(1)
    def main(ctx: CallContext) -> None:
        deeper(0)

    cpu = Cpu(clock)
    cpu.load(main)
    cpu.start()
    cpu.scan()
    messages = [e.message for e in cpu.diagnostics]
    assert any(m.startswith("calls nested too deeply (maximum recursion depth") for m in messages)
    assert not any("RecursionError" in m for m in messages), messages


def test_a_write_failure_the_store_did_not_name_is_said_in_words() -> None:
    full = OSError(errno.EFBIG, "File too large", "drill.sqlite-wal")
    assert _disk_words(full) == "File too large: drill.sqlite-wal"
    assert _disk_words(RuntimeError("no batch")) == (
        "an internal error while writing it: no batch (please report it)"
    )


def test_a_command_that_breaks_at_the_scan_boundary_is_diagnosed_in_words(
    clock: VirtualClock,
) -> None:
    """A command queued for the scan boundary that raises: the CPU goes on, the diagnostic
    entry (and the command's answer) say an internal error and what it said; an S7 error
    of a command keeps its own words."""
    cpu = Cpu(clock)
    cpu.start()

    def breaks(_: Cpu) -> None:
        raise KeyError("x")

    def refused(_: Cpu) -> None:
        raise BlockError("DB9 is not loaded")

    broken, s7 = cpu.submit(breaks), cpu.submit(refused)
    cpu.scan()
    assert cpu.mode.name == "RUN" and broken.done and s7.done
    assert broken.error == (
        "an internal error in the CPU while applying a command: 'x' (please report it)"
    )
    assert s7.error == "DB9 is not loaded"
    messages = [e.message for e in cpu.diagnostics]
    assert broken.error in messages and "DB9 is not loaded" in messages
