"""How a GRAPH FB's state is kept in the state file (``GraphState.state_view``): a per-step
or per-transition list that holds nothing but its fill (no interlock error anywhere, no
criteria, ...) is kept as ``{"fill": value}``, the running step times as ``[step index,
activation time]`` pairs; ``from_state`` reads these and the full lists of state file
format 4 alike, and refuses a compact form it cannot place."""

from __future__ import annotations

from typing import Any

import msgspec
import pytest

from s7graph.sequencer.state import GraphState

MS = 1_000_000


def _running() -> GraphState:
    """Five steps, S3 (index 2) active for 40 ms at 1 s, its interlock error set."""
    st = GraphState(5, 4)
    st.last_ns = 1000 * MS
    st.x[2] = True
    st.active = [2]
    st.t_ns[2] = st.u_ns[2] = 40 * MS
    st.t_ns[0] = 7 * MS  # S1 ran 7 ms, earlier
    st.il_err[2] = True
    st.crit[1] = 0b101
    st.tt[3] = True
    return st


def _on_disk(data: dict[str, Any]) -> dict[str, Any]:
    out: dict[str, Any] = msgspec.msgpack.decode(msgspec.msgpack.encode(data))
    return out


def test_a_list_that_holds_only_its_fill_is_kept_as_the_fill() -> None:
    view = _running().state_view()
    assert view["sv_err"] == {"fill": False}
    assert view["il_ok"] == {"fill": True}
    assert view["crit_flt"] == {"fill": 0}
    assert view["il_err"] == [False, False, True, False, False]  # in use: the list itself
    assert view["crit"] == [0, 0b101, 0, 0]


def test_running_step_times_are_kept_as_activation_times_of_the_running_steps() -> None:
    view = _running().state_view()
    assert view["t_since"] == {"fill": None, "at": [[2, 960 * MS]]}
    assert view["u_since"] == {"fill": None, "at": []}  # U stands still: interlock error
    assert view["t_ns"][2] is None and view["t_ns"][0] == 7 * MS


def test_the_compact_form_restores_exactly_as_the_full_one() -> None:
    st = _running()
    compact = GraphState.from_state(_on_disk(st.state_view()))
    full = GraphState.from_state(_on_disk(st.to_state()))
    assert compact == full == st
    assert compact.step_t_ms(2) == 40 and compact.il_err == st.il_err


def test_a_state_of_format_4_with_every_list_in_full_is_read() -> None:
    full = _on_disk(_running().to_state())
    assert full["sv_err"] == [False] * 5 and full["t_since"][2] == 960 * MS
    assert GraphState.from_state(full) == _running()


@pytest.mark.parametrize(
    ("key", "value", "fragment"),
    [
        ("sv_err", {"fill": False, "at": [[5, True]]}, "'sv_err' has an entry [5, True]"),
        ("sv_err", {"fill": 1}, "'sv_err' holds a non-boolean"),
        ("crit", {"fill": 0, "more": 1}, "'crit' is"),
        ("crit", {"at": []}, "'crit' is"),
        ("ev", {"fill": 0, "at": "x"}, "'ev' is"),
        ("t_since", {"fill": None, "at": [[2, "soon"]]}, "'t_since' holds a non-integer"),
        ("t_since", {"fill": None, "at": [[True, 3]]}, "'t_since' has an entry"),
    ],
)
def test_a_compact_list_that_does_not_fit_is_refused(
    key: str, value: object, fragment: str
) -> None:
    data = _on_disk(_running().state_view())
    data[key] = value
    with pytest.raises(ValueError) as refused:
        GraphState.from_state(data)
    assert fragment in str(refused.value)


@pytest.mark.parametrize(
    ("key", "value", "fragment"),
    [
        ("levels", {"HALT_SQ": None}, "'levels' is {'HALT_SQ': None}"),
        ("levels", {"S_ON": True}, "'levels' is"),
        ("levels", [["EN_IL", True]], "'levels' is"),
        ("to_level", {"EN_SV": 1}, "'to_level' is {'EN_SV': 1}"),
        ("to_level", {"INIT_SQ": None}, "'to_level' is"),
    ],
)
def test_level_overrides_that_are_not_a_level_pins_bool_are_refused(
    key: str, value: object, fragment: str
) -> None:
    """In force (``levels``) an override is TRUE or FALSE; queued (``to_level``) it may
    also be null, the pin deciding again from the next call."""
    data = _on_disk(_running().state_view())
    data[key] = value
    with pytest.raises(ValueError) as refused:
        GraphState.from_state(data)
    assert fragment in str(refused.value)


def test_level_overrides_in_force_and_queued_are_read_back() -> None:
    st = _running()
    st.levels = {"HALT_SQ": True}
    st.to_level = {"HALT_SQ": None, "EN_IL": False}
    back = GraphState.from_state(_on_disk(st.state_view()))
    assert back.levels == {"HALT_SQ": True}
    assert back.to_level == {"HALT_SQ": None, "EN_IL": False}
