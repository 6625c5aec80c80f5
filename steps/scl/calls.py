"""Calls in SCL syntax: functions, FCs and SFCs, FBs and SFBs with their instance DB,
multi-instances, EN and ENO (docs/scl.md, "Calls"; the guide ch. 13, calling FBs and FCs).

``FB17.DB10(FINALVAL := 10, IQ1 := v)`` writes the inputs into the instance, runs the FB and
copies the in/out parameters back; its outputs are read afterwards (``DB10.CONTROL``), as in
S7-SCL V5. ``FC1(X := 1, D := dist)`` passes inputs, in/outs, and takes outputs into the
variables named; ``v := FC1(…)`` also takes the function value. An FC may be called inside
an expression with inputs only. ``EN := c`` runs the block only when ``c`` holds (else ENO
is FALSE); ``ENO`` then reads the called block's OK flag. A block is found at run time by
label in the CPU's block table, as a CALL finds it.
"""

from __future__ import annotations

from s7graph.engine.blocks import Decl
from s7graph.engine.datatypes import ms_to_s5time
from s7graph.engine.errors import SourceLocation
from s7graph.steps.scl import model as m
from s7graph.steps.scl import types as ty
from s7graph.steps.scl.builtins import BUILTINS, bind
from s7graph.steps.scl.declare import BlockInfo, Param
from s7graph.steps.scl.diagnostics import Problem
from s7graph.steps.scl.gen import Block, Place, Target, X, in_memory

S5_TIMERS = {"S_PULSE": "SP", "S_PEXT": "SE", "S_ODT": "SD", "S_ODTS": "SS", "S_OFFDT": "SF"}
S5_COUNTERS = {"S_CU": ("CU",), "S_CD": ("CD",), "S_CUD": ("CU", "CD")}
_S5_OUTPUTS = {"BI": ty.WORD, "CV": ty.WORD, "Q": ty.BOOL}


class Calls:
    """The call translator of one block."""

    def __init__(self, b: Block) -> None:
        self.b = b

    def _args(self, target: Target) -> list[tuple[str, X, SourceLocation]]:
        return [(a.name, self.b.exprs.expr(a.value), a.loc) for a in target.args.items]

    # ---- in an expression

    def value(self, target: Target) -> X:
        """A function value: a built-in function, or an FC given inputs only."""
        if target.kind == "builtin":
            if target.name in S5_TIMERS or target.name in S5_COUNTERS:
                return self._s5(target, None, value=True)
            if target.name not in BUILTINS:
                raise Problem("E232", f"{target.name} is called as a statement", target.loc)
            spec = BUILTINS[target.name]
            xs = bind(target.name, spec.params, self._args(target), target.loc)
            return spec.gen(self.b, xs, target.loc)
        info = target.info
        if target.kind != "fc" or info is None:
            raise Problem("E232", f"{target.name} has no value: call it as a statement", target.loc)
        if info.ret is None:
            raise Problem("E232", f"{info.label} is VOID: it has no value", target.loc)
        inputs, en, outputs = self._fc_params(info, target)
        if outputs or en is not None:
            raise Problem("E232", "an FC in an expression takes inputs only", target.loc)
        args = ", ".join(f"{name!r}: {src}" for name, src in inputs)
        src = f"_fcall(ctx, _eno, _block(ctx, {info.label!r}), {{{args}}})"
        return X(info.ret, src)

    # ---- as a statement

    def statement(self, target: Target, result: Place | None = None) -> None:
        """Emit the call; ``result`` receives an FC's value (``v := FC1(…)``)."""
        if target.kind == "builtin":
            if target.name in S5_TIMERS or target.name in S5_COUNTERS:
                self._s5(target, result)
                return
            raise Problem("E232", f"the value of {target.name} must be used", target.loc)
        info = target.info
        assert info is not None
        if target.kind == "fc":
            self._fc(info, target, result)
        elif result is not None:
            raise Problem("E232", f"{info.label} is an FB: it has no function value", target.loc)
        else:
            self._fb(info, target)

    def _fc_params(
        self, info: BlockInfo, target: Target
    ) -> tuple[list[tuple[str, str]], str | None, list[tuple[Param, Place]]]:
        """The FC's inputs and in/outs as ``(name, source)``, EN, and outputs with their
        targets (in/outs are among the outputs too)."""
        args = target.args.items
        if len(args) == 1 and not args[0].name:
            ins = [p for p in info.params.values() if p.decl is not Decl.OUT]
            if len(ins) != 1:
                raise Problem("E230", f"{info.label}: name the parameters (x := …)", target.loc)
            args = (m.Arg(ins[0].name, args[0].value, args[0].loc),)
        inputs: list[tuple[str, str]] = []
        outputs: list[tuple[Param, Place]] = []
        en: str | None = None
        seen: set[str] = set()
        for arg in args:
            key = arg.name.upper()
            if key == "EN":
                en = self.b.exprs.cond(arg.value)
                continue
            param = self._param(info, arg, seen)
            if param.decl is Decl.OUT:
                outputs.append((param, self._actual_place(arg)))
                continue
            if param.decl is Decl.IN_OUT:
                place = self._actual_place(arg)
                self._in_out_type(param, place, arg)
                inputs.append((param.name, place.get))
                outputs.append((param, place))
                continue
            inputs.append((param.name, self._input(info, param, arg)))
        missing = [p.name for p in info.params.values() if p.decl is not Decl.OUT]
        missing = [n for n in missing if n.upper() not in seen]
        if missing:
            raise Problem(
                "E231", f"{info.label}: parameter {', '.join(missing)} missing", target.loc
            )
        return inputs, en, outputs

    def _param(self, info: BlockInfo, arg: m.Arg, seen: set[str]) -> Param:
        key = arg.name.upper()
        param = info.params.get(key)
        if not arg.name or param is None or param.decl is Decl.STAT or key in seen:
            what = arg.name or "(unnamed)"
            raise Problem(
                "E230", f"{info.label} has no parameter {what}, or it is given twice", arg.loc
            )
        seen.add(key)
        return param

    def _input(self, info: BlockInfo, param: Param, arg: m.Arg) -> str:
        """Python source of an input's value; for a system block's ANY parameter the pointer
        text it reads (``P#DB5.DBX4.0 BYTE 20``)."""
        if param.type.kind == "ANY":
            return self._pointer(info, param, arg)
        if param.type.kind == "BLOCK_DB":
            return self._block_db(param, arg)
        x = self.b.exprs.expr(arg.value)
        return self.b.exprs.convert(x, param.type, arg.loc, "pass")

    def _block_db(self, param: Param, arg: m.Arg) -> str:
        """A BLOCK_DB input takes a DB — ``DB10``, a DB's symbol, ``WORD_TO_BLOCK_DB(w)`` —
        or a BLOCK_DB parameter of the caller: the DB's number (S7-SCL manual, "Data types",
        parameter types)."""
        path = arg.value if isinstance(arg.value, m.Path) else None
        wanted = f'{param.name} is a BLOCK_DB: pass a DB (DB10, "Data"), WORD_TO_BLOCK_DB(w)'
        base = path.base if path is not None and not path.selectors else None
        if base is not None and base.text.upper() not in self.b.locals:
            number = self.b.prog.db_number(base.text)
            if number is not None and base.kind in ("block", "symbol", "name"):
                if not 1 <= number <= 65535:
                    raise Problem("E214", f"DB{number}: a DB is numbered 1..65535", arg.loc)
                return str(number)
            if base.kind in ("block", "symbol"):
                raise Problem(
                    "E220", f"{wanted} or a BLOCK_DB parameter; {base.text} is no DB", arg.loc
                )
        sels = path.selectors if path is not None else ()
        if path is not None and path.base.text.upper() == "WORD_TO_BLOCK_DB" and len(sels) == 1:
            call = sels[0]
            if isinstance(call, m.Args):
                return self.b.places.block_db_number(call, path.loc)
        x = self.b.exprs.expr(arg.value)
        if x.type.kind in ("BLOCK_DB", "ERROR"):
            return x.src
        a = "an" if str(x.type)[:1] in "AEIOU" else "a"
        raise Problem("E220", f"{wanted} or a BLOCK_DB parameter, not {a} {x.type}", arg.loc)

    def _pointer(self, info: BlockInfo, param: Param, arg: m.Arg) -> str:
        """An ANY parameter (SFC 20 BLKMOV's SRCBLK and DSTBLK, SFC 21 FILL's BVAL and BLK …)
        points at its actual: an absolute operand (``MW10``, ``DB5.DBW2``, ``MD[i]``) or a
        variable of a global DB (``DB5.recipe``, ``"Data".temps[i]``), whose bytes the block
        reads and writes. A variable of the block itself is held as a value, not as bytes,
        and has no address to point at (E220). A string constant is taken as the pointer
        text itself (``'P#DB5.DBX0.0 BYTE 20'``)."""
        called = info.label if info.name.upper() == info.label else f"{info.name} ({info.label})"
        if isinstance(arg.value, m.Path):
            got = self.b.places.resolve(arg.value)
            if isinstance(got, Place) and got.pointer:
                return got.pointer
            if isinstance(got, Place):
                raise Problem(
                    "E220",
                    f"{called}: {param.name} is an ANY pointer to bytes; {got.what} is a "
                    "variable of the block, held as a value: pass an absolute operand "
                    "(MW10, DB5.DBW2) or a variable of a global DB, or assign it whole",
                    arg.loc,
                )
        x = self.b.exprs.expr(arg.value)
        if x.const is not None and isinstance(x.const.value, str) and x.type.kind == "STRING":
            return x.src
        raise Problem(
            "E220",
            f"{called}: {param.name} is an ANY pointer: pass an absolute operand or a "
            f"variable of a global DB, not the value of an expression ({x.type})",
            arg.loc,
        )

    def _actual_place(self, arg: m.Arg) -> Place:
        if not isinstance(arg.value, m.Path):
            raise Problem("E223", f"{arg.name} needs a variable, not a value", arg.loc)
        return self.b.places.place(arg.value, writing=True)

    def _in_out_type(self, param: Param, place: Place, arg: m.Arg) -> None:
        """An in/out parameter takes a variable of its very type — a STRUCT's member names
        too, as the block reads and writes them by name (S7 passes the variable itself)."""
        if not (ty.widens(place.type, param.type) and ty.widens(param.type, place.type)):
            raise Problem("E220", f"{param.name} is {param.type}; {place.type} is passed", arg.loc)
        if param.type.aggregate and place.type != param.type:
            raise Problem(
                "E220",
                f"{param.name} is {_described(param.type)}; {_described(place.type)} is passed "
                "(an in/out STRUCT takes one with the same member names)",
                arg.loc,
            )

    def _fc(self, info: BlockInfo, target: Target, result: Place | None) -> None:
        b = self.b
        inputs, en, outputs = self._fc_params(info, target)
        if result is not None and info.ret is None:
            raise Problem("E232", f"{info.label} is VOID: it has no value to assign", target.loc)
        a, r = b.temp("a"), b.temp("r")
        b.emit(f"{a} = {{{', '.join(f'{n!r}: {s}' for n, s in inputs)}}}")
        if en is not None:
            b.emit(f"if {en}:")
            b.indent += 1
        b.emit(f"{r} = ctx._invoke(_block(ctx, {info.label!r}), {a})")
        b.emit(f"_eno[0] = {a}.pop('ENO', True) is not False")
        for param, place in outputs:
            value = self._take(X(param.type, f"{a}[{param.name!r}]"), place, target)
            b.emit(f"if {param.name!r} in {a}: {place.store(value)}")
        if result is not None:
            assert info.ret is not None
            b.emit(result.store(self._take(X(info.ret, r), result, target)))
        if en is not None:
            b.indent -= 1
            b.emit("else:")
            b.emit("    _eno[0] = False")

    def _take(self, x: X, place: Place, target: Target) -> str:
        return self.b.exprs.convert(x, place.type, target.loc, "assign")

    def _fb(self, info: BlockInfo, target: Target) -> None:
        """``FB17.DB10(…)`` or ``inst(…)``: inputs into the instance, run, in/outs back."""
        b = self.b
        i, v = b.temp("i"), b.temp("v")
        lines: list[str] = []
        backs: list[str] = []
        en: str | None = None
        seen: set[str] = set()
        for arg in target.args.items:
            if arg.name.upper() == "EN":
                en = b.exprs.cond(arg.value)
                continue
            param = self._param(info, arg, seen)
            item = f"{v}[{param.name!r}]"
            if param.decl is Decl.OUT:
                raise Problem("E230", f"{param.name} is an output: read it after the call", arg.loc)
            if param.decl is Decl.IN_OUT:
                place = self._actual_place(arg)
                self._in_out_type(param, place, arg)
                lines.append(f"{item} = {place.get}")
                backs.append(place.store(self._take(X(param.type, item), place, target)))
                continue
            lines.append(f"{item} = {self._input(info, param, arg)}")
        if en is not None:
            b.emit(f"if {en}:")
            b.indent += 1
        b.emit(f"{i} = {target.instance}")
        b.emit(f"{v} = {i}.values")
        for line in lines:
            b.emit(line)
        # the engine's own call path (``engine.context.CallContext._invoke``: nesting depth,
        # scan marks, the innermost block named in an error); ENO is what an SCL FB returns,
        # its OK flag, and TRUE for any other block
        b.emit(f"_eno[0] = ctx._invoke({i}.fb, {i}) is not False")
        for line in backs:
            b.emit(line)
        if en is not None:
            b.indent -= 1
            b.emit("else:")
            b.emit("    _eno[0] = False")

    # ---- S5 timers and counters

    def _s5(self, target: Target, result: Place | None, value: bool = False) -> X:
        """``S_ODT(T_NO := T10, S := x, TV := T#1S, R := r, BI := w, Q := q)`` and the
        counters ``S_CUD(C_NO := C3, CU := …, CD := …, S := …, PV := …, R := …, CV := w,
        Q := q)``: the function value is the remaining time (S5TIME) or the count (BCD)."""
        b, name = self.b, target.name
        timer = name in S5_TIMERS
        ins = ("S", "TV", "R") if timer else ("CU", "CD", "S", "PV", "R")
        allowed = ins if timer else (*S5_COUNTERS[name], "S", "PV", "R")
        number = "T_NO" if timer else "C_NO"
        given: dict[str, str] = {}
        outs: list[tuple[ty.SclType, int, Place]] = []
        for arg in target.args.items:
            key = arg.name.upper()
            if key in given or (key not in (number, *allowed) and key not in _S5_OUTPUTS):
                raise Problem("E230", f"{name} has no parameter {arg.name or '(unnamed)'}", arg.loc)
            if key in _S5_OUTPUTS:
                if value:
                    raise Problem("E232", f"{name} with outputs is a statement", arg.loc)
                outs.append((_S5_OUTPUTS[key], 2 if key == "Q" else 1, self._actual_place(arg)))
                given[key] = ""
                continue
            given[key] = self._s5_input(key, arg, timer)
        if number not in given:
            raise Problem("E231", f"{name}: parameter {number} missing", target.loc)
        args = [given[number], *(given.get(k, "0" if k in ("TV", "PV") else "False") for k in ins)]
        if timer:
            call = f"_s5_timer(ctx, {S5_TIMERS[name]!r}, {', '.join(args)})"
        else:
            call = f"_s5_counter(ctx, {', '.join(args)})"
        rtype = ty.S5TIME if timer else ty.WORD
        if value:
            return X(rtype, f"{call}[0]")
        r = b.temp("r")
        b.emit(f"{r} = {call}")
        for t, k, place in outs:
            b.emit(place.store(self._take(X(t, f"{r}[{k}]"), place, target)))
        if result is not None:
            word = _s5time_word(result) if timer else None
            if word is not None:  # the time left as the timer's word: its time base kept
                b.emit(word.store(f"{r}[3]"))
            else:
                b.emit(result.store(self._take(X(rtype, f"{r}[0]"), result, target)))
        return X(rtype, f"{r}[0]")

    def _s5_input(self, key: str, arg: m.Arg, timer: bool) -> str:
        if key == "TV":
            return self._s5_word(arg)
        x = self.b.exprs.expr(arg.value)
        if key in ("T_NO", "C_NO"):
            cell = ty.TIMER if timer else ty.COUNTER
            if x.type.kind not in (cell.kind, "INT", "WORD", "ERROR"):
                raise Problem("E220", f"{key} is a {cell.kind} or an INT, not {x.type}", arg.loc)
            return x.src
        want = {"PV": ty.WORD}.get(key, ty.BOOL)
        return self.b.exprs.convert(x, want, arg.loc, "pass")

    def _s5_word(self, arg: m.Arg) -> str:
        """TV as the S5TIME word the timer is started with, time base and BCD count (S7-SCL
        manual, timers: TV is an S5TIME): a WORD's bits, an S5TIME in an operand area's or a
        global DB's bytes as they lie there, an S5TIME held as a value (a literal, a block's
        variable) in the finest time base that holds it."""
        x, place = self._operand(arg.value)
        if x.type.kind == "WORD":
            return x.src
        word = _s5time_word(place) if place is not None else None
        if word is not None:
            return word.get
        ms = self.b.exprs.convert(x, ty.S5TIME, arg.loc, "pass")
        if x.const is not None and ms.isdigit():
            return str(ms_to_s5time(int(ms)))  # a literal: encoded once, here
        return f"_s5w({ms})"

    def _operand(self, e: m.Expr) -> tuple[X, Place | None]:
        """``e`` compiled, with the place it reads when it names a variable or an operand
        (as ``Exprs.expr`` compiles a path)."""
        if not isinstance(e, m.Path):
            return self.b.exprs.expr(e), None
        got = self.b.places.resolve(e)
        if isinstance(got, Place):
            return X(got.type, got.get), got
        return (self.value(got) if isinstance(got, Target) else got), None


def _s5time_word(place: Place) -> Place | None:
    """An S5TIME in memory (``place.address``) as the WORD there, time base and BCD count
    as they lie; None for any other place."""
    if place.type.kind != "S5TIME" or not place.address:
        return None
    return in_memory(ty.WORD, place.address, place.what)


def _described(t: ty.SclType) -> str:
    """A STRUCT with its member names (``STRUCT a, b``), else the type's name."""
    if t.kind == "STRUCT":
        return f"{t.name or 'STRUCT'} ({', '.join(name for name, _ in t.fields)})"
    return str(t)
