"""Wire messages between a CPU and its views: frozen msgspec structs, JSON on the bus.

Every struct bounds its numbers, strings and lists, so a hostile message is refused with a
:class:`ProtocolError` naming the bad field (``$.args.step``), never an exception that
escapes.

How messages evolve (docs/bus.md, "How messages evolve"): what the CPU takes — a command
and its arguments (``web.commands``), a :class:`LoginRequest`, a :class:`WatchRequest` —
is strict: an unknown field is refused. What the CPU says (status, deltas, alarms, the
diagnostic buffer, charts, replies …) is read leniently: a reader ignores a field it does
not know, so a newer CPU may add fields (each with a default) and older readers go on
reading. A field never changes type or meaning and is never removed; a change that would
need that raises :data:`PROTOCOL`, which :class:`CpuStatus` carries as ``v``.
:class:`CpuStatus` leaves out fields at their default, so readers from before this rule
(strict everywhere) read every status but one naming a STOP's entries.
"""

from __future__ import annotations

import re
from typing import Annotated, Any, Literal, TypeVar

import msgspec
from msgspec import UNSET, Meta, Struct, UnsetType

from s7graph.sequencer.change.base import MAX_SOURCE
from s7graph.sequencer.checks.interfaces import Interface, ProgramBlocks, UserPin
from s7graph.sequencer.text.format import format_expr
from s7graph.sequencer.text.model import Chart, Expr
from s7graph.steps.conditions import MAX_CONTACTS
from s7graph.web.bus.chart_text import action_rows, contact_spans, permanent_rows
from s7graph.web.commands import (
    MODES,
    NAME_PATTERN,
    OPS,
    REMOVED_CHOICES,
    AnyCommand,
    Command,
    Mac,
    Mode,
    MsgId,
    MsgKey,
    Name,
    Origin,
    Scalar,
    Seq,
    Token,
    UserName,
    explain,
)

__all__ = [
    "EVENTS",
    "MAX_MESSAGE_BYTES",
    "MAX_PARTS",
    "MAX_PERMANENT",
    "MODES",
    "OPS",
    "PART_BYTES",
    "PROTOCOL",
    "REFUSAL_KINDS",
    "REMOVED_CHOICES",
    "ActionInfo",
    "AlarmEntry",
    "AlarmEvent",
    "AlarmHistory",
    "AlarmList",
    "AuditEntry",
    "AuditList",
    "BlockInterface",
    "BlockInterfaces",
    "BlockPin",
    "BlockSource",
    "BlockSources",
    "ChartLayout",
    "ChartPart",
    "ChartSource",
    "Command",
    "CommandReply",
    "Contact",
    "CpuState",
    "CpuStatus",
    "CycleReport",
    "CycleStats",
    "DiagBuffer",
    "DiagEvent",
    "FbOperands",
    "ForceEntry",
    "ForceList",
    "LoginReply",
    "LoginRequest",
    "OperandCatalog",
    "OperandInfo",
    "OperandValues",
    "PermanentContact",
    "PermanentInfo",
    "ProjectFile",
    "ProjectFiles",
    "ProtocolError",
    "Refusal",
    "ScanDeltas",
    "SequenceInfo",
    "StepDetail",
    "StepInfo",
    "StepStateUpdate",
    "SyncReport",
    "SyncStepInfo",
    "TransitionCriteria",
    "TransitionInfo",
    "WatchRequest",
    "WatchValue",
    "WatchValues",
    "condition_text",
    "decode",
    "encode",
    "join_layout",
    "refusal_kind",
    "refusal_reply",
    "split_layout",
    "valid_name",
    "watch_bytes",
]

SCHEMA = 1
PROTOCOL = 1
"""The bus protocol's version: raised only by a change an older reader cannot ignore (a
field removed, or one that changes type or meaning); a new field with a default is not."""
MAX_MESSAGE_BYTES = 1 << 20  # refuse anything larger before decoding it
PART_BYTES = 1 << 19
"""A chart layout larger than this goes in parts of at most this size (:func:`split_layout`)."""
MAX_PARTS = 1024

Event = Literal["S1", "S0", "V1", "V0", "L1", "L0", "A1", "R1"]
EVENTS: tuple[str, ...] = ("S1", "S0", "V1", "V0", "L1", "L0", "A1", "R1")
_NAME_RE = re.compile(NAME_PATTERN)

StepNo = Annotated[int, Meta(ge=0, le=65535)]
Count = Annotated[int, Meta(ge=0, le=2**63 - 1)]
Text = Annotated[str, Meta(max_length=4096)]
ShortText = Annotated[str, Meta(max_length=256)]
Steps = Annotated[list[StepNo], Meta(max_length=4096)]
ValueName = Annotated[str, Meta(min_length=1, max_length=128)]
Millis = Annotated[float, Meta(ge=0.0, le=1e12)]
Label = Annotated[str, Meta(max_length=80)]
LevelPin = Literal["HALT_SQ", "EN_IL", "EN_SV"]
CpuState = Literal["RUN", "STOP", "STARTUP", "HOLD"]


def valid_name(name: str) -> bool:
    """Whether ``name`` may be a CPU or FB name (letters, digits, ``_ . -``; no key wildcards)."""
    return bool(_NAME_RE.match(name))


class ProtocolError(ValueError):
    """A message that does not decode to the expected struct; the text says where and why."""


class _Msg(Struct, frozen=True, kw_only=True):
    """What the CPU says: a reader ignores the fields it does not know."""


class _Scan(_Msg, frozen=True, kw_only=True, omit_defaults=True, gc=False):
    """What the CPU says every scan (a delta and its parts): fields at their default are
    left out (a reader applies the defaults), and the garbage collector does not track
    them (they hold no cycles), so a scan's many updates cost it nothing."""


class _Request(_Msg, frozen=True, forbid_unknown_fields=True, kw_only=True):
    """What the CPU takes: strict, an unknown field is refused."""


# ---------------------------------------------------------------- chart structure


# Where each contact of a condition stands in its text (start, end), in CRIT bit order
Spans = Annotated[list[tuple[Count, Count]], Meta(max_length=32)]


class ActionInfo(_Msg, frozen=True, kw_only=True):
    """One row of a step's action table as S7-GRAPH shows it: event, qualifier (``C``
    appended when interlocked), operand and time or value; ``watch`` names the value the CPU
    sends while the step is active (the operand's, an assignment's target's; "" none)."""

    event: Annotated[str, Meta(max_length=8)] = ""
    qualifier: Annotated[str, Meta(max_length=8)]
    operand: Text
    value: ShortText = ""
    watch: Annotated[str, Meta(max_length=128)] = ""


MAX_PERMANENT = 256  # permanent instructions a layout lists at most


class PermanentContact(_Msg, frozen=True, kw_only=True):
    """One contact of a permanent coil's condition: ``text`` as written (``NOT "Stop"``),
    ``watch`` the bit it reads, whose value the CPU sends every scan ("": a comparison),
    ``negated`` whether a NOT inverts it."""

    text: ShortText = ""
    watch: Annotated[str, Meta(max_length=128)] = ""
    negated: bool = False


class PermanentInfo(_Msg, frozen=True, kw_only=True):
    """One permanent instruction of the FB (S7-GRAPH's permanent pre- and post-instructions):
    ``place`` ``before`` or ``after`` the sequences, its text as the chart file writes it,
    and ``watch``, the operand it writes, whose value the CPU sends every scan ("": none,
    a block call)."""

    place: Literal["before", "after"] = "before"
    text: Text = ""
    watch: Annotated[str, Meta(max_length=128)] = ""
    contacts: Annotated[list[PermanentContact], Meta(max_length=MAX_CONTACTS)] = []
    """A coil's contacts (or an assignment's of a logic operation), each with the bit it
    reads; none for another assignment or a call."""


class StepInfo(_Msg, frozen=True, kw_only=True):
    """One step box: number, name, which frames the view draws around it, its action table,
    and its interlock and supervision conditions with where their contacts stand."""

    number: StepNo
    name: ShortText = ""
    initial: bool = False
    interlock: bool = False
    supervision: bool = False
    message: Text = ""
    actions: Annotated[list[ActionInfo], Meta(max_length=256)] = []
    interlock_condition: Text = ""
    interlock_contacts: Spans = []
    supervision_condition: Text = ""
    supervision_contacts: Spans = []


class TransitionInfo(_Msg, frozen=True, kw_only=True):
    """One transition bar; ``targets == []`` is a branch stop (``TO STOP``); ``contacts``:
    where each contact stands in ``condition``."""

    number: StepNo
    name: ShortText = ""
    sources: Steps
    targets: Steps
    condition: Text = ""
    contacts: Spans = []


class SequenceInfo(_Msg, frozen=True, kw_only=True):
    """One sequencer (a column in the chart), listing its steps and transitions in file order."""

    number: StepNo
    name: ShortText = ""
    steps: Steps
    transitions: Steps


class ChartLayout(_Msg, frozen=True, kw_only=True):
    """What a view needs to draw one GRAPH FB (served by ``fb/<name>/chart``)."""

    fb: Name
    steps: Annotated[list[StepInfo], Meta(max_length=4096)]
    transitions: Annotated[list[TransitionInfo], Meta(max_length=4096)]
    sequences: Annotated[list[SequenceInfo], Meta(max_length=256)]
    schema: int = SCHEMA
    version: Count = 0  # the chart version the CPU runs (1 at start, +1 per download)
    permanent: Annotated[list[PermanentInfo], Meta(max_length=MAX_PERMANENT)] = []
    """The permanent instructions, those before the sequences first (each at most 1,024
    characters shown; a reader of the time before this field has none)."""
    parts: Annotated[int, Meta(ge=0, le=MAX_PARTS)] = 0
    """How many :class:`ChartPart` s complete this layout (0: it is whole): a layout too
    large for one message comes without its steps' action tables — or, larger still,
    without its steps and transitions — and those come in parts (``fb/<name>/chart/part``,
    :func:`split_layout`, :func:`join_layout`)."""

    @classmethod
    def from_chart(cls, chart: Chart, *, fb: str | None = None, version: int = 0) -> ChartLayout:
        """Describe ``chart`` for a view; ``fb`` defaults to the chart's name."""
        steps = []
        for s in chart.all_steps():
            interlock, il_spans = _condition(s.interlock)
            supervision, sv_spans = _condition(s.supervision)
            steps.append(
                StepInfo(
                    number=s.number,
                    name=_clip(s.name, 256),
                    initial=s.initial,
                    interlock=s.interlock is not None,
                    supervision=s.supervision is not None,
                    message=_clip(s.message, 4096),
                    actions=[
                        ActionInfo(
                            event=r.event,
                            qualifier=r.qualifier,
                            operand=_clip(r.operand, 4096),
                            value=_clip(r.value, 256),
                            watch=r.watch,
                        )
                        for r in action_rows(s.actions[:256])
                    ],
                    interlock_condition=interlock,
                    interlock_contacts=il_spans,
                    supervision_condition=supervision,
                    supervision_contacts=sv_spans,
                )
            )
        transitions = []
        for t in chart.all_transitions():
            condition, spans = _condition(t.condition)
            transitions.append(
                TransitionInfo(
                    number=t.number,
                    name=_clip(t.name, 256),
                    sources=list(t.sources),
                    targets=list(t.targets),
                    condition=condition,
                    contacts=spans,
                )
            )
        sequences = [
            SequenceInfo(
                number=q.number,
                name=_clip(q.name, 256),
                steps=[s.number for s in q.steps],
                transitions=[t.number for t in q.transitions],
            )
            for q in chart.sequences
        ]
        permanent = [
            PermanentInfo(
                place=p.place,
                text=_clip(p.text, 1024),
                watch=p.watch,
                contacts=[
                    PermanentContact(text=_clip(c.text, 256), watch=c.watch, negated=c.negated)
                    for c in p.contacts
                ],
            )
            for p in permanent_rows(chart)[:MAX_PERMANENT]
        ]
        return cls(
            fb=fb or chart.name,
            steps=steps,
            transitions=transitions,
            sequences=sequences,
            version=version,
            permanent=permanent,
        )

    def step(self, number: int) -> StepInfo | None:
        """The step with this number, or None."""
        return next((s for s in self.steps if s.number == number), None)


class ChartPart(_Msg, frozen=True, kw_only=True):
    """Part ``k`` of a layout served in parts (``fb/<name>/chart/part?k=K``): whole steps
    from index ``first_step`` of the layout's steps on, whole transitions from
    ``first_transition`` on, for chart ``version``."""

    fb: Name
    version: Count = 0
    k: Annotated[int, Meta(ge=0, lt=MAX_PARTS)] = 0
    first_step: Annotated[int, Meta(ge=0, le=4096)] = 0
    steps: Annotated[list[StepInfo], Meta(max_length=4096)] = []
    first_transition: Annotated[int, Meta(ge=0, le=4096)] = 0
    transitions: Annotated[list[TransitionInfo], Meta(max_length=4096)] = []


BlockNo = Annotated[int, Meta(ge=0, le=65535)]


class BlockPin(_Msg, frozen=True, kw_only=True):
    """A parameter (``IN``, ``OUT``, ``IN_OUT``) or static variable (``STAT``) of a user
    block: its name, direction and S7 type (``OBJECT``: one a chart cannot pass)."""

    name: Annotated[str, Meta(min_length=1, max_length=128)]
    direction: Literal["IN", "OUT", "IN_OUT", "STAT"]
    type: ShortText


class BlockInterface(_Msg, frozen=True, kw_only=True):
    """A user FB or FC as a chart's call sees it: its number, name, parameters in declared
    order (an FC's function value as the output ``RET_VAL``) and an FB's static variables."""

    kind: Literal["FB", "FC"]
    number: BlockNo
    name: ShortText = ""
    pins: Annotated[list[BlockPin], Meta(max_length=1024)] = []
    statics: Annotated[list[BlockPin], Meta(max_length=4096)] = []


class BlockInterfaces(_Msg, frozen=True, kw_only=True):
    """The interfaces of the user blocks a CPU holds (``sequencer.checks.interfaces.
    ProgramBlocks``): its FBs and FCs, its instance DBs (number, FB label), its global DBs
    and where they come from (``sources``, for messages)."""

    blocks: Annotated[list[BlockInterface], Meta(max_length=4096)] = []
    instances: Annotated[list[tuple[BlockNo, Label]], Meta(max_length=65536)] = []
    global_dbs: Annotated[list[BlockNo], Meta(max_length=65536)] = []
    sources: Text = ""

    @classmethod
    def of(cls, program: ProgramBlocks) -> BlockInterfaces:
        """The message of ``program`` (each block once, in its order)."""
        blocks = {i.label: i for i in program.blocks.values()}
        return cls(
            blocks=[
                BlockInterface(
                    kind=i.kind,  # type: ignore[arg-type]  # FB or FC: program_blocks
                    number=i.number,
                    name=_clip(i.name, 256),
                    pins=[_pin(p) for p in i.pins],
                    statics=[_pin(p) for p in i.statics],
                )
                for i in blocks.values()
            ],
            instances=sorted(program.instances.items()),
            global_dbs=sorted(program.global_dbs),
            sources=_clip(program.sources, 4096),
        )

    def program(self) -> ProgramBlocks:
        """The interfaces as the chart's checks read them, keyed as ``program_blocks``
        keys them: by label, and by name where no block before took the name."""
        found: dict[str, Interface] = {}
        for b in self.blocks:
            pins = tuple(UserPin(p.name, p.direction, p.type) for p in b.pins)
            statics = tuple(UserPin(p.name, "STAT", p.type) for p in b.statics)
            interface = Interface(b.kind, b.number, b.name, pins, statics)
            found[interface.label] = interface
            found.setdefault(b.name.upper(), interface)
        dbs = frozenset(self.global_dbs)
        return ProgramBlocks(found, dict(self.instances), dbs, self.sources)


def _pin(pin: UserPin) -> BlockPin:
    direction: Any = pin.direction  # IN, OUT, IN_OUT or STAT: interfaces.program_blocks
    return BlockPin(name=pin.name[:128], direction=direction, type=_clip(pin.type, 256))


class ChartSource(_Msg, frozen=True, kw_only=True):
    """The running chart as ``.s7g`` text, for an editor (``fb/<name>/source``): its
    ``version`` (as in :class:`ChartLayout`), the file it came from (a name, no directory),
    the text of the symbol table it was compiled with, and ``blocks``: the S7-SCL sources
    the CPU runs beside it, whole, by file name (no directory) in the CPU's order — those a
    download's ``blocks`` replace; ``left_out``: the names of those that did not fit in
    one message; ``interfaces``: the interfaces of the user blocks the CPU holds when
    ``blocks`` do not give them all (a program of blocks that is no S7-SCL source, sources
    left out), None otherwise and from a CPU from before."""

    fb: Name
    version: Count = 0
    file: ShortText = ""
    text: Annotated[str, Meta(max_length=MAX_SOURCE)]
    symbols: Annotated[str, Meta(max_length=MAX_SOURCE)] = ""
    blocks: Annotated[dict[ShortText, str], Meta(max_length=4096)] = {}
    left_out: Annotated[list[ShortText], Meta(max_length=4096)] = []
    interfaces: BlockInterfaces | None = None


class BlockSource(_Msg, frozen=True, kw_only=True):
    """One S7-SCL block the CPU runs, as written: its label (``FB17``), its name, the file
    it came from (a name, no directory), the line it starts on and its text."""

    label: Label
    name: ShortText = ""
    file: ShortText = ""
    line: Count = 0
    text: Annotated[str, Meta(max_length=MAX_SOURCE)] = ""


class BlockSources(_Msg, frozen=True, kw_only=True):
    """The S7-SCL blocks the CPU was loaded with, as source (``blocks``), in source order;
    ``left_out``: the labels of those that did not fit in one message; ``files``: the
    sources whole, by file name (no directory), in the room the blocks leave;
    ``files_left_out``: the names of those that did not fit."""

    blocks: Annotated[list[BlockSource], Meta(max_length=4096)] = []
    left_out: Annotated[list[Label], Meta(max_length=4096)] = []
    files: Annotated[dict[ShortText, str], Meta(max_length=4096)] = {}
    files_left_out: Annotated[list[ShortText], Meta(max_length=4096)] = []


class ProjectFile(_Msg, frozen=True, kw_only=True):
    """A file of the CPU's project directory an editor can open, with its format
    (``s7g``, ``simaticml``, ``plcopen``, ``iec-text``)."""

    name: ShortText
    format: ShortText


class ProjectFiles(_Msg, frozen=True, kw_only=True):
    """The charts and importable files of the CPU's project directory (``project``)."""

    directory: Text = ""
    files: Annotated[list[ProjectFile], Meta(max_length=4096)] = []


# ---------------------------------------------------------------- per-scan state


class StepStateUpdate(_Scan, frozen=True, kw_only=True):
    """The FB's state after one scan (``fb/<name>/state``; ``fb/<name>/delta`` on change).

    ``seq`` counts changes (the bus publisher numbers them); ``disturbed`` are steps with an
    interlock or supervision error, ``latched`` those whose supervision error is not yet
    acknowledged; ``events`` are ``[event, step]`` pairs raised this scan."""

    seq: Count = 0
    cycle: Count
    t_ms: Count
    mode: Mode
    active: Steps
    disturbed: Steps = []
    latched: Steps = []
    events: Annotated[list[tuple[Event, StepNo]], Meta(max_length=4096)] = []
    values: Annotated[dict[ValueName, Scalar], Meta(max_length=1024)] = {}
    details: Annotated[list[StepDetail], Meta(max_length=4096)] = []
    halted: bool = False  # HALT_SQ in force (a pin or a ``halt`` command)
    il_enabled: bool = True  # EN_IL
    sv_enabled: bool = True  # EN_SV
    # the level pins a command holds (``halt``, ``en_il``, ``en_sv``), kept over restarts
    overrides: Annotated[dict[LevelPin, bool], Meta(max_length=3)] = {}

    def changed_from(self, other: StepStateUpdate | None) -> bool:
        """Whether this scan differs from ``other`` in more than its cycle and time."""
        if other is None:
            return True
        return (
            bool(self.events)
            or self.mode != other.mode
            or self.active != other.active
            or self.disturbed != other.disturbed
            or self.latched != other.latched
            or self.values != other.values
            or (self.halted, self.il_enabled, self.sv_enabled, self.overrides)
            != (other.halted, other.il_enabled, other.sv_enabled, other.overrides)
            or not _same_coarse(self.details, other.details)
        )


MAX_FBS = 256  # FBs of one CPU (``CpuStatus.fbs``)


class ScanDeltas(_Scan, frozen=True, kw_only=True):
    """``deltas``: one message per CPU scan in which an FB changed, holding the
    :class:`StepStateUpdate` of every FB that changed (by FB name, each with its own
    ``seq``). ``seq`` counts these messages: a gap means one was lost (get ``state`` of the
    FBs followed). A scan whose deltas would not fit in one message goes out in several,
    each with the scan's ``seq``."""

    seq: Count = 0
    cycle: Count
    t_ms: Count
    fbs: Annotated[dict[Name, StepStateUpdate], Meta(max_length=MAX_FBS)] = {}


def _same_coarse(a: list[StepDetail], b: list[StepDetail]) -> bool:
    """Whether two scans' details are equal with whole-second times: a step's T/U alone
    makes a delta once a second. A detail unchanged since the last scan is the same object
    (``web.bus.step_details``): an identity test."""
    if len(a) != len(b):
        return False
    for x, y in zip(a, b, strict=True):
        if x is y:
            continue
        if x.t_ms // 1000 != y.t_ms // 1000 or x.u_ms // 1000 != y.u_ms // 1000:
            return False
        if msgspec.structs.replace(x, t_ms=y.t_ms, u_ms=y.u_ms) != y:
            return False
    return True


class Contact(_Scan, frozen=True, kw_only=True):
    """One contact of a condition in its last evaluation (a CRIT bit): ``ok`` when it lets
    the condition through (a ``NOT x`` contact when ``x`` is false)."""

    text: Text
    ok: bool


Contacts = Annotated[list[Contact], Meta(max_length=32)]


class TransitionCriteria(_Scan, frozen=True, kw_only=True):
    """A valid transition leaving an active step: whether its condition held (``Tn.TT``)
    at its last evaluation, and each contact."""

    number: StepNo
    name: ShortText = ""
    holds: bool
    contacts: Contacts = []


class StepDetail(_Scan, frozen=True, kw_only=True):
    """Why an active step does (not) switch: its times (to 0.1 s; a change of times alone is
    a change once a second), interlock and supervision state with their contacts, and its
    valid outgoing transitions."""

    number: StepNo
    t_ms: Count = 0
    u_ms: Count = 0
    interlock_ok: bool = True
    interlock_error: bool = False
    supervision_fault: bool = False
    interlock: Contacts = []
    supervision: Contacts = []
    transitions: Annotated[list[TransitionCriteria], Meta(max_length=256)] = []


PartName = Annotated[str, Meta(max_length=16)]


class CycleReport(_Msg, frozen=True, kw_only=True):
    """Where one cycle's time went (``engine.profile``): the scan it began with, when (wall
    ms since the epoch), its length, whether its work overran the set cycle time, and the
    ms of each phase of the runner's loop (``scan``, ``alarms``, ``stage``, ``edge``,
    ``gc``, ``idle``, ``late``), then ``cpu`` (the scan thread ran), ``processor`` (it
    waited for one) and ``lock`` (it was blocked) where the system says."""

    scan: Count = 0
    at_ms: Count = 0
    cycle_ms: Millis = 0.0
    overrun: bool = False
    parts: Annotated[dict[PartName, Millis], Meta(max_length=16)] = {}


class CycleStats(_Msg, frozen=True, kw_only=True):
    """The CPU's cycle statistics in ms: cycle time (OB1 start to OB1 start: last, min,
    max), mean scan execution time, how many cycles overran the set cycle time, how many
    ran long (over ``long_over_ms``), and the breakdowns of the longest and the last long
    cycle; the share of the cycle commands may take at a scan boundary (``comm_load``, per
    cent; 0: not limited) and at how many boundaries it ran out with commands waiting; the
    scan thread's real-time priority (``priority``, 0: normal scheduling) and the processor
    it keeps (``core``, -1: none)."""

    last_ms: Millis = 0.0
    min_ms: Millis = 0.0
    max_ms: Millis = 0.0
    exec_ms: Millis = 0.0
    overruns: Count = 0
    long: Count = 0
    long_over_ms: Millis = 0.0
    longest: CycleReport | None = None
    last_long: CycleReport | None = None
    comm_load: Annotated[float, Meta(ge=0, le=100)] = 0.0
    comm_limited: Count = 0
    priority: Annotated[int, Meta(ge=0, le=99)] = 0
    core: Annotated[int, Meta(ge=-1, le=4095)] = -1


# ---------------------------------------------------------------- the diagnostic buffer

EventIdNumber = Annotated[int, Meta(ge=0, le=0xFFFF)]
ObNumber = Annotated[int, Meta(ge=0, le=255)]
MAX_DIAG_ENTRIES = 1000


class DiagEvent(_Msg, frozen=True, kw_only=True):
    """One entry of the CPU's diagnostic buffer, as STEP 7's "Diagnostic Buffer" lists it:
    ``number`` is its place among the entries the CPU wrote to its state file (kept across
    restarts; the newest has the highest), ``event_id`` (``16#4302`` is
    17154) with its ``text``, what the entry says (``info``) and the block and address it
    names, the OB the event requests (``ob``, 0: none) and the priority class that OB runs
    in, the time on the CPU's clock (``t_ms``) and on the wall clock (``wall_ms``, ms since
    the epoch; 0: not known)."""

    number: Count
    event_id: EventIdNumber
    text: Text = ""
    info: Text = ""
    block: ShortText = ""
    address: ShortText = ""
    ob: ObNumber = 0
    priority: ObNumber = 0
    t_ms: Count = 0
    wall_ms: Count = 0


class DiagBuffer(_Msg, frozen=True, kw_only=True):
    """Entries of the diagnostic buffer, newest first: the ``diag`` queryable's answer (the
    newest ``n``, 100 unless the query says ``?n=``) and ``diag/new``'s publication (the
    entries written since the last one). ``total``: the ``number`` of the newest entry
    (a subscriber that saw an older total than ``total - len(entries)`` missed some: get
    ``diag`` again); ``capacity``: how many the CPU keeps."""

    total: Count = 0
    capacity: Count = 0
    entries: Annotated[list[DiagEvent], Meta(max_length=MAX_DIAG_ENTRIES)] = []


class CpuStatus(_Msg, frozen=True, kw_only=True, omit_defaults=True):
    """``status``: the CPU's run state and its FBs; published on change and at 1 Hz. A
    field at its default is left out of the JSON; ``v`` is the :data:`PROTOCOL` the CPU
    speaks (left out: 1)."""

    cpu: Name
    state: CpuState = "RUN"
    cycle: Count = 0
    t_ms: Count = 0
    fbs: Annotated[list[Name], Meta(max_length=256)] = []
    stats: CycleStats | None = None
    login: Literal["users", "demo"] = "demo"  # demo: no users file, names are claimed
    forces: Count = 0  # force jobs active: the CPU's FRCE LED is on when > 0
    reason: Text = ""  # why the CPU is in STOP (its STOP entry and the error before it)
    stop: DiagEvent | None = None  # in STOP: the diagnostic entry of the STOP
    cause: DiagEvent | None = None  # the error entry that caused it (none: the STOP itself)
    v: Annotated[int, Meta(ge=1, le=65535)] = PROTOCOL


class ForceEntry(_Msg, frozen=True, kw_only=True):
    """One force job: the address, the value as shown (``TRUE``, ``-5``, ``W#16#00FF``),
    the symbol it was given by and who forced it."""

    address: Annotated[str, Meta(max_length=32)]
    value: ShortText
    symbol: ShortText = ""
    user: Label = ""


class ForceList(_Msg, frozen=True, kw_only=True):
    """The CPU's force jobs (``forces`` on change, also a queryable), in area order (I, Q,
    M); ``seq`` counts the changes."""

    seq: Count = 0
    entries: Annotated[list[ForceEntry], Meta(max_length=256)] = []


# ---------------------------------------------------------------- the watch table

MAX_WATCH = 64
WatchText = Annotated[str, Meta(min_length=1, max_length=128)]


class WatchRequest(_Request, frozen=True, kw_only=True):
    """``watch`` queryable: the addresses to read at the next scan boundary (STEP 7's
    "Monitor/Modify Variables", triggered once at the end of a cycle): an absolute address
    (``MW0``, ``Q4.0``, ``DB20.DBW2``, ``T5``), a symbol, or a DB variable by name
    (``DB20.avg``, ``DB10.ctu.cv``, ``DB20.speeds[2]``), each optionally with the type to
    show it as (``MW0:INT``, ``MD4:REAL``). A logged-in client may sign it as a command:
    ``user``, ``token``, ``seq`` and ``mac`` over :func:`watch_bytes` — the CPU then queues
    it in its user's own share (docs/bus.md, "The watch table: watch"); unset, the request
    is the one it always was."""

    addresses: Annotated[list[WatchText], Meta(min_length=1, max_length=MAX_WATCH)]
    user: UserName | UnsetType = UNSET
    token: Token | UnsetType = UNSET
    seq: Seq | UnsetType = UNSET
    mac: Mac | UnsetType = UNSET


_WATCH_SIGNED = b"s7graph watch\n"


def watch_bytes(request: WatchRequest) -> bytes:
    """What a signed watch request's ``mac`` signs: its JSON without ``mac``, after a
    prefix of its own (a command's signature never passes for a watch's)."""
    return _WATCH_SIGNED + msgspec.json.encode(msgspec.structs.replace(request, mac=UNSET))


class WatchValue(_Msg, frozen=True, kw_only=True):
    """One watched address: its value (None when it cannot be read), the value as S7 shows
    it (``TRUE``, ``W#16#00FF``, ``-5``, ``T#1S``), its type, or why it cannot be read."""

    address: WatchText
    value: Scalar = None
    text: Text = ""
    type: ShortText = ""
    error: Text = ""


class WatchValues(_Msg, frozen=True, kw_only=True):
    """The answer of ``watch``: the values at the end of scan ``cycle`` (CPU clock
    ``t_ms``), in the order asked, with the CPU's run state; ``error``: why the request was
    refused as a whole (nothing read)."""

    cycle: Count = 0
    t_ms: Count = 0
    state: CpuState = "RUN"
    values: Annotated[list[WatchValue], Meta(max_length=MAX_WATCH)] = []
    error: Text = ""


# ---------------------------------------------------------------- synchronization


class SyncStepInfo(_Msg, frozen=True, kw_only=True):
    """One step judged against the process values (``fb/<fb>/sync``): whether it is active,
    its interlock holds, a transition into it holds (``entered``), which leaving
    transitions hold (``done``); it ``fits`` (interlock held, none done) and is ``likely``
    (fits and entered)."""

    number: StepNo
    name: Label = ""
    sequence: Annotated[int, Meta(ge=0, le=255)] = 0
    active: bool = False
    interlock: bool = True
    entered: bool = False
    done: Annotated[list[StepNo], Meta(max_length=256)] = []
    fits: bool = False
    likely: bool = False

    @property
    def label(self) -> str:
        """``S2 Clamp`` (``S2`` for a step without a name)."""
        return f"S{self.number} {self.name}".strip()

    @property
    def verdict(self) -> str:
        """In words: ``likely``, ``fits``, ``interlock not held`` or ``done (T1 holds)``."""
        if self.likely or self.fits:
            return "likely" if self.likely else "fits"
        if not self.interlock:
            return "interlock not held"
        return f"done ({', '.join(f'T{n}' for n in self.done)} holds)"


class SyncReport(_Msg, frozen=True, kw_only=True):
    """The answer of ``fb/<fb>/sync``: every step of the FB judged on the values at the end
    of scan ``cycle`` (CPU clock ``t_ms``), in chart order, with the CPU's run state and the
    sequencer's mode; ``error``: why nothing was judged."""

    fb: Annotated[str, Meta(max_length=128)] = ""
    cycle: Count = 0
    t_ms: Count = 0
    state: CpuState = "RUN"
    mode: Mode = "AUTO"
    steps: Annotated[list[SyncStepInfo], Meta(max_length=4096)] = []
    error: Text = ""

    def ordered(self) -> list[SyncStepInfo]:
        """The likely steps, the other fitting ones, then the rest, each in chart order."""
        return sorted(self.steps, key=lambda s: (not s.likely, not s.fits))


# ---------------------------------------------------------------- operands


class OperandInfo(_Msg, frozen=True, kw_only=True):
    """One operand a CPU publishes on ``operands``: its name, S7 type (``BOOL``, ``INT``,
    ``TIME``, ``STRING[20]``), address (a symbol's; "" for an FB's variable or pin), the
    comment, and a pin's direction (``IN``/``OUT``; "" for the others)."""

    name: ValueName
    type: ShortText
    address: Annotated[str, Meta(max_length=64)] = ""
    comment: Text = ""
    direction: Literal["IN", "OUT", ""] = ""


Infos = Annotated[list[OperandInfo], Meta(max_length=4096)]


class FbOperands(_Msg, frozen=True, kw_only=True):
    """One FB's operands: the variables of its chart (``VAR``) and the pins of its
    parameter set, each list in the chart's and the pin table's order."""

    variables: Infos = []
    pins: Infos = []


class OperandCatalog(_Msg, frozen=True, kw_only=True):
    """``operands/list`` (a queryable): what :class:`OperandValues` carries, and their
    types; ``version`` changes when an online change changes an FB's variables or pins."""

    version: Count = 0
    symbols: Infos = []
    fbs: Annotated[dict[Name, FbOperands], Meta(max_length=256)] = {}


Values = Annotated[dict[ValueName, Scalar], Meta(max_length=4096)]


class OperandValues(_Msg, frozen=True, kw_only=True):
    """``operands``: the values of the symbol table's operands and of each FB's variables
    and pins (``fbs``: FB → name → value), published on change at most
    ``web.bus.operands.PERIOD_MS`` apart, read at a scan boundary (also a queryable);
    ``seq`` counts the changes, ``catalog`` is the :class:`OperandCatalog`'s version. An
    operand that cannot be read is left out."""

    seq: Count = 0
    cycle: Count = 0
    catalog: Count = 0
    symbols: Values = {}
    fbs: Annotated[dict[Name, Values], Meta(max_length=256)] = {}


# ---------------------------------------------------------------- messages (alarms)


class AlarmEntry(_Msg, frozen=True, kw_only=True):
    """One message of the CPU's message list. Times are wall-clock ms since the epoch;
    ``fb``/``db``/``step``/``kind`` (``IL`` interlock, ``SV`` supervision) name the step
    of a sequencer message."""

    msg_id: MsgId
    event_id: Count
    state: Literal["incoming", "outgoing"]
    text: Text = ""
    source: ShortText = ""
    came_ms: Count
    went_ms: Count | None = None
    ack_required: bool = True
    acked: bool = False
    ack_user: Annotated[str, Meta(max_length=64)] = ""
    ack_ms: Count | None = None
    fb: ShortText = ""
    db: Count | None = None
    step: StepNo | None = None
    kind: Literal["IL", "SV", ""] = ""


class AlarmList(_Msg, frozen=True, kw_only=True):
    """The CPU's message list (``alarms`` on change, ``alarms/list`` queryable), oldest
    first; ``seq`` counts the changes."""

    seq: Count = 0
    cycle: Count = 0
    entries: Annotated[list[AlarmEntry], Meta(max_length=4096)] = []

    def pending(self) -> list[AlarmEntry]:
        """The entries still waiting for an acknowledgement."""
        return [e for e in self.entries if e.ack_required and not e.acked]


# ---------------------------------------------------------------- commands

# The commands are the tagged union of ``web.commands`` (one struct per op, typed
# arguments); ``Command`` is their base, and ``decode(data, Command)`` decodes any of them.

Lines = Annotated[list[Text], Meta(max_length=4096)]

REFUSAL_KINDS: tuple[str, ...] = (
    "access",  # the sender may not: no login, a bad token, a role too low
    "state",  # not now: the CPU or the sequencer is not in a state that takes it
    "argument",  # a value the CPU cannot take: an address, a literal, a file name
    "not_found",  # no such step, FB, op or file
    "busy",  # a queue full, a conflicting command queued, expired waiting: retry
    "timeout",  # applied, but not confirmed durable in time
    "communication",  # the CPU did not answer, or not readably (said by the client)
    "acked",  # the message is acknowledged already
    "no_event",  # no such message in the message list
    "refused",  # none of the above: this CPU does not take it
)
"""What kind of refusal a :class:`CommandReply` is (``kind``), decided where the refusal is
made so a reader need not parse the reason's words. A later CPU may add a kind: a reader
takes one it does not know as none ("")."""
RefusalKindText = Annotated[str, Meta(max_length=32)]


class Refusal(str):
    """A reason for refusing a command that names its ``kind`` (one of
    :data:`REFUSAL_KINDS`): the text as any ``str``, the kind read by :func:`refusal_kind`
    where the :class:`CommandReply` is made. Encoded as its text."""

    kind: str

    def __new__(cls, kind: str, text: str) -> Refusal:
        if kind not in REFUSAL_KINDS:
            raise ValueError(f"refusal kind {kind!r}: not one of {', '.join(REFUSAL_KINDS)}")
        made = super().__new__(cls, text)
        made.kind = kind
        return made


def refusal_kind(reason: str) -> str:
    """The kind of ``reason`` ("" for a plain text: no kind said)."""
    return reason.kind if isinstance(reason, Refusal) else ""


def refusal_reply(reason: str, **fields: Any) -> CommandReply:
    """A refusal as a reply: ``reason``'s text (cut to 4096 characters) and its kind."""
    return CommandReply(
        applied=False, reason=str(reason)[:4096], kind=refusal_kind(reason), **fields
    )


class CommandReply(_Msg, frozen=True, kw_only=True):
    """The answer to a command: applied, or refused with a reason and its ``kind``
    (:data:`REFUSAL_KINDS`; "": not said — an older CPU, or a refusal given no kind; a
    field added later, so a reply without it still reads). The engineering ops
    (``download``, ``undo_download``, ``save``, ``open``) add ``lines`` (a change summary,
    diagnostics, what the carry-over kept), ``version`` (the chart version running after a
    download, or seen by a preview) and ``text`` (the chart ``open`` read)."""

    applied: bool
    reason: Text = ""
    op: ShortText = ""
    fb: ShortText = ""
    cycle: Count | None = None
    lines: Lines = []
    version: Count | None = None
    removed: Steps = []  # active steps the change removes (the sender chooses keep or init)
    text: Annotated[str, Meta(max_length=MAX_SOURCE)] = ""
    kind: RefusalKindText = ""


# ---------------------------------------------------------------- login, audit, history


# A SCRAM message (RFC 5802): printable ASCII without spaces, bounded; a login's id.
ScramMessage = Annotated[str, Meta(pattern=r"^[!-~]{0,512}\Z")]
LoginId = Annotated[str, Meta(pattern=r"^[A-Za-z0-9_-]{0,32}\Z")]


class LoginRequest(_Request, frozen=True, kw_only=True):
    """``login`` queryable, a SCRAM-SHA-256 exchange (no password on the wire): ``login``
    with the user and the client-first message in ``scram`` (nothing more without a users
    file), then ``proof`` with the ``login_id`` answered and the client-final message; or
    ``logout`` with the token to revoke, signed (``mac``) with the session key."""

    op: Literal["login", "proof", "logout"]
    user: UserName = ""
    scram: ScramMessage = ""
    login_id: LoginId = ""
    token: Token = ""
    mac: Mac = ""
    origin: Origin = ""


class LoginReply(_Msg, frozen=True, kw_only=True):
    """The answer to one step. A challenge: ``ok`` false, a ``login_id`` and the
    server-first message in ``scram`` (send the proof). Logged in: a token valid until
    ``expires_ms`` (wall clock), the role, the server-final message in ``scram`` (the
    client checks the CPU's signature), ``verified`` False for a name claimed without a
    users file. Or a refusal and why."""

    ok: bool
    reason: Text = ""
    user: UserName = ""
    role: Annotated[str, Meta(max_length=16)] = ""
    token: Token = ""
    expires_ms: Count = 0
    verified: bool = True
    login_id: LoginId = ""
    scram: ScramMessage = ""


class AuditEntry(_Msg, frozen=True, kw_only=True):
    """One command as the CPU audited it (``audit``, ``audit/list``); ``count``: how many
    refusals of unauthenticated senders the row stands for (one minute, one source and
    reason) — published again, with the same ``id``, as it grows."""

    id: Count
    t_ms: Count
    user: Label
    role: Annotated[str, Meta(max_length=16)] = ""
    origin: Annotated[str, Meta(max_length=160)] = ""
    op: ShortText
    fb: ShortText = ""
    args: Text = ""
    outcome: Literal["applied", "refused"]
    reason: Text = ""
    count: Annotated[int, Meta(ge=1, le=2**63 - 1)] = 1
    claimed: Label = ""
    """The name an unauthenticated sender gave (``user`` is ``(unauthenticated)``): a
    claim nobody proved; "" for a proven author's row."""


class AuditList(_Msg, frozen=True, kw_only=True):
    """Audit rows, oldest first: the last ones (``audit/list``), or each message's newest
    acknowledgement with a comment (``audit/acked``)."""

    entries: Annotated[list[AuditEntry], Meta(max_length=1000)] = []


class AlarmEvent(_Msg, frozen=True, kw_only=True):
    """One message event of the alarm history: came (``incoming``), went (``outgoing``) or
    ``acknowledged`` by ``user``; wall time in ms."""

    id: Count
    t_ms: Count
    msg_id: MsgKey
    state: ShortText
    text: Text = ""
    user: Label = ""


class AlarmHistory(_Msg, frozen=True, kw_only=True):
    """The last message events, oldest first (``alarms/history``)."""

    entries: Annotated[list[AlarmEvent], Meta(max_length=1000)] = []


# ---------------------------------------------------------------- encode / decode

T = TypeVar("T")
_DECODERS: dict[type[Any], msgspec.json.Decoder[Any]] = {}


def _enc_hook(obj: object) -> object:
    """A :class:`Refusal` (a ``str`` that names its kind) as its text."""
    if isinstance(obj, str):
        return str(obj)
    raise NotImplementedError(f"cannot encode {type(obj).__name__}")


_ENCODER = msgspec.json.Encoder(enc_hook=_enc_hook)


def encode(message: Struct) -> bytes:
    """JSON bytes of a message."""
    return _ENCODER.encode(message)


def decode(data: bytes | bytearray | memoryview | str, kind: type[T]) -> T:
    """Decode JSON ``data`` as ``kind``; raise :class:`ProtocolError` with a clear reason."""
    try:
        size = len(data.encode() if isinstance(data, str) else data)
    except UnicodeEncodeError:
        raise ProtocolError(f"invalid {kind.__name__}: text that is not valid UTF-8") from None
    if size > MAX_MESSAGE_BYTES:
        raise ProtocolError(f"message too large: {size} bytes (limit {MAX_MESSAGE_BYTES})")
    decoder = _DECODERS.get(kind)
    if decoder is None:
        target: Any = AnyCommand if kind is Command else kind  # any op's struct
        decoder = _DECODERS[kind] = msgspec.json.Decoder(target)
    try:
        return decoder.decode(data)  # type: ignore[no-any-return]
    except msgspec.ValidationError as exc:
        reason = explain(_op_of(data) if kind is Command else None, str(exc))
        raise ProtocolError(f"invalid {kind.__name__}: {_one_line(reason)}") from None
    except msgspec.DecodeError as exc:
        raise ProtocolError(f"malformed JSON: {exc}") from None
    except (RecursionError, UnicodeError, ValueError, TypeError) as exc:
        raise ProtocolError(f"invalid {kind.__name__}: {_unreadable(exc)}") from None


def _unreadable(exc: Exception) -> str:
    """Why a message does not decode, in words (never the exception's class name)."""
    if isinstance(exc, RecursionError):
        return "nested too deeply (arrays or objects inside each other)"
    if isinstance(exc, UnicodeError):
        return "text that is not valid UTF-8"
    said = _one_line(" ".join(str(exc).split()))[:256]
    return f"a value that cannot be read: {said}" if said else "a value that cannot be read"


def _one_line(text: str) -> str:
    """``text`` with what it quotes of a hostile message escaped (``\\n``): one log line."""
    if text.isprintable():
        return text
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)


class _OpOnly(Struct):
    op: Any = None


def _op_of(data: bytes | bytearray | memoryview | str) -> object:
    """The ``op`` of a command that did not decode, to say what it lacks (None: unknown)."""
    try:
        return msgspec.json.decode(data, type=_OpOnly).op
    except (msgspec.MsgspecError, RecursionError, ValueError, TypeError):
        return None


def layout_problem(layout: ChartLayout) -> str | None:
    """Why a view would refuse ``layout`` as it comes over the bus (a limit of this
    protocol: steps, numbers, names, a step too large for one message), in words, or None
    when it decodes — whole or in parts (:func:`split_layout`)."""
    try:
        head, parts = split_layout(layout)
        decode(encode(head), ChartLayout)
    except (ProtocolError, msgspec.ValidationError) as exc:
        return _layout_words(layout, str(exc))
    for part in parts:
        try:
            decode(encode(part), ChartPart)
        except (ProtocolError, msgspec.ValidationError) as exc:
            return _layout_words(layout, _in_layout(str(exc), part))
    return None


def _in_layout(message: str, part: ChartPart) -> str:
    """A part's ``message`` with the place of its step or transition in the layout."""

    def shifted(m: re.Match[str]) -> str:
        first = part.first_step if m[1] == "steps" else part.first_transition
        return f"`$.{m[1]}[{int(m[2]) + first}]"

    return re.sub(r"`\$\.(steps|transitions)\[(\d+)\]", shifted, message)


_TOO_MANY = re.compile(r"^invalid \w+: Expected `array` of length <= (\d+) - at `\$\.(.+)`$")
_NOT_A_NAME = re.compile(r"^invalid \w+: Expected `str` matching regex .* - at `\$\.fb`$", re.S)


def _layout_words(layout: ChartLayout, message: str) -> str:
    """msgspec's ``message`` on ``layout`` in words, its place kept (as
    ``web.commands.explain`` says a command's): a list longer than the view draws (``a
    sequence (Main) has 5,000 steps, more than the 4,096 the view draws``), an FB name the
    bus cannot carry; any other as msgspec says it."""
    if _NOT_A_NAME.match(message):
        return (
            f"the FB name {layout.fb!r} is not one the bus carries: 1-64 of A-Z a-z 0-9 _ . -, "
            "not starting with a digit, dot or dash - at `$.fb`"
        )
    m = _TOO_MANY.match(message)
    if m is None:
        return message
    place = m[2]
    owner, _, field = place.rpartition(".")
    parent = _at(layout, owner) if owner else layout
    items = _at(layout, place)
    limit = int(m[1])
    if owner:
        kind = re.sub(r"\[\d+\]$", "", owner.rpartition(".")[2]).removesuffix("s")
        label = getattr(parent, "name", "") or getattr(parent, "number", "")
        whole = f"a {kind} ({label})" if label != "" else f"a {kind}"
    else:
        whole = "the chart"
    if isinstance(items, list):
        said = f"{whole} has {len(items):,} {field}, more than the {limit:,} the view draws"
    else:
        said = f"{whole} has more than {limit:,} {field}, more than the view draws"
    return f"{said} - at `$.{place}`"


def _at(layout: ChartLayout, place: str) -> object:
    """The value at ``place`` (``sequences[0].steps``) of ``layout``; None when there is
    none."""
    value: object = layout
    for name, index in re.findall(r"(\w+)|\[(\d+)\]", place):
        try:
            value = value[int(index)] if index else getattr(value, name)  # type: ignore[index]
        except (AttributeError, IndexError, TypeError):
            return None
    return value


def split_layout(
    layout: ChartLayout, limit: int = PART_BYTES
) -> tuple[ChartLayout, list[ChartPart]]:
    """``layout`` as it goes over the bus: whole if its JSON fits in ``limit`` bytes, else a
    head (its ``parts`` says how many follow) without the steps' action tables, and parts of
    at most ``limit`` bytes carrying the whole steps; if the head is still too large, it
    leaves out steps and transitions and the parts carry both. A single step or transition
    larger than ``limit`` gets a part of its own."""
    if len(encode(layout)) <= limit:
        return msgspec.structs.replace(layout, parts=0), []
    head = msgspec.structs.replace(
        layout, steps=[msgspec.structs.replace(s, actions=[]) for s in layout.steps], parts=0
    )
    chunks: list[tuple[str, int, list[Any]]] = [
        ("steps", k, c) for k, c in _chunks(layout.steps, limit)
    ]
    if len(encode(head)) > limit:
        head = msgspec.structs.replace(head, steps=[], transitions=[])
        chunks += [("transitions", k, c) for k, c in _chunks(layout.transitions, limit)]
    parts = []
    for k, (what, first, items) in enumerate(chunks):
        if what == "steps":
            part = ChartPart(
                fb=layout.fb, version=layout.version, k=k, first_step=first, steps=items
            )
        else:
            part = ChartPart(
                fb=layout.fb, version=layout.version, k=k, first_transition=first, transitions=items
            )
        parts.append(part)
    if len(parts) > MAX_PARTS:
        raise ProtocolError(f"chart layout too large: {len(parts)} parts (limit {MAX_PARTS})")
    return msgspec.structs.replace(head, parts=len(parts)), parts


def _chunks(items: list[Any], limit: int) -> list[tuple[int, list[Any]]]:
    """``items`` cut into runs whose JSON stays within ``limit`` bytes: (first index, run)."""
    out: list[tuple[int, list[Any]]] = []
    run: list[Any] = []
    size = first = 0
    for i, item in enumerate(items):
        n = len(encode(item)) + 1
        if run and size + n > limit - 256:  # room for the part's own fields
            out.append((first, run))
            run, size, first = [], 0, i
        run.append(item)
        size += n
    if run:
        out.append((first, run))
    return out


def join_layout(head: ChartLayout, parts: list[ChartPart]) -> ChartLayout:
    """The whole layout from its ``head`` and its parts (in any order); ``ProtocolError``
    when one is missing, of another chart version, or does not fit the head."""
    if len(parts) != head.parts or sorted(p.k for p in parts) != list(range(head.parts)):
        raise ProtocolError(f"chart layout: {len(parts)} of {head.parts} parts")
    steps, transitions = list(head.steps), list(head.transitions)
    for part in sorted(parts, key=lambda p: p.k):
        if part.fb != head.fb or part.version != head.version:
            raise ProtocolError(
                f"chart layout part {part.k} is of {part.fb} version {part.version}, "
                f"not {head.fb} version {head.version}"
            )
        _place(steps, part.first_step, part.steps, "steps")
        _place(transitions, part.first_transition, part.transitions, "transitions")
    return msgspec.structs.replace(head, steps=steps, transitions=transitions, parts=0)


def _place(into: list[Any], first: int, items: list[Any], what: str) -> None:
    """Put ``items`` at ``first`` of ``into``: over the head's (stripped) entries there, or
    after the last when the head left them out."""
    if not items:
        return
    if first > len(into):
        raise ProtocolError(f"chart layout: {what} from {first} follow only {len(into)}")
    into[first : first + len(items)] = items


def _clip(text: str, limit: int) -> str:
    return text if len(text) <= limit else text[: limit - 1] + "…"


# ---------------------------------------------------------------- condition text


def _condition(expr: Expr | None) -> tuple[str, list[tuple[int, int]]]:
    """A condition's text as a view shows it and where its contacts stand (none when the
    text had to be clipped before the end of a contact)."""
    text = _clip(condition_text(expr), 4096)
    written, spans = contact_spans(expr)
    if written != text:  # clipped (or written otherwise): keep the contacts that are whole
        spans = [(a, b) for a, b in spans if b < len(text) and text[:b] == written[:b]]
    return text, spans


def condition_text(expr: Expr | None) -> str:
    """An expression as S7 text (``"Start" AND NOT S3.X``); "" for an empty condition.
    The chart writer's printer (``sequencer.text.format``, one precedence table), a chain
    of AND, OR or XOR written without inner parentheses."""
    if expr is None:
        return ""
    return format_expr(expr, chains=True)
