"""A chart's operands must lie in the memory it runs on: one beyond its area (``I200.0``
with 128 bytes of inputs, ``MW300`` with 256 of markers, ``T300`` with 256 timers) is refused
when the chart is bound to the memory, naming the operand — as S7's area length error —
never an index error of the generated code, and never a write that grows the area. A REAL
beyond the REAL range is stored as an infinity, as the CPU's overflow gives."""

from __future__ import annotations

import struct

import pytest

from s7graph.engine.errors import AddressError
from tests.sequencer.helpers import chart, seq


def _with(condition: str, rows: str = "") -> str:
    return seq(f"""
  INITIAL_STEP S1 "a": {rows} END_STEP
  STEP S2 "b": END_STEP
  TRANSITION T1 FROM S1 TO S2 := {condition};
""")


@pytest.mark.parametrize(
    ("condition", "rows", "says"),
    [
        ("I200.0", "", "I200.0 is outside the I area (128 bytes)"),
        ("I0.0", "N MW300 := 7;", "MW300 is outside the M area (256 bytes)"),
        ("MD254 > L#0", "", "MD254 is outside the M area (256 bytes)"),
        ("T300", "", "T300: only 256 T cells exist"),
        ("I0.0", "S1 CU C 300;", "C300: only 256 C cells exist"),
    ],
)
def test_an_operand_beyond_its_area_is_refused_naming_it(
    condition: str, rows: str, says: str
) -> None:
    with pytest.raises(AddressError) as caught:
        chart(_with(condition, rows))
    assert caught.value.message == says


def test_a_real_beyond_the_real_range_is_stored_as_an_infinity() -> None:
    run = chart(
        _with("I0.0", "N r := r * r; N MD0 := r;"), header="VAR r : REAL := 3.0E38; END_VAR"
    )
    run.call()
    raw = run.mem.get("MD0")
    assert struct.unpack(">f", int(raw).to_bytes(4, "big"))[0] == float("inf")
