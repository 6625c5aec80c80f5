"""Scan marks (``engine.marks``): what one process writes, another mapping of the same
memory reads — the cycle running since when, the section and the innermost block."""

from __future__ import annotations

import mmap

import pytest

from s7graph.engine import fb, fc, ob
from s7graph.engine.clock import VirtualClock
from s7graph.engine.cpu import Cpu
from s7graph.engine.marks import MARKS_SIZE, MarkReader, ScanMarks


def test_marks_written_on_one_mapping_are_read_on_another() -> None:
    page = mmap.mmap(-1, MARKS_SIZE)
    marks, reader = ScanMarks(page), MarkReader(page)
    marks.max_cycle(150_000_000)
    marks.begin(123_456)
    marks.section("plant p.py")
    assert (reader.busy_since_ns, reader.section, reader.max_cycle_ns) == (
        123_456,
        "plant p.py",
        150_000_000,
    )
    marks.section(None)
    marks.end()
    assert (reader.busy_since_ns, reader.scans, reader.section) == (0, 1, "")
    reader.release()


def test_a_block_is_marked_while_it_runs_and_its_caller_again_after() -> None:
    @ob(1)
    def main(ctx: object) -> None: ...

    @fb(3, name="mixer")
    def mixer(ctx: object, db: object) -> None: ...

    page = bytearray(MARKS_SIZE)
    marks, reader = ScanMarks(page), MarkReader(page)
    outer = marks.enter(main)
    assert reader.block == 'OB1 "main"'
    inner = marks.enter(mixer)
    assert reader.block == 'FB3 "mixer"'
    marks.leave(inner)
    assert reader.block == 'OB1 "main"'
    marks.leave(outer)
    assert reader.block == ""


def test_marks_refuse_a_buffer_too_small_or_read_only() -> None:
    with pytest.raises(ValueError, match="writable"):
        ScanMarks(bytearray(16))
    with pytest.raises(ValueError, match="writable"):
        ScanMarks(memoryview(bytes(MARKS_SIZE)))


def test_a_scan_marks_each_block_as_it_runs(clock: VirtualClock) -> None:
    page = bytearray(MARKS_SIZE)
    reader = MarkReader(page)
    seen: list[str] = []

    @fc(7, name="crunch")
    def crunch(ctx: object, params: object) -> None:
        seen.append(reader.block)

    @ob(1)
    def main(ctx: object) -> None:
        seen.append(reader.block)
        ctx.call(crunch)  # type: ignore[attr-defined]
        seen.append(reader.block)

    cpu = Cpu(clock)
    cpu.load(main, crunch)
    cpu.mark_blocks(ScanMarks(page))
    cpu.start()
    cpu.scan()
    assert seen == ['OB1 "main"', 'FC7 "crunch"', 'OB1 "main"']
    assert reader.block == ""
