"""The FB pin table and parameter sets (docs/semantics.md, "FB pins" and "Decisions")."""

from __future__ import annotations

import itertools

import pytest

from s7graph.engine.errors import SourceLocation
from s7graph.sequencer.params import (
    PARAMETER_SETS,
    PINS,
    Direction,
    PinError,
    check_pin,
    input_defaults,
    markdown_table,
    output_defaults,
    pin,
    pins_for,
)
from s7graph.sequencer.text.model import ChartOptions
from tests.paths import ROOT


def words(text: str) -> list[str]:
    return text.split()


def names(set_name: str, direction: Direction) -> set[str]:
    return {p.name for p in pins_for(set_name) if p.direction is direction}


def test_minimum_set_has_only_init_sq() -> None:
    assert [p.name for p in pins_for("MINIMUM")] == ["INIT_SQ"]


def test_standard_set_is_exactly_the_spec_list() -> None:
    assert names("STANDARD", Direction.IN) == set(
        words(
            "OFF_SQ INIT_SQ ACK_EF S_PREV S_NEXT SW_AUTO SW_TAP SW_TOP SW_MAN S_SEL S_ON "
            "S_OFF T_PUSH"
        )
    )
    assert names("STANDARD", Direction.OUT) == set(
        words("S_NO S_MORE S_ACTIVE ERR_FLT AUTO_ON TAP_ON TOP_ON MAN_ON")
    )


def test_maximum_set_adds_halt_zero_and_enables_to_standard() -> None:
    assert names("MAXIMUM", Direction.IN) - names("STANDARD", Direction.IN) == {
        "HALT_SQ",
        "HALT_TM",
        "ZERO_OP",
        "EN_IL",
        "EN_SV",
    }
    assert names("MAXIMUM", Direction.OUT) - names("STANDARD", Direction.OUT) == {
        "SQ_HALTED",
        "TM_HALTED",
        "OP_ZEROED",
        "IL_ENABLED",
        "SV_ENABLED",
    }


def test_user_set_is_every_pin_of_graph_semantics_d2() -> None:
    d2_in = words(
        "OFF_SQ INIT_SQ ACK_EF REG_EF ACK_S REG_S HALT_SQ HALT_TM ZERO_OP EN_IL EN_SV "
        "EN_ACKREQ EN_SSKIP DISP_SACT DISP_SEF DISP_SALL S_PREV S_NEXT SW_AUTO SW_TAP SW_TOP "
        "SW_MAN S_SEL S_SELOK S_ON S_OFF T_PREV T_NEXT T_PUSH"
    )
    d2_out = words(
        "S_NO S_MORE S_ACTIVE S_TIME S_TIMEOK S_CRITLOC S_CRITLOCERR S_CRITSUP S_STATE T_NO "
        "T_MORE T_CRIT T_CRITOLD T_CRITFLT ERROR FAULT ERR_FLT SQ_ISOFF SQ_HALTED TM_HALTED "
        "OP_ZEROED IL_ENABLED SV_ENABLED ACKREQ_ENABLED SSKIP_ENABLED SACT_DISP SEF_DISP "
        "SALL_DISP AUTO_ON TAP_ON TOP_ON MAN_ON"
    )
    user = pins_for("USER")
    assert [p.name for p in user if p.direction is Direction.IN] == d2_in
    assert [p.name for p in user if p.direction is Direction.OUT] == d2_out
    assert len(user) == len(PINS)


def test_parameter_sets_nest() -> None:
    for small, big in itertools.pairwise(PARAMETER_SETS):
        assert {p.name for p in pins_for(small)} < {p.name for p in pins_for(big)}


def test_pin_types_follow_the_seed_interface() -> None:
    types = {p.name: p.type for p in PINS}
    assert types["S_SEL"] == "INT" and types["S_NO"] == "INT" and types["T_NO"] == "INT"
    assert types["S_TIME"] == "TIME" and types["S_TIMEOK"] == "TIME"
    assert types["S_STATE"] == "WORD"
    for dword in ("S_CRITLOC", "S_CRITLOCERR", "S_CRITSUP", "T_CRIT", "T_CRITOLD", "T_CRITFLT"):
        assert types[dword] == "DWORD"
    others = set(types) - {"S_SEL", "S_NO", "T_NO", "S_TIME", "S_TIMEOK", "S_STATE"}
    assert {types[n] for n in others} - {"DWORD"} == {"BOOL"}


def test_pin_lookup_is_case_insensitive_and_unknown_is_none() -> None:
    found = pin("halt_sq")
    assert found is not None and found.name == "HALT_SQ" and found.sets == ("MAXIMUM", "USER")
    assert pin("NOT_A_PIN") is None


def test_check_pin_outside_the_set_names_the_sets_that_have_it() -> None:
    with pytest.raises(PinError) as err:
        check_pin("HALT_SQ", "STANDARD", SourceLocation("stim.jsonl", 3, 1))
    text = str(err.value)
    assert "stim.jsonl:3:1" in text
    assert "pin HALT_SQ is not in parameter set STANDARD; use PARAMETERS := MAXIMUM or USER" in text


def test_check_pin_rejects_unknown_names_and_wrong_directions() -> None:
    with pytest.raises(PinError, match="not an FB pin"):
        check_pin("FOO", "USER")
    with pytest.raises(PinError, match="S_NO is an OUT pin"):
        check_pin("S_NO", "USER", direction=Direction.IN)
    with pytest.raises(PinError, match="unknown parameter set"):
        check_pin("INIT_SQ", "HUGE")
    assert check_pin("init_sq", "minimum").name == "INIT_SQ"


def test_enables_default_true_and_options_set_ack_and_skip_defaults() -> None:
    plain = input_defaults("STANDARD")
    assert plain["EN_IL"] is True and plain["EN_SV"] is True and plain["EN_ACKREQ"] is True
    assert plain["OFF_SQ"] is False and plain["S_SEL"] == 0 and plain["DISP_SACT"] is False
    opts = input_defaults("STANDARD", ChartOptions(ack_required=False, skip_steps=True))
    assert opts["EN_ACKREQ"] is False and opts["EN_SSKIP"] is True


def test_output_defaults_cover_only_the_set() -> None:
    assert output_defaults("STANDARD") == {
        "S_NO": 0,
        "S_MORE": False,
        "S_ACTIVE": False,
        "ERR_FLT": False,
        "AUTO_ON": True,
        "TAP_ON": False,
        "TOP_ON": False,
        "MAN_ON": False,
    }
    assert output_defaults("MINIMUM") == {}


def test_markdown_table_has_a_row_per_pin_with_set_marks() -> None:
    table = markdown_table()
    lines = table.strip().splitlines()
    assert len(lines) == 2 + len(PINS)
    assert lines[0].startswith("| Pin | Dir | Type | MINIMUM | STANDARD | MAXIMUM | USER |")
    halt = next(line for line in lines if line.startswith("| `HALT_SQ`"))
    assert halt.count("✓") == 2
    init = next(line for line in lines if line.startswith("| `INIT_SQ`"))
    assert init.count("✓") == 4


def test_the_semantics_doc_holds_the_pin_table_of_the_code() -> None:
    """The one pin table is the code's: docs/semantics.md prints it verbatim (the README's
    copy moved there)."""
    root = ROOT
    for doc in (root / "docs" / "semantics.md",):
        assert markdown_table() in doc.read_text(encoding="utf-8"), doc.name
