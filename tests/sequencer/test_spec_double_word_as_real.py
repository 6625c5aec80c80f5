"""docs/semantics.md, "Decisions" (type rules): an untyped double-word address (``MD20``)
stands for a DINT, a REAL or a TIME, whichever the other side needs — beside a REAL its 32
bits are a REAL's, read and written as such (``MD20 > 1.5`` compares as ``L MD20`` /
``L 1.5`` / ``>R`` does), as the argument of a REAL function too (``SIN(MD28)``). A stimulus
gives a word or double word in the format it is written in: a negative number as INT or
DINT, a number with a point as REAL.

Through ``s7graph sim`` (the black-box contract), 10 ms per cycle."""

from __future__ import annotations

import struct
from pathlib import Path

from tests.sequencer.helpers import seq, sim_trace, source

CHART = source(
    seq("""
  INITIAL_STEP S1 "a":
    N MD24 := r; N e := SIN(MD28); N d := ROUND(MD24); N x := MD24 * 2.0;
  END_STEP
"""),
    header=(
        "VAR r : REAL := 2.5; e : REAL; d : DINT; x : REAL; END_VAR\n"
        "PERMANENT AFTER\n  M1.1 := MD20 > 1.5;\n  M1.2 := MD24 > 2.0;\n"
        "  M1.3 := MW10 < -3;\n  M1.4 := MD30 < L#0;\nEND_PERMANENT\n"
    ),
)


def _bits(value: float) -> int:
    """The 32 bits of a REAL, as a DWORD."""
    return int.from_bytes(struct.pack(">f", value), "big")


def test_a_double_word_beside_a_real_is_read_and_written_as_a_real(tmp_path: Path) -> None:
    stim = [{"at_ms": 0, "set": {"MD20": _bits(1.5), "MD28": _bits(1.5707964)}}]
    rc, lines = sim_trace(tmp_path, CHART, stim, cycles=2, watch="M1.1,M1.2,e,d,x,MD24")
    assert rc == 0
    values = lines[-1]["values"]
    assert values["M1.1"] is False  # 1.5 > 1.5, not 1069547520 > 1.5
    assert values["MD24"] == _bits(2.5) and values["M1.2"] is True
    assert abs(values["e"] - 1.0) < 1e-6
    assert values["d"] == 2 and values["x"] == 5.0  # ROUND(2.5), 2.5 * 2.0


def test_a_stimulus_gives_words_signed_and_double_words_as_reals(tmp_path: Path) -> None:
    stim = [{"at_ms": 0, "set": {"MW10": -5, "MD30": -7, "MD20": 2.5, "IW0": -1}}]
    rc, lines = sim_trace(tmp_path, CHART, stim, cycles=1, watch="M1.1,M1.3,M1.4,MD20,IW0")
    assert rc == 0
    assert lines[0]["values"] == {
        "M1.1": True,
        "M1.3": True,
        "M1.4": True,
        "MD20": _bits(2.5),
        "IW0": 0xFFFF,
    }
