"""The CPU message list and SFC17 ALARM_SQ / SFC18 ALARM_S / SFC19 ALARM_SC (docs/runtime.md, "The
block runtime"; docs/semantics.md, "Messages")."""

from __future__ import annotations

import json

from s7graph.sfb.alarms import (
    RET_EV_ID_RANGE,
    RET_NOT_OCCUPIED,
    RET_SD_TOO_LONG,
    RET_SIG_UNCHANGED,
    MessageList,
    MessageState,
)

S = 1_000_000_000


def test_alarm_sq_comes_and_goes_on_sig_edges_and_stays_until_acknowledged() -> None:
    ml = MessageList()
    assert ml.alarm(True, 5, 1 * S, sd=(42,)) == 0
    assert ml.alarm(True, 5, 2 * S) == RET_SIG_UNCHANGED  # no edge, no message
    (msg,) = ml.entries()
    assert (msg.msg_id, msg.state, msg.came_ns, msg.values) == (5, MessageState.INCOMING, S, (42,))
    assert ml.alarm(False, 5, 3 * S) == 0
    gone = ml.get(5)
    assert gone is not None and gone.state is MessageState.OUTGOING and not gone.acked
    acked = ml.acknowledge(5, "operator", 4 * S)
    assert acked is not None and (acked.ack_user, acked.ack_ns) == ("operator", 4 * S)
    assert ml.entries() == ()
    assert [e.kind for e in ml.log()] == ["incoming", "outgoing", "acknowledged"]


def test_alarm_s_needs_no_acknowledgement_and_leaves_when_it_goes() -> None:
    ml = MessageList()
    ml.alarm(True, 6, 0, ack=False)
    assert ml.acknowledge(6, "operator", 1) is None
    ml.alarm(False, 6, 2, ack=False)
    assert ml.entries() == ()


def test_alarm_sc_reports_signal_and_acknowledgement_state() -> None:
    ml = MessageList()
    assert ml.alarm_sc(9)[0] == RET_NOT_OCCUPIED
    ml.alarm(True, 9, 0)
    assert ml.alarm_sc(9) == (0, True, False)
    ml.acknowledge(9, "op", 1)
    assert ml.alarm_sc(9) == (0, True, True)


def test_ret_val_conventions_of_the_alarm_sfcs() -> None:
    """Errors are negative (8081 EV_ID 0), warnings positive (0001 SD > 12 B)."""
    ml = MessageList()
    assert ml.alarm(True, 0, 0) == RET_EV_ID_RANGE < 0
    assert ml.alarm(True, 1, 0, sd_bytes=16) == RET_SD_TOO_LONG > 0
    assert RET_SIG_UNCHANGED == 0x8084 - 0x10000


def test_acknowledging_an_incoming_message_keeps_it_listed_until_it_goes() -> None:
    ml = MessageList()
    ml.raise_("FB1/DB1/S3/SV", 0, text="S003 material is missing")
    ml.acknowledge("FB1/DB1/S3/SV", "op", 1)
    assert len(ml.entries()) == 1
    ml.clear("FB1/DB1/S3/SV", 2)
    assert ml.entries() == ()


def test_a_new_occurrence_gets_a_new_event_id_and_raise_is_idempotent_while_incoming() -> None:
    ml = MessageList()
    first = ml.raise_("k", 0)
    assert ml.raise_("k", 5) is first
    ml.clear("k", 6)
    second = ml.raise_("k", 7)  # came again before the first was acknowledged
    assert second.event_id > first.event_id and not second.acked


def test_pop_events_reports_changes_once() -> None:
    ml = MessageList()
    ml.raise_("a", 0)
    ml.clear("a", 1)
    assert [e.kind for e in ml.pop_events()] == ["incoming", "outgoing"]
    assert ml.pop_events() == ()


def test_the_message_list_survives_a_json_snapshot_round_trip() -> None:
    ml = MessageList()
    ml.alarm(True, 5, 1, sd=(42,))
    ml.raise_("il", 2, text="interlock", values=(3, "Clamp"))
    ml.acknowledge(5, "op", 3)
    copy = MessageList()
    copy.restore(json.loads(json.dumps(ml.snapshot())))
    assert copy.entries() == ml.entries()
    assert copy.log() == ml.log()
    assert copy.alarm(True, 5, 4) == RET_SIG_UNCHANGED  # the SIG edge memory came along
    assert copy.raise_("new", 5).event_id == ml.raise_("new", 5).event_id
