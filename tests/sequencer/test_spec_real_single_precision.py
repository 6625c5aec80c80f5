"""docs/semantics.md, "Decisions" (type rules): a REAL is an IEEE 754 single (32 bits, 24 of
mantissa) wherever a chart holds or computes one — a variable, a constant, the result of
``+ - * /`` and of a REAL function — as the CPU's floating-point unit gives it; so ``r = 0.1``
holds after ``r := 0.1``, and ``16777216.0 + 1.0`` stays ``16777216.0``. A REAL in the trace
is written as the watch table shows it: the shortest decimal that reads back as the same
REAL (``0.1``, not ``0.10000000149011612``).

Through ``s7graph sim`` (the black-box contract), 10 ms per cycle."""

from __future__ import annotations

import math
import struct
from pathlib import Path

from tests.sequencer.helpers import seq, sim_trace, source


def _single(value: float) -> float:
    return float(struct.unpack(">f", struct.pack(">f", value))[0])


CHART = source(
    seq("""
  INITIAL_STEP S1 "a":
    N r := 0.1;
    N sum := sum + 0.1;
    N big := big + 1.0;
    N q := r * 3.0;
    N p := r + 0.2;
    N d := DINT_TO_REAL(n);
    N z := zero / zero;
    N e := EXP(100.0);
  END_STEP
"""),
    header=(
        "VAR r : REAL; p : REAL; sum : REAL; big : REAL := 16777216.0; q : REAL; d : REAL;\n"
        "  n : DINT := L#16777217; z : REAL; zero : REAL; e : REAL; END_VAR\n"
        "PERMANENT AFTER\n  M1.0 := r = 0.1;\n  M1.1 := p = 0.3;\nEND_PERMANENT\n"
    ),
)
WATCH = "r,sum,big,q,d,z,e,M1.0,M1.1"


def test_a_real_variable_equals_the_constant_it_was_given(tmp_path: Path) -> None:
    rc, lines = sim_trace(tmp_path, CHART, [], cycles=1, watch=WATCH)
    assert rc == 0
    values = lines[0]["values"]
    assert values["M1.0"] is True  # 0.1 as a REAL on both sides
    assert values["M1.1"] is True  # 0.1 + 0.2 = 0.3 in 32 bits (not in 64)


def test_sums_round_to_32_bits_every_time(tmp_path: Path) -> None:
    rc, lines = sim_trace(tmp_path, CHART, [], cycles=10, watch=WATCH)
    assert rc == 0
    total = _single(lines[0]["values"]["sum"])
    for line in lines[1:]:
        total = _single(total + _single(0.1))
        assert _single(line["values"]["sum"]) == total
    assert total != sum([0.1] * round(total / 0.1))  # not the 64-bit sum
    assert lines[-1]["values"]["big"] == 16777216.0  # 2 ** 24 + 1.0 has no REAL


def test_dint_to_real_keeps_24_bits_and_0_by_0_is_not_a_number(tmp_path: Path) -> None:
    rc, lines = sim_trace(tmp_path, CHART, [], cycles=1, watch=WATCH)
    assert rc == 0
    values = lines[0]["values"]
    assert values["d"] == 16777216.0
    assert math.isnan(values["z"])
    assert values["e"] == math.inf  # EXP beyond the REAL range: an infinity, not NaN


def test_the_trace_writes_a_real_as_the_watch_table_shows_it(tmp_path: Path) -> None:
    rc, lines = sim_trace(tmp_path, CHART, [], cycles=1, watch=WATCH)
    assert rc == 0
    assert lines[0]["values"]["r"] == 0.1
    assert lines[0]["values"]["q"] == 0.3
