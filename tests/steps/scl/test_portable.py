"""A compiled S7-SCL source as bytes (``steps/scl/portable.py``): made in another process,
it runs as the source compiled here does; the blocks it calls but does not write are the
receiving side's own; one it cannot find is named."""

from __future__ import annotations

import pickle
import subprocess
import sys

import pytest

from s7graph import sfb
from s7graph.engine.blocks import FB, FC
from s7graph.steps.scl.portable import compile_portable, load_portable
from tests.paths import ROOT
from tests.steps.scl.helpers import build, cpu_with

LIB = """FUNCTION_BLOCK FB17
VAR_INPUT go : BOOL; END_VAR
VAR n : INT; hist : ARRAY[1..3] OF INT; s : STRUCT a : INT; END_STRUCT; t : TON; END_VAR
  IF go THEN n := n + 1; hist[1] := n; s.a := n * 2; END_IF;
  t(IN := go, PT := T#50ms);
END_FUNCTION_BLOCK
"""
USER = """FUNCTION_BLOCK FB18
VAR x : FB17; k : INT; END_VAR
  x(go := TRUE); k := k + 3;
END_FUNCTION_BLOCK
ORGANIZATION_BLOCK OB1
  FB18.DB5();
END_ORGANIZATION_BLOCK
"""
CHILD = """
import sys
from s7graph import sfb
from s7graph.steps.scl.portable import compile_portable
text = sys.stdin.read()
_, (tree, code) = compile_portable(text, "lib.scl", blocks=sfb.SYSTEM_BLOCKS)
sys.stdout.buffer.write(len(tree).to_bytes(8, "little") + tree + code)
"""


def _made_elsewhere(text: str) -> tuple[bytes, bytes]:
    """``text`` compiled by another Python process, its bytes."""
    done = subprocess.run(
        [sys.executable, "-c", CHILD], input=text.encode(), capture_output=True, cwd=ROOT
    )
    assert done.returncode == 0, done.stderr.decode()
    n = int.from_bytes(done.stdout[:8], "little")
    return done.stdout[8 : 8 + n], done.stdout[8 + n :]


def test_a_program_made_in_another_process_runs_as_the_one_compiled_here() -> None:
    lib = load_portable(_made_elsewhere(LIB), sfb.SYSTEM_BLOCKS)
    known = [*sfb.SYSTEM_BLOCKS, *(b for b in lib.blocks if isinstance(b, FB | FC))]
    _, data = compile_portable(USER, "user.scl", blocks=known)
    user = load_portable(data, known)
    here_lib = build(LIB)
    here_user = build(USER, blocks=[b for b in here_lib.blocks if isinstance(b, FB | FC)])
    results = []
    for programs in ((lib, user), (here_lib, here_user)):
        cpu, clock = cpu_with(programs[0])
        programs[1].load(cpu)
        cpu.start("warm")
        for _ in range(7):
            cpu.scan()
            clock.advance(10)
        results.append(cpu.instance_dbs[5].snapshot())
    assert results[0] == results[1]
    assert results[0]["k"] == 21
    x = results[0]["x"]
    assert isinstance(x, dict) and x["n"] == 7 and x["hist"] == [7, 0, 0]
    fb17 = next(b for b in lib.blocks if isinstance(b, FB))
    assert fb17.state_format == here_lib.block("FB17").state_format  # type: ignore[union-attr]
    assert user.block("FB18").interface[0].init is fb17  # the loaded FB17, not a copy


def test_a_block_the_receiving_side_lacks_is_named() -> None:
    lib = build(LIB)
    known = [*sfb.SYSTEM_BLOCKS, *(b for b in lib.blocks if isinstance(b, FB | FC))]
    _, data = compile_portable(USER, "user.scl", blocks=known)
    with pytest.raises(pickle.UnpicklingError, match="calls FB17, which is not loaded"):
        load_portable(data, sfb.SYSTEM_BLOCKS)
