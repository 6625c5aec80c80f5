"""A chart's calls of user FBs and FCs checked against the program's blocks (E047;
docs/cli.md, "s7graph check"): ``s7graph check CHART.s7g --blocks BLOCKS.scl``.

Without the program's blocks a call of a user block is not checked (only the program that
loads them knows them). With them, as a CALL in STEP 7 is checked against the called block
(STEP7 comprehensive guide vol. 2, ch. 14): the block is there; an FB has an instance DB
named by number, an FC none; that DB is no global DB and no instance of another FB, in the
program or in the chart's other calls; ``:=`` names an input or in/out, ``=>`` an output or
in/out, each once; an FC is given every parameter (its RET_VAL may be left out); a value
fits its parameter's type; an ARRAY, STRUCT or multi-instance parameter cannot be passed. A
BLOCK_DB input takes a DB (``DB5``, a DB's symbol) or its number as a WORD (``W#16#5``),
and a DB goes to a BLOCK_DB input only (S7-SCL manual, "Data types", parameter types).
Against the blocks a CPU holds (``validate(held=…)``: the editor, a download into the
running CPU) the same, but a call of a block the CPU lacks and an instance DB are left to
the swap, which judges them against the CPU itself (``sequencer.calls.plan_calls``).
"""

from __future__ import annotations

from collections.abc import Sequence

from s7graph.engine.errors import SourceLocation
from s7graph.sequencer.checks.context import _Ctx
from s7graph.sequencer.checks.interfaces import Interface, ProgramBlocks, UserPin
from s7graph.sequencer.checks.types import _CELL_FLEX, _as_bit, _as_number, _resolve, _show, _unify
from s7graph.sequencer.text.model import BlockCall, Const, Operand

__all__ = [
    "DB_TYPE",
    "check_instance",
    "check_own_blocks",
    "check_user_call",
    "db_only",
    "db_to_value",
    "instance_db_passed",
]

DB_TYPE = "@DB"
"""The type of a call's actual parameter that names a DB (``DB5``, ``"Recipe"``)."""

Typed = Sequence[tuple[str, str | None, object]]
"""Each parameter given: its name, the type of its value or operand (None: unknown), the
expression or operand (for its place)."""


def _where(call: BlockCall) -> str:
    return f"{call.kind} {call.block}" if call.kind else f'"{call.block}"'


def check_user_call(ctx: _Ctx, call: BlockCall, el: str, types: Typed) -> None:
    """E047 for each way ``call`` (of an FB, an FC or a block symbol) does not fit the
    program's blocks ``ctx.blocks``, or the CPU's ``ctx.held`` (a block the CPU lacks and
    the instance DB are the swap's to judge). Without either, the blocks the compiler reads
    (``ctx.readable``) check what goes to a BLOCK_DB input and where a DB goes: a mistake
    there would hand the block a DB's number for a value, or a value for a DB's number."""
    program = ctx.blocks if ctx.blocks is not None else ctx.held
    if program is None:
        block = ctx.readable.find(call.kind, call.block) if ctx.readable is not None else None
    else:
        block = program.find(call.kind, call.block)
        if block is None and program is ctx.blocks:
            _not_in_program(ctx, call, el, program)
        elif block is not None:
            _check_block(ctx, call, el, block)
    if block is None:
        return
    for name, t, e in types:
        pin = block.pin(name)
        if pin is not None and (t == DB_TYPE or pin.type == "BLOCK_DB"):
            _check_block_db(ctx, block, pin, t, e, el)
        elif pin is not None and program is not None:
            _check_value(ctx, call, el, block, pin, t, e)


def _not_in_program(ctx: _Ctx, call: BlockCall, el: str, program: ProgramBlocks) -> None:
    kind = call.kind or "FB"
    known = f"{kind}s: {program.known(kind)}" if call.kind else "no block of that name"
    why = f"{_where(call)} is not in the program's blocks ({program.sources}; {known})"
    ctx.err("E047", why, call.loc, el)


def _check_block(ctx: _Ctx, call: BlockCall, el: str, block: Interface) -> None:
    """An FB's instance DB, an FC without one; the parameters named."""
    if block.kind == "FB":
        _check_fb_instance(ctx, call, el, block)
    elif call.instance is not None:
        ctx.err("E047", f"{block.label} is an FC and takes no instance DB", call.loc, el)
    _check_pins(ctx, call, el, block)


def _check_value(
    ctx: _Ctx, call: BlockCall, el: str, block: Interface, pin: UserPin, t: str | None, e: object
) -> None:
    """The value given for ``pin`` fits its type; an in/out's is an operand in memory."""
    loc = getattr(e, "loc", call.loc)
    if t is not None:
        _check_type(ctx, block, pin, t, loc, el)
    if pin.direction == "IN_OUT" and not _in_memory(ctx, e, el):
        why = (
            f"{block.label}: {pin.name} is an in/out parameter: it takes an operand in "
            "memory (an address or its symbol), which the block writes back"
        )
        ctx.err("E047", why, loc, el)


def db_only(e: object) -> str:
    """Why a DB does not fit a parameter that is no BLOCK_DB."""
    text = f'"{e.name}"' if isinstance(e, Operand) and e.quoted else getattr(e, "name", "")
    return f"{text} is a DB, which only a BLOCK_DB input takes"


def db_to_value(block: str, pin: str, type_: object, e: object) -> str:
    """Why the DB ``e`` does not fit ``block``'s parameter ``pin`` of ``type_`` (no
    BLOCK_DB): one wording for the checks and for a load against the CPU's block."""
    shown = _show(type_) if isinstance(type_, str) else str(type_)
    return f"{block}: {pin} is {shown}; {db_only(e)}"


def instance_db_passed(number: int, owner: str) -> str:
    """Why the instance DB ``number`` of ``owner`` cannot go to a BLOCK_DB input."""
    return (
        f"DB{number} is the instance DB of {owner}; it holds its variables by name, not the "
        "bytes a BLOCK_DB input reaches"
    )


def _check_block_db(
    ctx: _Ctx, block: Interface, pin: UserPin, t: str | None, e: object, el: str
) -> None:
    """A DB to a BLOCK_DB input, or its number as a WORD (not 0: a DB is numbered
    1..65535); a DB to no other parameter."""
    loc = getattr(e, "loc", SourceLocation())
    if pin.type != "BLOCK_DB":
        ctx.err("E047", db_to_value(block.label, pin.name, pin.type, e), loc, el)
    elif t is not None and t != DB_TYPE and _unify("WORD", t) != "WORD":
        why = (
            f"{block.label}: {pin.name} is a BLOCK_DB: pass a DB (DB5, a DB's symbol) or its "
            f"number as a WORD (W#16#5), not {_show(t)}"
        )
        ctx.err("E047", why, loc, el)
    elif isinstance(e, Const) and e.value == 0:
        why = f"{block.label}: {pin.name} is a BLOCK_DB: {e.text} is no DB (numbered 1..65535)"
        ctx.err("E047", why, loc, el)


def _in_memory(ctx: _Ctx, e: object, el: str) -> bool:
    """Whether ``e`` is an operand in the CPU's memory (an address or a symbol of one, not
    a timer or counter cell): what a call writes an in/out parameter back to."""
    if not isinstance(e, Operand):
        return False
    res = _resolve(ctx, e, el)
    return res is None or (res.kind in ("address", "symbol") and res.type not in _CELL_FLEX)


def _check_fb_instance(ctx: _Ctx, call: BlockCall, el: str, block: Interface) -> None:
    if call.instance is None:
        why = f"{block.label} is an FB and needs an instance DB (CALL FB {block.number}, DB n)"
        ctx.err("E047", why, call.loc, el)
    elif not isinstance(call.instance, int):
        why = f"{block.label}: name its instance DB by number (DB 10), not {call.instance!r}"
        ctx.err("E047", why, call.loc, el)
    elif ctx.blocks is not None:  # the CPU's blocks: the swap judges the DB (plan_calls)
        check_instance(ctx, call, el, block.label)


def check_instance(ctx: _Ctx, call: BlockCall, el: str, label: str) -> None:
    """The instance DB ``call`` names for ``label`` (an FB or SFB): no global DB and no
    instance of another block, in the program (when given) or in the chart's other calls."""
    number = call.instance
    if not isinstance(number, int):
        return
    code = "E046" if label.startswith("SFB") else "E047"
    program = ctx.blocks
    if program is not None and number in program.global_dbs:
        why = f"DB{number} is a global DB of the program, not an instance DB of {label}"
        ctx.err(code, why, call.loc, el)
        return
    held = program.instances.get(number) if program is not None else None
    if held is not None and held != label:
        why = f"DB{number} is the instance DB of {held} in the program, not of {label}"
        ctx.err(code, why, call.loc, el)
        return
    other = ctx.instances.setdefault(number, label)
    if other != label:
        ctx.err(code, f"DB{number} is the instance DB of {other} already", call.loc, el)


def _check_pins(ctx: _Ctx, call: BlockCall, el: str, block: Interface) -> None:
    seen: set[str] = set()
    for names, given_as_input in (
        ([n for n, _ in call.inputs], True),
        ([n for n, _ in call.outputs], False),
    ):
        for name in names:
            pin = block.pin(name)
            if pin is None:
                known = ", ".join(p.name for p in block.pins) or "none"
                why = f"{block.label} has no parameter {name} (parameters: {known})"
                ctx.err("E047", why, call.loc, el)
                continue
            if pin.name.upper() in seen:
                ctx.err("E047", f"{block.label}: parameter {pin.name} given twice", call.loc, el)
            seen.add(pin.name.upper())
            if given_as_input and not pin.is_input:
                why = f"{block.label}: {pin.name} is an output, use {pin.name} => ..."
                ctx.err("E047", why, call.loc, el)
            if not given_as_input and not pin.is_output:
                why = f"{block.label}: {pin.name} is an input, use {pin.name} := ..."
                ctx.err("E047", why, call.loc, el)
    missing = [p.name for p in block.pins if p.name.upper() not in seen and p.name != "RET_VAL"]
    if block.kind == "FC" and missing:
        why = f"{block.label}: an FC takes every parameter; {', '.join(missing)} missing"
        ctx.err("E047", why, call.loc, el)


def _check_type(
    ctx: _Ctx, block: Interface, pin: UserPin, t: str, loc: SourceLocation, el: str
) -> None:
    want = pin.type.upper()
    if want == "OBJECT" or want.startswith(("ARRAY", "STRUCT")):
        why = f"{block.label}: {pin.name} is an ARRAY or STRUCT; a chart passes elementary values"
        ctx.err("E047", why, loc, el)
        return
    if want in ("TIMER", "COUNTER"):
        fits = t == ("@T" if want == "TIMER" else "@C")
    elif want == "ANY":
        fits = True
    else:
        fits = _unify(want, _as_bit(t) if want == "BOOL" else _as_number(t)) is not None
    if not fits:
        why = f"{block.label}: {pin.name} is {_show(want)}, {_show(t)} does not fit it"
        ctx.err("E047", why, loc, el)


def check_own_blocks(ctx: _Ctx) -> None:
    """E047 when the program's blocks write the chart's own FB or instance DB (the header's
    ``FB n DB m``): loaded beside the chart, one would replace the other."""
    program, chart = ctx.blocks, ctx.chart
    if program is None:
        return
    fb = program.blocks.get(f"FB{chart.fb_number}") if chart.fb_number is not None else None
    if fb is not None and fb.label == f"FB{chart.fb_number}":
        why = f"FB{chart.fb_number}, the chart's FB, is a block of the program too"
        ctx.err("E047", f"{why} ({program.sources})", chart.loc)
    number = chart.db_number
    if number is not None and (number in program.global_dbs or number in program.instances):
        why = f"DB{number}, the chart's instance DB, is a DB of the program too"
        ctx.err("E047", f"{why} ({program.sources})", chart.loc)
