"""The blocks a chart calls, and the instance DBs its calls of system blocks need.

A chart calls blocks from action rows (``CALL SFB 4, DB 10 (IN := …)``) and permanent instructions,
FBs, FCs, SFBs and SFCs alike (STEP7 comprehensive guide vol. 2, ch. 14). A system block belongs to
the CPU's operating system, as on S7; the instance DB an SFB call names is created with the chart,
as the SCL compiler creates the DB a call names when it does not exist (STEP7 comprehensive guide
vol. 2, ch. 13). So ``prepare_calls(cpu, chart)`` runs before a chart is first called — at load, and
at an online change before the swap: it creates each missing instance DB of an SFB call, and of a
call of a user FB the CPU has loaded (an S7-SCL FB of ``--blocks``), and refuses (nothing created)
when a named DB is already something else: a global DB, or the instance of another block. A call
of a user block (``CALL FC 9``, ``CALL FB 5, DB 5``) that the CPU has not loaded is
reported in ``missing``: a chart run by itself has the system blocks only, and the call stops the
CPU when it is reached (a programming error without OB121, as on S7). A download into the running
CPU may not add such a call: ``swap`` refuses it. A DB a call passes (``src := DB5``, a DB's
symbol) goes to a BLOCK_DB input of the block the CPU holds, else the chart is refused: the
block would take the DB's number for a value. The calls are walked as the chart's text
walks them (``sequencer.text.call_sites``).

A chart compiled without the program's blocks has its calls of user blocks unchecked; run,
a call that does not fit its block (a parameter it lacks, a value of another type, an
output given with ``:=``) stops the CPU when reached. ``unfit_calls`` is the check a
download into a running CPU makes against the blocks the CPU holds: E047 as ``s7graph
check --blocks`` words it, for the calls of those blocks only — a call of a block the CPU
lacks, and an instance DB that is something else, are ``plan_calls``'s to judge.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

from s7graph.engine.errors import BlockError
from s7graph.sequencer.checks.interfaces import ProgramBlocks, is_block_db
from s7graph.sequencer.checks.user_calls import db_to_value, instance_db_passed
from s7graph.sequencer.checks.validate import validate
from s7graph.sequencer.text.call_sites import CallSite, call_sites
from s7graph.sequencer.text.model import BlockCall, Chart, Operand
from s7graph.sequencer.text.names import db_argument
from s7graph.steps.diagnostics import Diagnostic

__all__ = [
    "CallPlan",
    "CallSite",
    "call_sites",
    "missing_blocks",
    "plan_calls",
    "prepare_calls",
    "unfit_calls",
]


@dataclass(slots=True)
class CallPlan:
    """What ``prepare_calls`` found: ``problems`` refuse the chart, ``missing`` are user
    blocks it calls that the CPU does not have, ``created`` the instance DBs it made."""

    problems: list[str] = field(default_factory=list)
    missing: list[str] = field(default_factory=list)
    created: list[int] = field(default_factory=list)
    missing_blocks: set[str] = field(default_factory=set)  # their labels: FC9, FB5
    wanted: dict[int, Any] = field(default_factory=dict)  # instance DB → its block, to create


def prepare_calls(cpu: Any, chart: Chart, *, allowed_missing: set[str] | None = None) -> CallPlan:
    """Create the instance DBs ``chart``'s SFB calls name in ``cpu`` (an ``engine.Cpu``);
    nothing is created when one of them cannot be (``problems``). With ``allowed_missing``
    (a download into a running CPU: the blocks the running chart already lacks), a call of
    any other block the CPU lacks is a problem too: reached, it would stop the plant."""
    table = getattr(cpu.mem, "symbols", None)
    sites = call_sites(chart)
    plan = plan_calls(
        cpu, sites, allowed_missing=allowed_missing, dbs=lambda e: db_argument(e, chart, table)
    )
    if not plan.problems:
        for number, block in plan.wanted.items():
            cpu.create_instance_db(number, block)
            plan.created.append(number)
    return plan


def plan_calls(
    cpu: Any,
    sites: Iterable[CallSite],
    *,
    allowed_missing: set[str] | None = None,
    find: Callable[[str], Any] | None = None,
    dbs: Callable[[object], int | None] | None = None,
) -> CallPlan:
    """What :func:`prepare_calls` finds for the calls ``sites``, nothing created (the
    instance DBs it would create in ``wanted``): an online change's preview says so before
    the swap. ``find``: the block of a label, None when the CPU lacks it (default: the
    CPU's own; a preview with S7-SCL sources looks in those first). ``dbs``: the DB an
    actual parameter names, if any (default: ``DB5``, or a DB symbol of the CPU's table)."""
    plan = CallPlan()
    look = find if find is not None else _finder(cpu)
    if dbs is None:
        dbs = functools.partial(db_argument, chart=None, symbols=getattr(cpu.mem, "symbols", None))
    by_label = find is not None
    for site in sites:
        c = site.call
        label = _label(c)
        block = look(label)
        if block is None:
            plan.missing_blocks.add(label)
            if allowed_missing is not None and label not in allowed_missing:
                why = f"{label} is not in this CPU; reached, the call would stop it"
                plan.problems.append(site.line("error", why))
            else:
                why = f"{label} is not in this CPU; reached, the call stops it"
                plan.missing.append(site.line("warning", why))
            continue
        _check_db_inputs(plan, site, block, dbs, cpu.instance_dbs)
        if getattr(block, "kind", None) not in ("SFB", "FB"):  # by number or name ("TON")
            continue
        if not isinstance(c.instance, int):
            plan.problems.append(site.line("error", "name the instance DB by its number"))
            continue
        held = cpu.instance_dbs.get(c.instance)
        # a preview's block of new sources is the one the download makes its DB's FB
        same = held is not None and (
            held.fb is block or (by_label and held.fb.label == block.label)
        )
        if held is not None and not same:
            why = f"DB{c.instance} is the instance DB of {held.fb.label} {held.fb.name!r}"
            plan.problems.append(site.line("error", why))
        elif held is None and c.instance in cpu.mem.dbs:
            plan.problems.append(site.line("error", f"DB{c.instance} is a global DB"))
        elif held is None and plan.wanted.setdefault(c.instance, block) is not block:
            why = f"DB{c.instance} is named as the instance of another block too"
            plan.problems.append(site.line("error", why))
    return plan


def _check_db_inputs(
    plan: CallPlan,
    site: CallSite,
    block: Any,
    dbs: Callable[[object], int | None],
    instances: Mapping[int, Any],
) -> None:
    """A problem for each DB ``site`` passes to a parameter of ``block`` that is no
    BLOCK_DB input (``block`` as the CPU holds it: a chart compiled without the program's
    blocks has not been checked against them), and for an instance DB passed: it holds
    values by name, no bytes for the block to reach."""
    params = {v.name.upper(): v for v in getattr(block, "interface", ())}
    for name, e in site.call.inputs:
        var = params.get(name.upper())
        number = dbs(e) if var is not None and isinstance(e, Operand) else None
        if var is None or number is None or not isinstance(e, Operand):
            continue
        if not is_block_db(var):
            why = db_to_value(block.label, var.name, var.type, e)
            plan.problems.append(site.line("error", why))
        elif (held := instances.get(number)) is not None:
            what = f'"{e.name}"' if e.quoted else e.name
            why = f"{what}: {instance_db_passed(number, held.fb.label)}"
            plan.problems.append(site.line("error", why))


def unfit_calls(chart: Chart, symbols: Any, blocks: ProgramBlocks) -> list[Diagnostic]:
    """The E047 errors of ``chart``'s calls of the user blocks ``blocks`` holds (the CPU's):
    a parameter the block lacks, given twice or the wrong way (an output with ``:=``), a
    value of another type, an FB without an instance DB, an FC with one, an FC not given
    every parameter. A call of a block ``blocks`` lacks is left out (the swap's rule for
    blocks the CPU lacks), and so is the judgement of an instance DB (``plan_calls``): the
    validator's check against the CPU's blocks (``validate(held=…)``), in one pass."""
    if not any(blocks.find(s.call.kind, s.call.block) for s in call_sites(chart)):
        return []  # no call of the CPU's blocks: nothing to check
    return [d for d in validate(chart, symbols, held=blocks) if d.is_error and d.code == "E047"]


def _finder(cpu: Any) -> Callable[[str], Any]:
    def find(label: str) -> Any:
        try:
            return cpu.block(label)
        except BlockError:  # not loaded
            return None

    return find


def missing_blocks(cpu: Any, chart: Chart) -> set[str]:
    """The labels of the blocks ``chart`` calls that ``cpu`` does not have."""
    out: set[str] = set()
    for label in {_label(site.call) for site in call_sites(chart)}:
        try:
            cpu.block(label)
        except BlockError:
            out.add(label)
    return out


def _label(c: BlockCall) -> str:
    """``FC9``, ``SFB4`` or a symbolic name: what ``Cpu.block`` looks up."""
    return f"{c.kind}{c.block}" if c.kind else str(c.block)
