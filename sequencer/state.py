"""GraphState: the content of a GRAPH FB's instance DB (docs/semantics.md, "One FB call" and "FB
pins", docs/architecture.md, "The core is a function").

Everything the cycle remembers between calls lives here, in flat lists indexed by the
compiled step index ``i`` (``0 .. n_steps-1``, see ``CompiledChart.step_numbers``) and the
compiled transition index ``j`` (``CompiledChart.transition_numbers``). No per-call
allocation per step: the cycle updates the lists in place. ``to_state``/``from_state`` give a
JSON-able snapshot that restores exactly (persistence, online change, hot standby).

Field names are a contract with ``sequencer/display.py`` and ``sequencer/messages.py``
(which compute S_NO, S_STATE, criteria outputs and alarms from this object) — never rename.

Times are integer nanoseconds of the injected clock; ``step_t_ms``/``step_u_ms`` give the
S7 TIME values (ms) that ``Sn.T``/``Sn.U`` read.

On disk (``to_state``) a running step time is kept as its activation timestamp — the clock
time at which it was 0 (``t_since``/``u_since``; ``t_ns``/``u_ns`` then ``None``) — and a frozen
one (step inactive, U during a disturbance, HALT_TM) as its value, so a call that switched
nothing leaves the snapshot as it was, but for the ``VOLATILE`` keys (the call counter and
the clock time of the last call: saved with every write, never a reason for one).
``from_state`` turns them back into the values they had at ``last_ns``, and checks every
field (ValueError: a malformed state is refused, never half restored).

The state file (``state_view``, since state file format 5) keeps a per-step or
per-transition list that holds nothing but its fill (``_FILL``: False, 0, True for ``il_ok``)
as ``{"fill": value}``, and the activation timestamps as ``{"fill": None, "at": [[step
index, timestamp], ...]}``: most lists of a large chart say that nothing happened, and
hundreds of entries saying so cost the encoding every scan. ``from_state`` reads both
forms.
"""

from __future__ import annotations

from typing import Any, Final

MODES: Final = ("AUTO", "MAN", "TAP", "TOP")
STEP_TIME_LIMIT_NS: Final = 10 * 36525 * 86_400 * 10**9 // 100
"""The longest step time (T, U) a saved state may hold: 10 years. More is no run's count
but a garbled value (S7's own TIME ends at T#24D20H31M23S647MS; the runtime counts on past
it, so a step may wait longer than that and still be restarted)."""
LEVEL_PINS: Final = ("HALT_SQ", "EN_IL", "EN_SV")
"""The level pins an operator or engineer may hold at a value (``GraphFB.set_level``)."""
Command = tuple[str, int | None, str | None]
"""An operator command queued for the next call (``GraphFB.command``): the pin, the step
number it acts on (S_ON, S_OFF, ACK_S) or None, and the user it acts as or None."""

# Inputs whose rising edge (not level) counts (docs/semantics.md, "One FB call", step 1 and "Modes"
# and "FB pins").
EDGE_INPUTS: Final = (
    "INIT_SQ",
    "ACK_EF",
    "ACK_S",
    "REG_EF",
    "REG_S",
    "S_ON",
    "S_OFF",
    "T_PUSH",
    "SW_AUTO",
    "SW_MAN",
    "SW_TAP",
    "SW_TOP",
    "S_PREV",
    "S_NEXT",
    "T_PREV",
    "T_NEXT",
    "S_SELOK",
    "DISP_SACT",
    "DISP_SEF",
    "DISP_SALL",
)
COMMAND_PINS: Final = frozenset((*EDGE_INPUTS, "OFF_SQ"))
"""The pins an operator command may act as (``GraphFB.command``): a saved queue holding
another is refused."""

STEP_LISTS: Final = (
    "x",
    "t_ns",
    "u_ns",
    "act_ns",
    "il_ok",
    "il_err",
    "sv_cond",
    "sv_err",
    "crit_loc",
    "crit_loc_err",
    "crit_sup",
)
"""The per-step lists that hold from one call to the next: ``carry_over`` takes them to
another chart version by step number. The other per-step list, ``ev``, is this call's."""
TRANSITION_LISTS: Final = ("tt", "crit", "crit_old", "crit_flt")
"""The per-transition lists (``carry_over`` takes them over by transition number)."""
_STEP_LISTS: Final = (*STEP_LISTS, "ev")
_LIST_FIELDS: Final = (*_STEP_LISTS, *TRANSITION_LISTS)
_BOOL_LISTS: Final = frozenset(("x", "il_ok", "il_err", "sv_cond", "sv_err", "tt"))
_FILL: Final = {name: name == "il_ok" if name in _BOOL_LISTS else 0 for name in _LIST_FIELDS}
"""What each per-step / per-transition list holds where nothing happened (a new state); the
state file keeps a list that holds only that as ``{"fill": value}`` (``state_view``)."""
_SCALAR_FIELDS: Final = (
    "mode",
    "calls",
    "last_ns",
    "off",
    "halted",
    "tm_halted",
    "zeroed",
    "il_enabled",
    "sv_enabled",
    "ackreq_enabled",
    "sskip_enabled",
    "error",
    "fault",
    "err_flt",
    "ov",
    "ov_count",
    "s_no",
    "t_no",
)


class GraphState:
    """The instance-DB content of one GRAPH FB.

    Per step ``i``:
      ``x[i]``            step active (``Sn.X``)
      ``t_ns[i]``         activation time accumulator (``Sn.T``; keeps the last value after exit)
      ``u_ns[i]``         activation time without disturbance (``Sn.U``; frozen while the step
                          has an interlock error or a supervision fault)
      ``act_ns[i]``       clock time of the last activation
      ``il_ok[i]``        interlock condition holds now (LS; True without interlock / EN_IL=0)
      ``il_err[i]``       step active and interlock not held (LA: disturbed, red)
      ``sv_cond[i]``      supervision condition true now (VS: the fault cause is present)
      ``sv_err[i]``       supervision fault, latched until acknowledged when ack is required
                          (VA / H_SV_FLT); blocks the step's transitions
      ``crit_loc[i]``     interlock criteria bits of this call (bit k = k-th contact true)
      ``crit_loc_err[i]`` copy of ``crit_loc`` taken when the interlock was lost
      ``crit_sup[i]``     supervision criteria bits of this call
      ``ev[i]``           step event bits of this call (``EV_S1`` ... ``EV_R1``)
    Per transition ``j``:
      ``tt[j]``           condition held at its last evaluation (``Tn.TT``)
      ``crit[j]``         criteria bits of this call; ``crit_old[j]`` those of the previous
                          evaluation; ``crit_flt[j]`` copy taken when a preceding step faulted
    Lists of this call (cleared at the start of each call):
      ``active``          active step indices, in activation order (the cycle's work list)
      ``ev_steps``        step indices whose ``ev`` is non-zero in this call
      ``fired``           transition indices that switched in this call, in switching order
      ``entered``/``left`` step indices activated / deactivated in this call
      ``log``             events raised in this call, in order: (step index, ``EV_*`` bit)
    Scalars:
      ``mode``            "AUTO" "MAN" "TAP" "TOP" (survives warm restart)
      ``inputs``          FB input pins latched at the start of this call (name → value)
      ``prev``            edge memories: each edge input's value in the previous call
      ``rose``            names of edge inputs with a rising edge in this call
      ``outputs``         FB output pins written at the end of this call (name → value)
      ``vars``            the chart's static variables (``VAR ... END_VAR``)
      ``off``             OFF_SQ holds in this call (SQ_ISOFF is "no step active");
                          ``halted`` SQ_HALTED; ``tm_halted`` TM_HALTED;
      ``zeroed``          OP_ZEROED; ``il_enabled`` ``sv_enabled`` ``ackreq_enabled``
                          ``sskip_enabled`` — the effective options of this call
      ``error``           some active step has an interlock error (ERROR)
      ``fault``           some step has a supervision fault (FAULT)
      ``err_flt``         ``error or fault`` (ERR_FLT)
      ``ov``              an arithmetic overflow happened in this call (OV status);
                          ``ov_count`` how many so far; ``diag`` the last messages (≤ 16)
      ``calls``           number of FB calls; ``last_ns`` clock time of the previous call
                          (-1 before the first)
      ``s_no`` ``t_no``   step / transition shown (owned by ``display.py``)
      ``display``         free scratch of ``display.py`` (persisted, JSON-able)
      ``repin``           the input pins the chart's own rows wrote in this call (not
                          saved: the call ends by writing them into the instance DB)
      ``levels``          level overrides in force (``LEVEL_PINS`` → value): HALT_SQ, EN_IL or
                          EN_SV held by a command whatever the pin; part of the instance DB, so
                          a warm or hot restart keeps them and a cold restart clears them
      ``to_enter``        step *numbers* made active outside a call (an online change's new
                          sequencer, ``GraphFB.enter``) whose S1 is the next call's
      ``to_place``        step *numbers* to place in the next call (``GraphFB.place``);
                          both part of the instance DB, as ``levels``: a restart from the
                          state file carries them out once, in its first call (a cold
                          restart clears them); numbers, so they outlive a chart change
      ``to_command``      operator commands for the next call (``GraphFB.command``: ``Command``
                          = pin, step number or None, user or None), in order
      ``to_level``        level overrides the next call puts in force (``LEVEL_PINS`` → value,
                          None: back to the pin; ``GraphFB.set_level``)
      ``to_release``      step *numbers* whose supervision message a user acknowledged: the
                          next call releases them as ACK_S would (``sequencer.messages``); all
                          three kept as ``to_place``: committed with the scan that took them,
                          carried out once in the first call after a warm or hot restart
    """

    __slots__ = (
        *_LIST_FIELDS,
        *_SCALAR_FIELDS,
        "n_steps",
        "n_transitions",
        "active",
        "ev_steps",
        "fired",
        "entered",
        "left",
        "log",
        "inputs",
        "prev",
        "rose",
        "outputs",
        "vars",
        "diag",
        "display",
        "levels",
        "to_enter",
        "to_place",
        "to_command",
        "to_level",
        "to_release",
        "repin",
    )

    VOLATILE: Final = ("calls", "last_ns")
    """Keys of ``to_state`` that change with every call without changing the state."""

    def __init__(self, n_steps: int, n_transitions: int) -> None:
        self.n_steps = n_steps
        self.n_transitions = n_transitions
        self.x: list[bool] = [False] * n_steps
        self.t_ns: list[int] = [0] * n_steps
        self.u_ns: list[int] = [0] * n_steps
        self.act_ns: list[int] = [0] * n_steps
        self.il_ok: list[bool] = [True] * n_steps
        self.il_err: list[bool] = [False] * n_steps
        self.sv_cond: list[bool] = [False] * n_steps
        self.sv_err: list[bool] = [False] * n_steps
        self.crit_loc: list[int] = [0] * n_steps
        self.crit_loc_err: list[int] = [0] * n_steps
        self.crit_sup: list[int] = [0] * n_steps
        self.ev: list[int] = [0] * n_steps
        self.tt: list[bool] = [False] * n_transitions
        self.crit: list[int] = [0] * n_transitions
        self.crit_old: list[int] = [0] * n_transitions
        self.crit_flt: list[int] = [0] * n_transitions
        self.active: list[int] = []
        self.ev_steps: list[int] = []
        self.fired: list[int] = []
        self.entered: list[int] = []
        self.left: list[int] = []
        self.log: list[tuple[int, int]] = []
        self.mode: str = "AUTO"
        self.inputs: dict[str, Any] = {}
        self.prev: dict[str, bool] = {}
        self.rose: set[str] = set()
        self.outputs: dict[str, Any] = {}
        self.vars: dict[str, Any] = {}
        self.off = False
        self.halted = False
        self.tm_halted = False
        self.zeroed = False
        self.il_enabled = True
        self.sv_enabled = True
        self.ackreq_enabled = True
        self.sskip_enabled = False
        self.error = False
        self.fault = False
        self.err_flt = False
        self.ov = False
        self.ov_count = 0
        self.diag: list[str] = []
        self.calls = 0
        self.last_ns = -1
        self.s_no = 0
        self.t_no = 0
        self.display: dict[str, Any] = {}
        self.levels: dict[str, bool] = {}
        self.to_enter: list[int] = []  # step numbers whose S1 is the next call's
        self.to_place: list[int] = []  # step numbers to place in the next call
        self.to_command: list[Command] = []  # operator commands for the next call
        self.to_level: dict[str, bool | None] = {}  # level overrides for the next call
        self.to_release: list[int] = []  # step numbers a message's acknowledgement releases
        self.repin: list[str] = []  # input pins the chart's rows wrote in this call

    # ------------------------------------------------------------ reading times (S7 TIME, ms)

    def step_t_ms(self, i: int) -> int:
        """``Sn.T`` of step index ``i`` in milliseconds."""
        return self.t_ns[i] // 1_000_000

    def step_u_ms(self, i: int) -> int:
        """``Sn.U`` of step index ``i`` in milliseconds."""
        return self.u_ns[i] // 1_000_000

    def disturbed(self, i: int) -> bool:
        """The step shows red: interlock error or supervision fault (SERRX)."""
        return self.il_err[i] or self.sv_err[i]

    # ------------------------------------------------------------ persistence

    def to_state(self) -> dict[str, Any]:
        """A JSON-able snapshot (running times as activation timestamps, see the module
        docstring), every list in full; ``from_state`` restores it exactly."""
        return {
            key: list(value)
            if type(value) is list
            else dict(value)
            if type(value) is dict
            else value
            for key, value in self._view(compact=False).items()
        }

    def state_view(self) -> dict[str, Any]:
        """What ``to_state`` returns, but sharing this state's lists and dicts (the step
        times aside, which it computes) and with the lists that hold little kept compact
        (``compact``): to be encoded at once and never kept, since the next call changes it
        in place. What the state file's staging reads every scan: no copies of per-step
        lists it only encodes, and no hundreds of entries that say nothing happened."""
        return self._view(compact=True)

    def _view(self, *, compact: bool) -> dict[str, Any]:
        data: dict[str, Any] = {"n_steps": self.n_steps, "n_transitions": self.n_transitions}
        for name, fill in _FILL.items():
            value = getattr(self, name)
            if (  # the ends first (a list in use seldom has fill at both), then count
                compact
                and value
                and value[0] == fill
                and value[-1] == fill
                and value.count(fill) == len(value)
            ):
                value = {"fill": fill}
            data[name] = value
        for name in _SCALAR_FIELDS:
            data[name] = getattr(self, name)
        last = self.last_ns
        t_since: list[list[int]] = []  # [step index, activation time] of the running steps
        u_since: list[list[int]] = []
        if last >= 0 and not self.tm_halted and self.active:
            t_ns: list[int | None] = list(self.t_ns)
            u_ns: list[int | None] = list(self.u_ns)
            data["t_ns"], data["u_ns"] = t_ns, u_ns
            il_err, sv_err = self.il_err, self.sv_err
            for i in self.active:
                t_since.append([i, last - self.t_ns[i]])
                t_ns[i] = None
                if not (il_err[i] or sv_err[i]):
                    u_since.append([i, last - self.u_ns[i]])
                    u_ns[i] = None
        for key, at in (("t_since", t_since), ("u_since", u_since)):
            kept = {"fill": None, "at": at}
            data[key] = kept if compact else _expand(kept, key, self.n_steps)
        data["active"] = self.active
        data["inputs"] = self.inputs
        data["prev"] = self.prev
        data["outputs"] = self.outputs
        data["vars"] = self.vars
        data["diag"] = self.diag
        data["display"] = self.display
        data["levels"] = self.levels
        data["to_enter"] = self.to_enter
        data["to_place"] = self.to_place
        data["to_command"] = [list(c) for c in self.to_command]
        data["to_level"] = self.to_level
        data["to_release"] = self.to_release
        return data

    @classmethod
    def from_state(cls, data: dict[str, Any]) -> GraphState:
        """Rebuild a state from ``to_state`` output (per-call lists start empty); ValueError
        (or TypeError) for a malformed one."""
        if not isinstance(data, dict):
            raise ValueError(f"a sequencer state is an object, not {type(data).__name__}")
        n, m = _count(data, "n_steps"), _count(data, "n_transitions")
        st = cls(n, m)
        for name in _LIST_FIELDS:
            setattr(st, name, _list(data, name, n if name in _STEP_LISTS else m))
        for name in _SCALAR_FIELDS:
            if name not in data:
                raise ValueError(f"no {name!r}")
            value = data[name]
            if not isinstance(value, type(getattr(st, name))) and not (
                isinstance(value, int) and isinstance(getattr(st, name), int)
            ):
                raise ValueError(f"{name!r} is {value!r}")
            setattr(st, name, value)
        if st.mode not in MODES:
            raise ValueError(f"unknown mode {st.mode!r}")
        last = st.last_ns
        for times, key in ((st.t_ns, "t_since"), (st.u_ns, "u_since")):
            since = _expand(data.get(key) or [None] * n, key, n)
            if not isinstance(since, list) or len(since) != n:
                raise ValueError(f"{key!r} does not hold {n} entries")
            for i, (value, mark) in enumerate(zip(times, since, strict=True)):
                if isinstance(mark, int):
                    times[i] = last - mark
                elif mark is not None:
                    raise ValueError(f"{key!r} holds a non-integer")
                elif not isinstance(value, int):
                    raise ValueError(f"{key[0]}_ns[{i}] is {value!r}")
                if not 0 <= times[i] <= STEP_TIME_LIMIT_NS:
                    raise ValueError(f"step index {i}: {key[0].upper()} = {_span(times[i])}")
        active = data["active"]
        if not isinstance(active, list) or any(
            not isinstance(i, int) or not 0 <= i < n for i in active
        ):
            raise ValueError(f"'active' is {active!r}")
        if sorted(active) != [i for i in range(n) if st.x[i]]:
            raise ValueError("'active' and 'x' disagree")
        st.active = [int(i) for i in active]
        # The event bits of the last call are cleared by the next, as without the restart
        # (``ev_steps`` says which): left set, an S1 action would run again in every call.
        st.ev_steps = [i for i, e in enumerate(st.ev) if e]
        for name in ("inputs", "prev", "outputs", "vars", "display"):
            value = data.get(name, {})
            if not isinstance(value, dict):
                raise ValueError(f"{name!r} is {value!r}")
            setattr(st, name, dict(value))
        st.diag = list(data.get("diag", []))
        st.levels = _levels(data, "levels")  # absent in a state from before overrides were kept
        for name in ("to_enter", "to_place", "to_release"):  # absent in a state from before
            numbers = data.get(name, [])
            if not isinstance(numbers, list) or any(type(n) is not int for n in numbers):
                raise ValueError(f"{name!r} is {numbers!r}")
            setattr(st, name, list(numbers))
        st.to_command = _commands(data.get("to_command", []))  # absent before: none queued
        st.to_level = _levels(data, "to_level", lifted=True)
        return st

    def __eq__(self, other: object) -> bool:
        return isinstance(other, GraphState) and self.to_state() == other.to_state()

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        return f"GraphState(active={self.active}, mode={self.mode}, calls={self.calls})"


def _levels(data: dict[str, Any], key: str, *, lifted: bool = False) -> dict[str, Any]:
    """``levels`` or ``to_level`` as saved (none when absent): a map of level pins to a
    BOOL, or to null where ``lifted`` (an override the next call lifts); anything else is
    refused (ValueError)."""
    value = data.get(key, {})
    if not isinstance(value, dict) or any(
        pin not in LEVEL_PINS or not (isinstance(v, bool) or (lifted and v is None))
        for pin, v in value.items()
    ):
        raise ValueError(f"{key!r} is {value!r}")
    return dict(value)


def _commands(value: object) -> list[Command]:
    """``to_command`` as saved (lists of pin, step number or null, user or null); a pin
    that is no command's, or an entry of another shape, is refused (ValueError)."""
    if not isinstance(value, list):
        raise ValueError(f"'to_command' is {value!r}")
    out: list[Command] = []
    for entry in value:
        if (
            not isinstance(entry, list | tuple)
            or len(entry) != 3
            or entry[0] not in COMMAND_PINS
            or not (entry[1] is None or type(entry[1]) is int)
            or not (entry[2] is None or isinstance(entry[2], str))
        ):
            raise ValueError(f"'to_command' has an entry {entry!r}")
        out.append((entry[0], entry[1], entry[2]))
    return out


def _span(ns: int) -> str:
    """A step time for a refusal: in days or years when that long."""
    days = ns / 86_400e9
    if abs(days) >= 365.25:
        return f"{days / 365.25:.1f} years"
    return f"{days:.1f} days" if abs(days) >= 1 else f"{ns // 1_000_000} ms"


def _count(data: dict[str, Any], key: str) -> int:
    value = data.get(key)
    if not isinstance(value, int) or isinstance(value, bool) or not 0 <= value <= 1_000_000:
        raise ValueError(f"{key!r} is {value!r}")
    return value


def _expand(value: object, key: str, n: int) -> object:
    """A list kept compact (``state_view``: ``{"fill": v}``, or ``{"fill": v, "at": [[i,
    v_i], ...]}``) in full; anything else as it is."""
    if not isinstance(value, dict):
        return value
    at = value.get("at", [])
    if set(value) - {"fill", "at"} or "fill" not in value or not isinstance(at, list):
        raise ValueError(f"{key!r} is {value!r}")
    out = [value["fill"]] * n
    for pair in at:
        if (
            not isinstance(pair, list)
            or len(pair) != 2
            or type(pair[0]) is not int
            or not 0 <= pair[0] < n
        ):
            raise ValueError(f"{key!r} has an entry {pair!r}")
        out[pair[0]] = pair[1]
    return out


def _list(data: dict[str, Any], key: str, n: int) -> list[Any]:
    value = _expand(data.get(key), key, n)
    if not isinstance(value, list) or len(value) != n:
        raise ValueError(f"{key!r} does not hold {n} entries")
    if key in _BOOL_LISTS:
        if any(not isinstance(v, bool) for v in value):
            raise ValueError(f"{key!r} holds a non-boolean")
    elif key not in ("t_ns", "u_ns") and any(not isinstance(v, int) for v in value):
        raise ValueError(f"{key!r} holds a non-integer")
    return list(value)
