"""The face's address space: the CPU, its FBs with their sequences and steps, the
symbol table's operands, and what the bus says of them (docs/opcua.md, "The address
space").

:class:`Space` builds the nodes from what the CPU serves — its status, each FB's chart
layout, the operand catalog (``web.bus.operands``) — and writes what it publishes into
them: the status (1 Hz and on change), each scan's state delta, the operand values. It
rebuilds an FB's sequences and steps when an online change brings another chart version,
and marks every value ``UncertainNoCommunicationLastUsableValue`` (keeping it: a Bad status
would empty it: OPC UA Part 4, "DataValue") while the CPU is gone from the
bus. Writable variables and methods are the face's (``web.opcua.face``) to serve:
:class:`Space` only says where they are.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from datetime import UTC, datetime
from typing import Any, Final, NamedTuple

import msgspec
from asyncua import ua

from s7graph.engine.modify import MODIFY_POINTS
from s7graph.web.bus.protocol import (
    ChartLayout,
    CpuStatus,
    DiagEvent,
    FbOperands,
    OperandCatalog,
    OperandInfo,
    OperandValues,
    StepStateUpdate,
)
from s7graph.web.opcua import sync
from s7graph.web.opcua.alarms import SEVERITY, condition_name
from s7graph.web.opcua.conditions import add_condition
from s7graph.web.opcua.diag import event_id_text
from s7graph.web.opcua.methods import MethodSpec, output_arguments
from s7graph.web.opcua.model import (
    BOOLEAN,
    MS,
    PERCENT,
    TEXT,
    UaType,
    node_id,
    to_variant,
    ua_type,
)
from s7graph.web.opcua.nodes import GOOD, Nodes
from s7graph.web.opcua.typed import ObjectIds, Server, StatusCodes, ua_id

__all__ = ["FORCEABLE", "WRITES", "Space", "StepNodes", "Writes", "symbol_writable"]

UINT16: Final = UaType(ua.VariantType.UInt16, "int", 0, 0xFFFF)
UINT32: Final = UaType(ua.VariantType.UInt32, "int", 0, 0xFFFF_FFFF)
UINT64: Final = UaType(ua.VariantType.UInt64, "int", 0, 2**64 - 1)
INT16: Final = UaType(ua.VariantType.Int16, "int", -(2**15), 2**15 - 1)
DURATION: Final = UaType(ua.VariantType.Double, "float", unit=MS, node=ObjectIds.Duration)
SHARE: Final = UaType(ua.VariantType.Double, "float", unit=PERCENT)
FORCEABLE: Final = ("I", "Q", "M")
"""The areas a force job takes: a symbol there is writable (an engineer's force)."""


class Writes(NamedTuple):
    """What a client's writes may reach under one ``--writes``: the areas whose symbols
    are writable, and whether a chart's own variables (an FB's ``Variables``) are."""

    areas: tuple[str, ...]
    variables: bool


WRITES: Final[dict[str, Writes]] = {
    "force": Writes(FORCEABLE, variables=False),
    "modify": Writes(tuple(str(area) for area in MODIFY_POINTS), variables=True),
}
"""The op a client's write of a symbol or a chart's variable sends (``s7graph opcua
--writes``), and what it makes writable: a ``force`` job, held until unforced (symbols on
I, Q, M), or a ``modify``, written once at the scan boundary as an S7-1500's OPC UA server
writes a PLC tag (symbols on I, Q, M, DB, and a chart's own variables by its instance DB's
name, ``"Seq_mix".count``)."""
STALE: Final = StatusCodes.UncertainNoCommunicationLastUsableValue
UNREADABLE: Final = StatusCodes.BadConfigurationError


def symbol_writable(address: str, op: str) -> bool:
    """Whether a client may write the symbol at ``address`` when a write sends ``op``."""
    area = "DB" if address.startswith("DB") else address[:1]
    writes = WRITES.get(op)
    return writes is not None and area in writes.areas


def _event_id(event: DiagEvent | None) -> str:
    return event_id_text(event.event_id) if event is not None else ""


# The CPU's status: its variables, their types, and how a status gives their value.
_CPU_VARS: Final[tuple[tuple[str, UaType, str, Callable[[CpuStatus], object]], ...]] = (
    ("State", TEXT, "the CPU's operating mode: RUN, STOP, STARTUP or HOLD", lambda s: s.state),
    ("StopReason", TEXT, "why the CPU is in STOP ('' in RUN)", lambda s: s.reason),
    (
        "StopEventId",
        TEXT,
        "in STOP: the event ID of the STOP's diagnostic entry, 16#4304 ('' in RUN)",
        lambda s: _event_id(s.stop if s.state == "STOP" else None),
    ),
    (
        "StopCauseEventId",
        TEXT,
        "in STOP: the event ID of the error entry that caused it ('': none, or in RUN)",
        lambda s: _event_id(s.cause if s.state == "STOP" else None),
    ),
    ("Cycle", UINT64, "scans since the CPU started", lambda s: s.cycle),
    ("Logins", TEXT, "users: logins checked; demo: names claimed", lambda s: s.login),
    ("ForceJobs", UINT32, "force jobs active (the FRCE LED is on when > 0)", lambda s: s.forces),
)
_CYCLE_VARS: Final[tuple[tuple[str, UaType, str, str], ...]] = (
    ("Last", DURATION, "the last cycle time", "last_ms"),
    ("Min", DURATION, "the shortest cycle time", "min_ms"),
    ("Max", DURATION, "the longest cycle time", "max_ms"),
    ("Execution", DURATION, "the mean execution time of a scan", "exec_ms"),
    ("Overruns", UINT64, "cycles that overran the set cycle time", "overruns"),
    ("LongCycles", UINT64, "cycles longer than LongOver", "long"),
    ("LongOver", DURATION, "the length above which a cycle counts as long", "long_over_ms"),
    ("CommLoad", SHARE, "the share of the cycle commands may take (0: not limited)", "comm_load"),
    (
        "CommLimited",
        UINT64,
        "scan boundaries whose share ran out with commands waiting",
        "comm_limited",
    ),
    (
        "ScanPriority",
        UINT16,
        "the scan thread's real-time priority (SCHED_FIFO; 0: normal scheduling)",
        "priority",
    ),
    ("ScanCore", INT16, "the processor kept for the scan thread (-1: none)", "core"),
)
# An FB's own variables: name, type, description, writable (the op a write sends).
_FB_VARS: Final[tuple[tuple[str, UaType, str, str], ...]] = (
    ("Mode", TEXT, "AUTO, MAN, TAP or TOP; a write switches it (op mode)", "mode"),
    ("Halted", BOOLEAN, "HALT_SQ in force; a write holds or frees it (op halt)", "halt"),
    ("InterlocksEnabled", BOOLEAN, "EN_IL; false written holds it off (op en_il)", "en_il"),
    ("SupervisionsEnabled", BOOLEAN, "EN_SV; false written holds it off (op en_sv)", "en_sv"),
    ("ActiveSteps", UINT16, "the active steps' numbers", ""),
    ("Disturbed", UINT16, "steps with an interlock error or a supervision fault", ""),
    ("ChartVersion", UINT64, "the chart version running (1 at start, +1 per download)", ""),
)
_SEQUENCE_VARS: Final[tuple[tuple[str, UaType, str], ...]] = (
    ("Number", UINT16, "the sequence's number"),
    ("Name", TEXT, "the sequence's name"),
)
_STEP_VARS: Final[tuple[tuple[str, UaType, str], ...]] = (
    ("Number", UINT16, "the step's number"),
    ("Name", TEXT, "the step's name"),
    ("Initial", BOOLEAN, "an initial step"),
    ("Active", BOOLEAN, "the step is active (Sn.X)"),
    ("T", DURATION, "time active, to 0.1 s, updated once a second (Sn.T; kept when it leaves)"),
    ("U", DURATION, "time active without a fault (Sn.U; kept when it leaves)"),
    ("Fault", BOOLEAN, "an interlock error or a supervision fault"),
    ("InterlockError", BOOLEAN, "the interlock does not hold (active step)"),
    ("SupervisionFault", BOOLEAN, "a supervision fault, waiting for acknowledgement"),
)


@dataclass
class StepNodes:
    """The node of one step and of its variables (by name)."""

    node: ua.NodeId
    vars: dict[str, ua.NodeId]
    conditions: dict[str, ua.NodeId] = field(default_factory=dict)  # IL/SV -> node
    t_ms: int = 0
    u_ms: int = 0
    sequence: int = 0  # the sequence it is in
    shape: tuple[bool, bool] | None = None  # it has an interlock, a supervision


@dataclass
class FbNodes:
    """One FB's nodes: the object, its variables, sequences (by number), steps (by
    number), pins and variables of the chart (by name, with their types)."""

    node: ua.NodeId
    vars: dict[str, ua.NodeId]
    version: int = -1
    sequences: dict[int, ua.NodeId] = field(default_factory=dict)
    steps: dict[int, StepNodes] = field(default_factory=dict)
    operands: dict[str, tuple[ua.NodeId, UaType]] = field(default_factory=dict)
    touched: set[int] = field(default_factory=set)  # the steps the last state set


def _described(fb: str, folder: str, info: OperandInfo) -> str:
    """An FB operand's description: a pin's direction and type and its comment; a chart
    variable's comment in the chart and its type, or without one what it is
    (``the chart's variable count of the GRAPH FB Seq_mix (INT)``)."""
    if folder == "Pins":
        said = f": {info.comment}" if info.comment else ""
        return f"{info.direction} {info.type}".strip() + said
    if info.comment:
        return f"{info.comment} ({info.type})"
    return f"the chart's variable {info.name} of the GRAPH FB {fb} ({info.type})"


def _v(value: object, t: UaType) -> ua.Variant:
    return to_variant(value, t)


class Space:
    """The CPU ``cpu`` as nodes of namespace ``ns`` of ``server``."""

    def __init__(self, server: Server, ns: int, cpu: str, *, writes: str = "force") -> None:
        self.server = server
        self.symbol_op = writes
        """The op a write of a symbol or a chart's variable sends: ``force`` or ``modify``
        (:data:`WRITES`)."""
        self.ns = ns
        self.cpu = cpu
        self.nodes = Nodes(server, ns)
        self.root = node_id(ns, cpu)
        self.fbs: dict[str, FbNodes] = {}
        self.symbols: dict[str, tuple[ua.NodeId, UaType]] = {}
        self.targets: dict[ua.NodeId, OperandInfo] = {}
        """A writable symbol's or chart variable's operand: its type, and the address or
        name a write sends (``"Seq_mix".count`` for a chart's variable)."""
        self.writes: dict[ua.NodeId, tuple[str, str]] = {}
        """A writable variable's FB and the op a write sends (a symbol's: ``symbol_op``)."""
        self.catalog_version = -1
        self._cpu_vars: dict[str, ua.NodeId] = {}
        self.online = False

    def nid(self, *parts: str) -> ua.NodeId:
        return node_id(self.ns, self.cpu, *parts)

    # ------------------------------------------------------------ building

    async def build_cpu(
        self, status: CpuStatus | None, methods: Iterable[tuple[MethodSpec, Callable[..., Any]]]
    ) -> None:
        """The CPU's object under Objects, its status variables, folders and methods."""
        n = self.nodes
        objects = ua_id(ObjectIds.ObjectsFolder)
        n.obj(
            objects,
            self.root,
            self.cpu,
            description=f"the s7graph CPU {self.cpu}, as its bus shows it",
            ref=ObjectIds.Organizes,
            notifier=True,
        )
        for name, t, text, _ in _CPU_VARS:
            self._cpu_vars[name] = n.var(self.root, self.nid(name), name, t, description=text)
        self._cpu_vars["Online"] = n.var(
            self.root, self.nid("Online"), "Online", BOOLEAN, description="the CPU is on the bus"
        )
        cycle = n.folder(self.root, self.nid("CycleTime"), "CycleTime", "the cycle statistics")
        for name, t, text, _ in _CYCLE_VARS:
            self._cpu_vars["CycleTime/" + name] = n.var(
                cycle, self.nid("CycleTime", name), name, t, description=text
            )
        n.folder(self.root, self.nid("Symbols"), "Symbols", "the symbol table's operands")
        n.folder(self.root, self.nid("Messages"), "Messages", "messages of no step, as conditions")
        for spec, callback in methods:
            self._method(self.root, (), spec, callback)
        await n.flush()
        if status is not None:
            await self.apply_status(status)

    def _method(
        self,
        parent: ua.NodeId,
        path: tuple[str, ...],
        spec: MethodSpec,
        callback: Callable[..., Any],
    ) -> None:
        self.nodes.method(
            parent,
            self.nid(*path, spec.name),
            spec.name,
            callback,
            description=spec.description,
            inputs=[a.argument() for a in spec.args],
            outputs=output_arguments(spec),
        )

    async def build_fb(
        self,
        fb: str,
        layout: ChartLayout,
        methods: Iterable[tuple[MethodSpec, Callable[..., Any]]],
        synchronize: Callable[..., Any] | None = None,
    ) -> None:
        """An FB's object under the CPU's: its variables, sequences and steps, methods (and
        ``Synchronize`` with the callback ``synchronize``)."""
        n = self.nodes
        node = n.obj(self.root, self.nid(fb), fb, description=f"the GRAPH FB {fb}")
        nodes = FbNodes(node, {})
        for name, t, text, op in _FB_VARS:
            array = name in ("ActiveSteps", "Disturbed")
            nodes.vars[name] = n.var(
                node, self.nid(fb, name), name, t, description=text, writable=bool(op), array=array
            )
            if op:
                self.writes[nodes.vars[name]] = (fb, op)
        n.folder(node, self.nid(fb, "Pins"), "Pins", "the pins of the FB's parameter set")
        n.folder(node, self.nid(fb, "Variables"), "Variables", "the chart's variables (VAR)")
        for spec, callback in methods:
            self._method(node, (fb,), spec, callback)
        if synchronize is not None:
            n.method(
                node,
                self.nid(fb, sync.NAME),
                sync.NAME,
                synchronize,
                description=sync.DESCRIPTION,
                inputs=[],
                outputs=sync.sync_output_arguments(),
            )
        self.fbs[fb] = nodes
        await n.flush()
        await self.build_chart(fb, layout)

    async def build_chart(self, fb: str, layout: ChartLayout) -> None:
        """The FB's sequences and steps for chart ``layout``; again after a download, as
        a change: a step kept keeps its nodes (a client's monitored items with them),
        one gone, moved to another sequence or given another interlock or supervision
        loses them, a new one gets them; names are renamed in place."""
        fbn = self.fbs[fb]
        if layout.version == fbn.version:
            return
        n = self.nodes
        infos = {s.number: s for s in layout.steps}
        sequence_of = {number: q.number for q in layout.sequences for number in q.steps}
        for number, nodes in list(fbn.steps.items()):
            info = infos.get(number)
            shape = (info.interlock, info.supervision) if info is not None else None
            if sequence_of.get(number) != nodes.sequence or shape != nodes.shape:
                await n.delete(nodes.node)
                del fbn.steps[number]
        numbers = {q.number for q in layout.sequences}
        for number, seq in list(fbn.sequences.items()):
            if number not in numbers:
                await n.delete(seq)
                del fbn.sequences[number]
        for q in layout.sequences:
            nid = self.nid(fb, f"Sequence{q.number}")
            n.root(nid)
            if q.number not in fbn.sequences:
                n.obj(fbn.node, nid, f"Sequence{q.number}")
                for var, t, text in _SEQUENCE_VARS:
                    n.var(nid, self.nid(fb, f"Sequence{q.number}", var), var, t, description=text)
                fbn.sequences[q.number] = nid
            for number in q.steps:
                if number not in fbn.steps and number in infos:
                    fbn.steps[number] = self._step(fb, nid, infos[number], q.number)
            n.end_root()
        await n.flush()
        fbn.version = layout.version
        fbn.touched = set(fbn.steps)  # the next state sets every step
        await self._names(fb, layout)

    async def _names(self, fb: str, layout: ChartLayout) -> None:
        """The sequences' and steps' names, numbers and display names of ``layout``."""
        fbn, n = self.fbs[fb], self.nodes
        for q in layout.sequences:
            nid = fbn.sequences[q.number]
            await n.rename(nid, f"Sequence {q.number}" + (f" {q.name}" if q.name else ""))
            await n.set(self.nid(fb, f"Sequence{q.number}", "Number"), _v(q.number, UINT16))
            await n.set(self.nid(fb, f"Sequence{q.number}", "Name"), _v(q.name, TEXT))
        for s in layout.steps:
            nodes = fbn.steps.get(s.number)
            if nodes is not None:
                await n.rename(nodes.node, f"S{s.number} {s.name}".strip(), s.message)
                await n.set(nodes.vars["Number"], _v(s.number, UINT16))
                await n.set(nodes.vars["Name"], _v(s.name, TEXT))
                await n.set(nodes.vars["Initial"], _v(s.initial, BOOLEAN))
        await n.set(fbn.vars["ChartVersion"], _v(layout.version, UINT64))

    def _step(self, fb: str, parent: ua.NodeId, step: Any, sequence: int) -> StepNodes:
        n = self.nodes
        key = f"S{step.number}"
        nid = self.nid(fb, key)
        n.root(nid)
        shown = f"{key} {step.name}".strip()  # as _names shows it: no rename at the start
        n.obj(parent, nid, key, display=shown, description=step.message)
        nodes = StepNodes(nid, {}, sequence=sequence, shape=(step.interlock, step.supervision))
        for var, t, text in _STEP_VARS:
            nodes.vars[var] = n.var(nid, self.nid(fb, key, var), var, t, description=text)
        for kind, flag in (("IL", step.interlock), ("SV", step.supervision)):
            if flag:
                cond = self.nid(fb, key, condition_name(kind))
                add_condition(
                    n,
                    nid,
                    cond,
                    condition_name(kind),
                    display=f"{key} {condition_name(kind)}",
                    severity=SEVERITY[kind],
                )
                n.reference(nid, cond, ObjectIds.HasCondition)
                nodes.conditions[kind] = cond
        n.end_root()
        return nodes

    async def build_operands(self, catalog: OperandCatalog) -> None:
        """The symbols' variables and each FB's pins and variables of ``catalog`` (again
        when its version changes: the old ones go)."""
        if catalog.version == self.catalog_version:
            return
        n = self.nodes
        for root in [self.nid("Symbols", s) for s in self.symbols]:
            await n.delete(root)
        for nid in list(self.targets):
            self.writes.pop(nid, None)
        self.targets.clear()
        self.symbols.clear()
        folder = self.nid("Symbols")
        for info in catalog.symbols:
            t = ua_type(info.type)
            nid = self.nid("Symbols", info.name)
            n.root(nid)
            text = f"{info.address} {info.type}" + (f": {info.comment}" if info.comment else "")
            writable = symbol_writable(info.address, self.symbol_op)
            n.var(folder, nid, info.name, t, description=text, writable=writable)
            n.prop(
                nid, "Address", ua.Variant(info.address, ua.VariantType.String), ObjectIds.String
            )
            n.end_root()
            self.symbols[info.name] = (nid, t)
            if writable:
                self.writes[nid] = ("", self.symbol_op)
                self.targets[nid] = info
        for fbn in self.fbs.values():
            for nid, _ in list(fbn.operands.values()):
                await n.delete(nid)
            fbn.operands.clear()
        for fb, operands in catalog.fbs.items():
            if fb in self.fbs:
                self._fb_operands(fb, operands)
        await n.flush()
        self.catalog_version = catalog.version

    def _fb_operands(self, fb: str, operands: FbOperands) -> None:
        fbn, n = self.fbs[fb], self.nodes
        writes = WRITES.get(self.symbol_op)
        for folder, infos in (("Pins", operands.pins), ("Variables", operands.variables)):
            writable = folder == "Variables" and writes is not None and writes.variables
            for info in infos:
                t = ua_type(info.type)
                nid = self.nid(fb, folder, info.name)
                n.root(nid)
                text = _described(fb, folder, info)
                n.var(self.nid(fb, folder), nid, info.name, t, description=text, writable=writable)
                n.end_root()
                fbn.operands[info.name] = (nid, t)
                if writable:
                    self.writes[nid] = (fb, self.symbol_op)
                    self.targets[nid] = msgspec.structs.replace(info, address=f'"{fb}".{info.name}')

    # ------------------------------------------------------------ values

    async def apply_status(self, status: CpuStatus) -> None:
        n, v = self.nodes, self._cpu_vars
        for name, t, _, read in _CPU_VARS:
            await self._put(v[name], read(status), t)
        await n.set(v["Online"], _v(self.online, BOOLEAN))
        stats = status.stats
        if stats is None:
            return
        for name, t, _, attr in _CYCLE_VARS:
            await self._put(v["CycleTime/" + name], getattr(stats, attr), t)

    async def _put(
        self, nid: ua.NodeId, value: object, t: UaType, when: datetime | None = None
    ) -> None:
        try:
            variant = to_variant(value, t)
        except (ValueError, TypeError, OverflowError):
            await self.nodes.set(nid, None, UNREADABLE, when)
            return
        await self.nodes.set(nid, variant, GOOD, when)

    async def apply_state(self, fb: str, update: StepStateUpdate) -> None:
        """One scan's state of FB ``fb``: its variables, its steps, its output pins."""
        fbn = self.fbs.get(fb)
        if fbn is None:
            return
        now = datetime.now(UTC)
        put = self._put
        await put(fbn.vars["Mode"], update.mode, TEXT, now)
        await put(fbn.vars["Halted"], update.halted, BOOLEAN, now)
        await put(fbn.vars["InterlocksEnabled"], update.il_enabled, BOOLEAN, now)
        await put(fbn.vars["SupervisionsEnabled"], update.sv_enabled, BOOLEAN, now)
        await self.nodes.set(
            fbn.vars["ActiveSteps"],
            ua.Variant(list(update.active), ua.VariantType.UInt16),
            GOOD,
            now,
        )
        await self.nodes.set(
            fbn.vars["Disturbed"],
            ua.Variant(list(update.disturbed), ua.VariantType.UInt16),
            GOOD,
            now,
        )
        active, disturbed, latched = set(update.active), set(update.disturbed), set(update.latched)
        details = {d.number: d for d in update.details}
        touched = active | disturbed | latched
        for number in sorted(touched | fbn.touched):
            step = fbn.steps.get(number)
            if step is None:
                continue
            d = details.get(number)
            if d is not None:
                step.t_ms, step.u_ms = d.t_ms, d.u_ms
            on = number in active
            await put(step.vars["Active"], on, BOOLEAN, now)
            await put(step.vars["T"], step.t_ms, DURATION, now)
            await put(step.vars["U"], step.u_ms, DURATION, now)
            await put(step.vars["Fault"], number in disturbed, BOOLEAN, now)
            il = d is not None and d.interlock_error
            await put(step.vars["InterlockError"], il, BOOLEAN, now)
            await put(
                step.vars["SupervisionFault"],
                number in latched or (d is not None and d.supervision_fault),
                BOOLEAN,
                now,
            )
        fbn.touched = touched
        for name, value in update.values.items():
            pin = fbn.operands.get(name)
            if pin is not None:
                await put(pin[0], value, pin[1], now)

    async def apply_operands(self, values: OperandValues) -> None:
        now = datetime.now(UTC)
        for name, (nid, t) in self.symbols.items():
            if name in values.symbols:
                await self._put(nid, values.symbols[name], t, now)
            else:
                await self.nodes.set(nid, None, UNREADABLE, now)
        for fb, fb_values in values.fbs.items():
            fbn = self.fbs.get(fb)
            if fbn is None:
                continue
            for name, (nid, t) in fbn.operands.items():
                if name in fb_values:
                    await self._put(nid, fb_values[name], t, now)

    async def set_online(self, online: bool) -> None:
        """The CPU came (its values follow from the bus) or went: every value written so
        far keeps its last value with ``UncertainNoCommunicationLastUsableValue``."""
        self.online = online
        await self.nodes.set(self._cpu_vars["Online"], _v(online, BOOLEAN))
        if online:
            for fbn in self.fbs.values():
                fbn.touched = set(fbn.steps)
            return
        for nid in self.nodes.written():
            if nid != self._cpu_vars["Online"]:
                await self.nodes.set(nid, None, STALE)

    # ------------------------------------------------------------ looking up

    def condition(self, fb: str, step: int, kind: str) -> ua.NodeId | None:
        fbn = self.fbs.get(fb)
        nodes = fbn.steps.get(step) if fbn is not None else None
        return nodes.conditions.get(kind) if nodes is not None else None

    def step_node(self, fb: str, step: int) -> ua.NodeId | None:
        fbn = self.fbs.get(fb)
        nodes = fbn.steps.get(step) if fbn is not None else None
        return nodes.node if nodes is not None else None

    async def message_condition(self, key: str, text: str, kind: str = "") -> ua.NodeId:
        """The condition node of a message of no step, ``Messages/<key>`` (made now when
        it is new; ``kind`` the message's, for its severity)."""
        nid = self.nid("Messages", key)
        if nid not in self.nodes.under:
            self.nodes.root(nid)
            add_condition(
                self.nodes,
                self.nid("Messages"),
                nid,
                key[:128],
                display=f"Message {key}",
                description=text or key,
                severity=SEVERITY.get(kind, SEVERITY[""]),
                condition=f"Message {key}",
            )
            self.nodes.end_root()
            self.nodes.reference(self.root, nid, ObjectIds.HasCondition)
            await self.nodes.flush()
        return nid
