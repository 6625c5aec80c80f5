"""An IEC 61131-3 sequential function chart as written, before it becomes a GRAPH chart.

The textual reader (``exchange.iec_text``) and the PLCopen XML reader (``exchange.plcopen``)
both build this; ``exchange.iec_to_chart`` maps it to the chart model with the rules of
``exchange.mapping``. Steps are named (IEC), every element keeps its place in the file.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from s7graph.engine.errors import SourceLocation
from s7graph.sequencer.exchange.st import SExpr, SStmt

__all__ = [
    "IecAction",
    "IecAssociation",
    "IecChart",
    "IecStep",
    "IecTransition",
    "IecVar",
    "StatementBody",
    "Unsupported",
]


@dataclass
class IecVar:
    """One declared variable; ``kind`` input output inout local external global temp;
    ``address`` the IEC location (``%IX0.1``) or ""; ``type`` upper case (a derived type
    or FB type keeps its name)."""

    name: str
    type: str
    kind: str
    loc: SourceLocation
    address: str = ""
    init: SExpr | None = None
    constant: bool = False


@dataclass
class Unsupported:
    """A body the importer cannot read (IL, an LD/FBD network beyond contacts and coils,
    a language it does not know): ``what`` says what it is."""

    what: str
    loc: SourceLocation


@dataclass
class StatementBody:
    """A transition body of ST statements rather than an expression (CODESYS, TwinCAT):
    it assigns the transition's value to the transition's ``name``."""

    name: str
    body: list[SStmt]
    text: str
    loc: SourceLocation
    origin: tuple[int, int] = (1, 1)


@dataclass
class IecAction:
    """A named action: its body is ST statements or an ``Unsupported`` one."""

    name: str
    body: list[SStmt] | Unsupported
    loc: SourceLocation
    origin: tuple[int, int] = (1, 1)  # where the body's text starts (ST places are relative)
    text: str = ""  # an ST body as written (kept for the SCL block when rows cannot hold it)


@dataclass
class IecAssociation:
    """``ACTION(qualifier, duration, indicator)`` of a step; an inline action carries its
    own body (``inline``)."""

    action: str
    qualifier: str
    loc: SourceLocation
    duration: str = ""
    indicator: str = ""
    inline: IecAction | None = None
    phase: str = ""  # CODESYS step actions: "entry", "active" or "exit" (qualifier unused)


@dataclass
class IecStep:
    name: str
    initial: bool
    loc: SourceLocation
    associations: list[IecAssociation] = field(default_factory=list)
    graph_number: int | None = None  # s7graph's own export carries the GRAPH data
    graph: dict[str, str] = field(default_factory=dict)


@dataclass
class IecTransition:
    """``TRANSITION [name] [(PRIORITY := n)] FROM … TO … := condition``; ``targets`` empty
    means the path ends (no IEC form; only s7graph's own export writes it). ``condition``
    is an ST expression, ST statements (``StatementBody``) or ``Unsupported`` (IL, a
    network the importer cannot read);
    ``order`` sorts the transitions leaving one step (priority, then left to right, then
    as written)."""

    sources: list[str]
    targets: list[str]
    condition: SExpr | Unsupported | StatementBody | None
    loc: SourceLocation
    name: str = ""
    priority: int | None = None
    x: float | None = None
    order: int = 0
    cond_origin: tuple[int, int] = (1, 1)
    jumps: set[str] = field(default_factory=set)  # targets reached through a jump
    graph_number: int | None = None
    graph: dict[str, str] = field(default_factory=dict)


@dataclass
class IecChart:
    """One POU with an SFC body. ``prelude``: statements of its body outside the SFC
    elements (textual SFC), run every call before the chart."""

    name: str
    kind: str  # functionBlock | program | function
    loc: SourceLocation
    dialect: str = "iec"  # beremiz | codesys | twincat | s7graph | iec
    vars: list[IecVar] = field(default_factory=list)
    steps: list[IecStep] = field(default_factory=list)
    transitions: list[IecTransition] = field(default_factory=list)
    actions: dict[str, IecAction] = field(default_factory=dict)
    prelude: list[SStmt] = field(default_factory=list)
    prelude_text: str = ""  # the prelude as written
    sfc_actions: set[str] = field(default_factory=set)  # actions that are charts (upper case)
    graph: dict[str, str] = field(default_factory=dict)
