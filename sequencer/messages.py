"""Interlock and supervision messages of a GRAPH FB in the CPU's message list (docs/semantics.md,
"Messages"; STEP7 comprehensive guide vol. 2, ch. 14).

With ``MESSAGES := TRUE`` every interlock error and supervision fault of a step becomes a message in
``sfb.alarms.MessageList`` with the book's text template (``S7GRAPH Supervision Error: FB1, DB1,
S001 material is missing``), coming and going with the fault and acknowledgeable. The cycle calls
``sync_messages`` once per FB call, after the fault latches are up to date; it diffs the latches in
``GraphState`` against what was already raised, so the cycle needs no other hook. The list records
who acknowledged and when (``program`` for ACK_EF / ACK_S / INIT_SQ, a user name for a remote
acknowledgement) and is persisted through ``MessageList.snapshot``.

Decisions (UNCERTAIN, pinned by tests/sequencer/test_messages.py):
* A supervision message comes when the step's fault latches (``sv_err``) and goes when the
  cause is gone (``sv_cond`` false, or the latch released); it needs acknowledgement when
  EN_ACKREQ is in force. It is acknowledged as ``program`` when the latch is released by
  the FB (ACK_EF, ACK_S, INIT_SQ, OFF_SQ).
* An interlock message comes and goes with ``il_err``; with EN_ACKREQ it needs
  acknowledgement too (ALARM_SQ, as in V5) and is acknowledged as ``program`` by an
  ACK_EF or INIT_SQ edge, or an ACK_S edge for the step shown in S_NO. Acknowledging it
  changes nothing in the sequence (an interlock error clears itself, docs/semantics.md,
  "Interlock").
* A supervision message acknowledged in the list by a user while the step is still latched
  is an acknowledgement of the step, whether or not its cause has gone: ``sync_messages``
  and ``remote_acks`` return those step indices (each occurrence once), and the cycle
  acknowledges them at its next call exactly as ACK_S would. The next ``sync_messages``
  lets that occurrence go; if the cause is still there the fault latches again (V1) and
  comes as a new, unacknowledged message — as after ACK_EF.
* An operator command (ACK_EF, ACK_S, INIT_SQ from the Control Sequencer) acknowledges
  what it releases as the command's user; ``program`` stays for the FB's own pins.
* Which occurrence was raised is remembered in ``GraphState.display["msg"]``
  (msg_id → event id) so a message acknowledged and removed from the list is not raised
  again while its latch lasts.
* A restart acknowledges nothing (``restart``: the startup OB's call): a message whose
  fault the restart cleared goes *outgoing* with the restart as its reason and stays listed
  until someone acknowledges it — also one of this FB the cold-restarted state has
  forgotten.
"""

from __future__ import annotations

from typing import Final

from s7graph.sequencer.compiled import CompiledChart
from s7graph.sequencer.state import GraphState
from s7graph.sfb.alarms import MessageList

PROGRAM_USER: Final = "program"
TEMPLATES: Final = {
    "IL": "S7GRAPH Interlock Error: {fb}, {db}, S{step:03d} {text}",
    "SV": "S7GRAPH Supervision Error: {fb}, {db}, S{step:03d} {text}",
}
SOURCE: Final = "S7-Graph"
_MEMORY_KEY: Final = "msg"
_RELEASED_KEY: Final = "msg_released"  # msg_id -> event id handed to the cycle as an ack


def message_id(fb_name: str, db_number: int, step: int, kind: str) -> str:
    """The message number of one step's interlock (``IL``) or supervision (``SV``) fault."""
    return f"{fb_name}/DB{db_number}/S{step}/{kind}"


def parse_message_id(msg_id: object) -> tuple[str, int, int, str] | None:
    """``(fb, db, step, kind)`` of a ``message_id``; None for any other message number."""
    if not isinstance(msg_id, str):
        return None
    parts = msg_id.rsplit("/", 3)
    if len(parts) != 4 or parts[3] not in TEMPLATES:
        return None
    fb, db, step, kind = parts
    if not (db[:2] == "DB" and db[2:].isdigit() and step[:1] == "S" and step[1:].isdigit()):
        return None
    return fb, int(db[2:]), int(step[1:]), kind


def message_text(chart: CompiledChart, fb_name: str, db_number: int, i: int, kind: str) -> str:
    """The text of step index ``i``'s message: the template with FB, DB, step number and the
    step's own message text (its name when it has none)."""
    step = chart.chart.all_steps()[i]
    fb = f"FB{chart.chart.fb_number}" if chart.chart.fb_number is not None else fb_name
    return TEMPLATES[kind].format(
        fb=fb, db=f"DB{db_number}", step=step.number, text=step.message or step.name
    )


def _memory(state: GraphState) -> dict[str, int]:
    mem = state.display.setdefault(_MEMORY_KEY, {})
    assert isinstance(mem, dict)
    return mem


def remote_acks(
    chart: CompiledChart,
    state: GraphState,
    message_list: MessageList,
    fb_name: str,
    db_number: int,
) -> list[int]:
    """Step indices whose supervision message a user acknowledged in the list while the
    step's fault is still latched, whether or not its cause has gone, and not yet handed to
    the cycle: the cycle acknowledges them as ACK_S would. Pure."""
    if not chart.options.messages:
        return []
    raised = state.display.get(_MEMORY_KEY, {})
    released = state.display.get(_RELEASED_KEY, {})
    found: list[int] = []
    for i, number in enumerate(chart.step_numbers):
        mid = message_id(fb_name, db_number, number, "SV")
        if not state.sv_err[i] or mid not in raised or released.get(mid) == raised[mid]:
            continue
        msg = message_list.get(mid)
        if msg is None or msg.event_id != raised[mid]:
            found.append(i)  # acknowledged and gone from the list
        elif msg.ack_required and msg.acked and msg.ack_user != PROGRAM_USER:
            found.append(i)
    return found


def sync_messages(
    chart: CompiledChart,
    state: GraphState,
    message_list: MessageList,
    fb_name: str,
    db_number: int,
    now_ns: int,
    *,
    user: str = PROGRAM_USER,
    step: int | None = None,
    restart: str = "",
) -> list[int]:
    """Bring the message list in line with this call's fault latches and acknowledgement
    edges (``state.rose``); return ``remote_acks`` (steps the cycle acknowledges at its next
    call). What this call's edges release is acknowledged as ``user`` (an operator's
    command; the FB's own pins: ``program``), ACK_S on ``step`` if given, else S_NO.
    ``restart`` names the restart of a startup OB's call: nothing is acknowledged, what it
    cleared goes outgoing with it as the reason. No-op without MESSAGES."""
    if not chart.options.messages:
        return []
    mem = _memory(state)
    released = state.display.get(_RELEASED_KEY)
    if released:  # handed to the cycle at the last call: that occurrence goes now
        for mid, event in list(released.items()):
            current = message_list.get(mid)
            if mem.get(mid) == event:
                if current is not None and current.event_id == event:
                    message_list.clear(mid, now_ns)
                mem.pop(mid, None)
            del released[mid]
    acks = remote_acks(chart, state, message_list, fb_name, db_number)
    for i, number in enumerate(chart.step_numbers):
        for kind, latched, cause in (
            ("SV", state.sv_err[i], state.sv_err[i] and state.sv_cond[i]),
            ("IL", state.il_err[i], state.il_err[i]),
        ):
            mid = message_id(fb_name, db_number, number, kind)
            if latched and mid not in mem:
                msg = message_list.raise_(
                    mid,
                    now_ns,
                    text=message_text(chart, fb_name, db_number, i, kind),
                    values=(number, chart.step_names[i]),
                    ack_required=state.ackreq_enabled,
                    source=SOURCE,
                )
                mem[mid] = msg.event_id
            current = message_list.get(mid)
            ours = current is not None and current.event_id == mem.get(mid)
            if ours and not cause and current is not None:
                # no-op unless incoming
                message_list.clear(mid, now_ns, reason=restart if not latched else "")
            if ours and kind == "SV" and not latched and not restart:
                message_list.acknowledge(mid, user, now_ns)  # the FB released it
            if not latched:
                mem.pop(mid, None)
    if acks:
        marks = state.display.setdefault(_RELEASED_KEY, {})
        assert isinstance(marks, dict)
        for i in acks:
            mid = message_id(fb_name, db_number, chart.step_numbers[i], "SV")
            if mid in mem:
                marks[mid] = mem[mid]
    if restart:
        _forgotten(message_list, fb_name, db_number, mem, now_ns, restart)
    else:
        _acknowledge_by_inputs(chart, state, message_list, fb_name, db_number, now_ns, user, step)
    return acks


def forget_removed(
    state: GraphState,
    message_list: MessageList,
    fb_name: str,
    db_number: int,
    now_ns: int,
    reason: str = "a download removed its step",
) -> None:
    """After an online change: a message of this FB still incoming for a step the chart no
    longer has goes outgoing, ``reason`` saying why (it stays listed until acknowledged, as
    after a restart); a step that is gone has no fault left to raise or clear it."""
    raised = state.display.get(_MEMORY_KEY, {})
    _forgotten(
        message_list, fb_name, db_number, raised if isinstance(raised, dict) else {}, now_ns, reason
    )


def _forgotten(
    message_list: MessageList,
    fb_name: str,
    db_number: int,
    raised: dict[str, int],
    now_ns: int,
    restart: str,
) -> None:
    """Messages of this FB still incoming although its state no longer knows them (a cold
    restart reset it, a changed chart lost the step): outgoing, the restart as the reason."""
    for msg in message_list.entries():
        where = parse_message_id(msg.msg_id)
        if where is None or where[:2] != (fb_name, db_number):
            continue
        if msg.msg_id not in raised:
            message_list.clear(msg.msg_id, now_ns, reason=restart)


def _acknowledge_by_inputs(
    chart: CompiledChart,
    state: GraphState,
    message_list: MessageList,
    fb_name: str,
    db_number: int,
    now_ns: int,
    user: str = PROGRAM_USER,
    step: int | None = None,
) -> None:
    """ACK_EF / INIT_SQ edges acknowledge every message of this FB, ACK_S those of the step
    shown in S_NO (or ``step``) — except supervision faults the FB still holds latched."""
    rose = state.rose
    target = state.s_no if step is None else step
    if "ACK_EF" in rose or "INIT_SQ" in rose:
        steps = range(chart.n_steps)
    elif "ACK_S" in rose and target in chart.step_index:
        steps = range(chart.step_index[target], chart.step_index[target] + 1)
    else:
        return
    for i in steps:
        number = chart.step_numbers[i]
        if not state.sv_err[i]:
            message_list.acknowledge(message_id(fb_name, db_number, number, "SV"), user, now_ns)
        message_list.acknowledge(message_id(fb_name, db_number, number, "IL"), user, now_ns)
