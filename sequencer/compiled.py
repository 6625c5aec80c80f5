"""CompiledChart: a chart as immutable, int-indexed data plus one compiled code object
(docs/architecture.md, "The core is a function"; docs/semantics.md, "Structure").

Steps and transitions are numbered ``0..n-1`` in definition order (sequence by sequence).
``leaving[i]`` lists the transitions leaving step ``i`` in priority order (the first written,
then by number: docs/semantics.md, "One FB call", step 4.2; ``compile.alternative_priority``).
All conditions and action programs of the chart are one generated Python module
(``source``), compiled once; ``bind(mem)`` executes it against one CPU's memory and returns
the ``Program`` (tuples of functions indexed like the steps/transitions).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from types import CodeType, FunctionType
from typing import Any

from s7graph.engine.errors import AddressError, SymbolError
from s7graph.sequencer.text.model import Chart, ChartOptions
from s7graph.steps.expressions import RUNTIME as EXPR_RUNTIME
from s7graph.steps.operands import RUNTIME as OPERAND_RUNTIME
from s7graph.steps.operands import area_buffer


class LiveValues:
    """The variables of instance DB ``number`` of ``instance_dbs`` as they are at each read:
    a user FB's instance DB is made again when its FB is downloaded into the running CPU
    (``engine.cpu_program.replace_instance_db``), and the chart reads the new one."""

    __slots__ = ("instance_dbs", "number")

    def __init__(self, instance_dbs: Mapping[int, Any], number: int) -> None:
        self.instance_dbs = instance_dbs
        self.number = number

    def __getitem__(self, name: str) -> Any:
        return self.instance_dbs[self.number].values[name]


@dataclass(frozen=True, slots=True)
class Program:
    """The generated functions of a chart bound to one memory.

    ``tcond[j](st) -> (bool, crit)``; ``ilc[i]``/``svc[i]`` the same or None (no interlock /
    supervision); ``act[i](st, R, ev, c_ok, zero)``; ``fin[i](st, R, ev)``;
    ``before(st, R)``/``after(st, R)`` the permanent instructions; ``step[i](st, R, ev,
    c_ok, zero) -> int`` (None for a step with an interlock, a supervision or a join): the
    leaving transitions of step ``i`` in priority order (``crit_old``/``crit``/``tt`` as
    each is evaluated) returning the first that holds, else -1 after running ``act[i]``'s
    rows; ``enter[j](st, R, ev, ev_d, zero)`` (None unless ``j`` leaves a step that has
    ``step[i]`` for one target ``d`` of the same sequencer without interlock or
    supervision): the final scan of the source step (``fin``, events ``ev``) and then the
    rows of ``d`` (``act[d]``, events ``ev_d``, interlock held); ``pulse[i](st)`` (None
    unless step ``i`` has ``S0 N`` rows): their operands back to 0, in the call after the
    one that left the step (the end of their one-call pulse)."""

    tcond: tuple[Any, ...]
    ilc: tuple[Any, ...]
    svc: tuple[Any, ...]
    act: tuple[Any, ...]
    fin: tuple[Any, ...]
    before: Any
    after: Any
    step: tuple[Any, ...] = ()
    enter: tuple[Any, ...] = ()
    pulse: tuple[Any, ...] = ()


Reach = tuple[str, int | None, int, str]
"""``(area, db, end, operand)``: an operand of the chart uses ``area`` (of DB ``db``) up to
byte ``end`` (for ``T``/``C``: cells up to number ``end`` - 1)."""


def _check_reach(reach: tuple[Reach, ...], mem: Any) -> None:
    """Refuse memory an operand reaches beyond, naming the operand (S7: an area length
    error), before the chart runs — a generated access would fail, or grow the area."""
    for area, db, end, name in reach:
        if area in ("T", "C"):
            cells = getattr(mem, "timers" if area == "T" else "counters", None)
            if cells is not None and end > len(cells):
                raise AddressError(f"{name}: only {len(cells)} {area} cells exist")
            continue
        size = len(area_buffer(mem, area, db))
        if end > size:
            where = f"DB{db}" if db is not None else f"the {area} area"
            raise AddressError(f"{name} is outside {where} ({size} bytes)")


def reach_problem(
    buffers: tuple[tuple[str, int | None], ...], reach: tuple[Reach, ...], mem: Any
) -> str | None:
    """Why ``mem`` lacks what a chart's operands use (``buffers``: the areas and DBs;
    ``reach``: how far), or None (:meth:`CompiledChart.reach_problem`)."""
    try:
        for area, db in buffers:
            area_buffer(mem, area, db)
        _check_reach(reach, mem)
    except (AddressError, SymbolError) as exc:
        return str(exc)
    return None


@dataclass(frozen=True)
class CompiledChart:
    chart: Chart
    options: ChartOptions
    parameters: str
    step_numbers: tuple[int, ...]
    step_names: tuple[str, ...]
    step_seq: tuple[int, ...]  # sequence index of each step
    initial: tuple[int, ...]  # indices of the initial steps
    has_interlock: tuple[bool, ...]
    has_supervision: tuple[bool, ...]
    transition_numbers: tuple[int, ...]
    transition_names: tuple[str, ...]
    tr_seq: tuple[int, ...]
    tr_src: tuple[tuple[int, ...], ...]  # preceding step indices
    tr_dst: tuple[tuple[int, ...], ...]  # following step indices; () = branch stop
    leaving: tuple[tuple[int, ...], ...]  # per step: leaving transitions, priority order
    seq_numbers: tuple[int, ...]
    seq_names: tuple[str, ...]
    seq_steps: tuple[tuple[int, ...], ...]
    crit_labels: tuple[tuple[str, ...], ...]  # per transition: contact texts
    il_labels: tuple[tuple[str, ...], ...]
    sv_labels: tuple[tuple[str, ...], ...]
    var_inits: dict[str, Any]
    var_types: dict[str, str]
    source: str
    code: tuple[CodeType, ...]  # the module, compiled in pieces (compile._batches)
    buffers: tuple[tuple[str, int | None], ...]
    consts: dict[str, Any]
    reach: tuple[Reach, ...] = ()
    """What the operands reach (``compile._Resolver.reaches``): ``bind`` refuses memory too
    small for them."""
    idbs: tuple[int, ...] = ()
    """The instance DBs whose variables the chart reads by name (``DB10.Q``,
    ``CodeGen.idbs``): ``bind`` binds each one's ``values``."""
    step_index: dict[int, int] = field(default_factory=dict)
    transition_index: dict[int, int] = field(default_factory=dict)
    warnings: tuple[str, ...] = ()
    # generated functions that share the code of another (``compile._share``): (name, name
    # of the compiled one, its other index defaults or None); ``code`` holds only the
    # distinct ones, ``source`` shows all
    aliases: tuple[tuple[str, str, tuple[int, ...] | None], ...] = ()

    @property
    def name(self) -> str:
        return self.chart.name

    @property
    def n_steps(self) -> int:
        return len(self.step_numbers)

    @property
    def n_transitions(self) -> int:
        return len(self.transition_numbers)

    def reach_problem(self, mem: Any) -> str | None:
        """Why :meth:`bind` would refuse ``mem`` (a DB the chart uses that does not exist, an
        operand beyond its area), or None: at an online change, said before the swap instead
        of stopping the CPU at the chart's first call."""
        return reach_problem(self.buffers, self.reach, mem)

    def bind(self, mem: Any, instance_dbs: Mapping[int, Any] | None = None) -> Program:
        """Execute the generated module against ``mem`` (once per FB instance);
        ``instance_dbs`` (the CPU's, by number) hold the variables the chart reads by name
        (``idbs``: ``DB10.Q``); the calls' ``prepare_calls`` created them. A system block's
        instance DB is bound as it is; a user FB's is looked up at each read
        (``LiveValues``)."""
        ns: dict[str, Any] = {"__builtins__": __builtins__, "_mem": mem}
        ns.update(OPERAND_RUNTIME)
        ns.update(EXPR_RUNTIME)
        ns.update(self.consts)
        for k, (area, db) in enumerate(self.buffers):
            ns[f"_m{k}"] = area_buffer(mem, area, db)
        _check_reach(self.reach, mem)
        dbs: Mapping[int, Any] = instance_dbs if instance_dbs is not None else {}
        for k, db in enumerate(self.idbs):
            idb = dbs.get(db)
            if idb is None:
                raise SymbolError(f"DB{db} is not an instance DB of this CPU (DB{db}.… read)")
            system = str(getattr(idb.fb, "kind", "")) == "SFB"
            ns[f"_d{k}"] = idb.values if system else LiveValues(dbs, db)
        for piece in self.code:
            exec(piece, ns)
        for name, first, defaults in self.aliases:
            f = ns[first]
            if defaults is not None:
                f = FunctionType(f.__code__, f.__globals__, f.__name__, defaults, f.__closure__)
            ns[name] = f
        n, m = self.n_steps, self.n_transitions
        return Program(
            tcond=tuple(ns[f"_t{j}"] for j in range(m)),
            ilc=tuple(ns.get(f"_il{i}") for i in range(n)),
            svc=tuple(ns.get(f"_sv{i}") for i in range(n)),
            act=tuple(ns[f"_a{i}"] for i in range(n)),
            fin=tuple(ns[f"_f{i}"] for i in range(n)),
            before=ns["_before"],
            after=ns["_after"],
            step=tuple(ns.get(f"_s{i}") for i in range(n)),
            enter=tuple(ns.get(f"_w{j}") for j in range(m)),
            pulse=tuple(ns.get(f"_p{i}") for i in range(n)),
        )

    def step_label(self, i: int) -> str:
        return f"S{self.step_numbers[i]}"

    def transition_label(self, j: int) -> str:
        return f"T{self.transition_numbers[j]}"
