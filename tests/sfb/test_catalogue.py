"""The one catalogue of system blocks and the RET_VAL conventions (STEP7 comprehensive guide vol. 2,
ch. 12)."""

from __future__ import annotations

import pytest

from s7graph.engine.errors import BlockError
from s7graph.sfb.catalogue import (
    CATALOGUE,
    Direction,
    as_int,
    as_word,
    br_of,
    find,
    general_error,
    is_error,
    lookup,
)


def test_lookup_by_key_with_or_without_blank_and_by_name() -> None:
    ton = lookup("SFB4")
    assert lookup("SFB 4") is ton and lookup("ton") is ton
    assert [(p.name, p.direction, p.type) for p in ton.pins] == [
        ("IN", Direction.IN, "BOOL"),
        ("PT", Direction.IN, "TIME"),
        ("Q", Direction.OUT, "BOOL"),
        ("ET", Direction.OUT, "TIME"),
    ]
    assert find("SFB99") is None
    with pytest.raises(BlockError, match="SFB99"):
        lookup("SFB99")


def test_the_catalogue_covers_spec_1_7() -> None:
    keys = {e.key for e in CATALOGUE}
    wanted = {
        "SFB0",
        "SFB1",
        "SFB2",
        "SFB3",
        "SFB4",
        "SFB5",
        "SFC0",
        "SFC1",
        "SFC17",
        "SFC18",
        "SFC20",
        "SFC21",
        "SFC43",
        "SFC46",
        "SFC47",
        "SFC51",
        "SFC52",
        "SFC64",
    }
    assert wanted <= keys
    assert len(keys) == len(CATALOGUE)


def test_check_call_validates_pins_directions_and_instance() -> None:
    ton = lookup("TON")
    assert ton.check_call(["IN", "PT"], ["Q"], has_instance=True) == []
    problems = ton.check_call(["IN", "XX", "Q"], ["PT"], has_instance=False)
    assert len(problems) == 4
    assert any("needs an instance DB" in p for p in problems)
    assert any("no parameter XX" in p for p in problems)
    assert lookup("STP").check_call(has_instance=True) == [
        "SFC46 STP is an SFC and takes no instance DB"
    ]


def test_ret_val_words_are_negative_ints_on_error() -> None:
    """Bit 15 set <=> RET_VAL < 0 <=> BR = 0."""
    assert general_error(1, 0x22) == as_int(0x8122) == -32478
    assert as_word(-32478) == 0x8122
    assert is_error(-1) and not br_of(-1)
    assert not is_error(0) and br_of(1)
