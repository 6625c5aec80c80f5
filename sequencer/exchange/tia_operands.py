"""The operands of a TIA Portal SimaticML GRAPH FB: LAD/FBD ``Access`` elements and action
tokens as the chart model's operands, and the global tags they name (the first half of
``exchange.simaticml``).

* ``"Tag".member`` is the symbol ``"Tag.member"``, ``#x`` the FB variable ``x``, ``%Q0.3``
  the address ``Q0.3``; a step's ``X T U`` and a transition's ``TT`` are attributes.
* A tag found in the symbol table given keeps its address there; one exported with an
  informative I/Q/M address keeps that one; the others get marker addresses within the
  CPU's M area (``markers``); none left is an error (I014).
* A DB member ``"T_S2".Q`` whose DB is a DB symbol — kept by s7graph's export in the block
  comment, or of the symbol table given — is that instance DB's variable read by name
  (``"T_S2".Q``), no tag.
* A DB as a whole (``Address`` area DB, type Block_DB: what a call passes to a Block_DB
  parameter) is ``DB5``; under a symbol, that DB symbol (``"Recipe"``, declared
  ``"Recipe" : DB5 : DB5`` unless kept or given already), no tag.
* A tag compared with a step's time is a TIME, as TIA compiles it (a DInt tag so declared
  is reported); an untyped integer compared with a time is milliseconds.
* A block constant (``LocalConstant``) is its value; a global constant (``GlobalConstant``:
  its value is in the PLC's constants table, not in a block export) an FB variable of
  that name, for the user to set (reported).
"""

from __future__ import annotations

from dataclasses import replace

from s7graph.engine.errors import LiteralError, S7Error, SourceLocation, SymbolError
from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.exchange.iec_expressions import const
from s7graph.sequencer.exchange.markers import Markers, used_bytes
from s7graph.sequencer.exchange.naming import safe_name
from s7graph.sequencer.exchange.problems import Problems
from s7graph.sequencer.exchange.xmltree import ElementError, Node
from s7graph.sequencer.text.model import (
    Const,
    Expr,
    Operand,
    StepAttr,
    SymbolDecl,
    TransAttr,
    VarDecl,
)

__all__ = ["TIA_TYPES", "TiaOperands", "component", "whole_db"]

# TIA data types → S7 types of the chart model.
TIA_TYPES = {
    "BOOL": "BOOL",
    "BYTE": "BYTE",
    "WORD": "WORD",
    "DWORD": "DWORD",
    "INT": "INT",
    "DINT": "DINT",
    "REAL": "REAL",
    "TIME": "TIME",
    "S5TIME": "S5TIME",
    "DATE": "DATE",
    "TIME_OF_DAY": "TIME_OF_DAY",
    "TOD": "TIME_OF_DAY",
    "CHAR": "CHAR",
    "STRING": "STRING",
    "DATE_AND_TIME": "DATE_AND_TIME",
    "DTL": "",
}
_AREAS = {"Input": "I", "Output": "Q", "Memory": "M"}
_WIDTH = {
    "BOOL": "",
    "BYTE": "B",
    "CHAR": "B",
    "WORD": "W",
    "INT": "W",
    "S5TIME": "W",
    "DWORD": "D",
    "DINT": "D",
    "REAL": "D",
    "TIME": "D",
}


class TiaOperands:
    """The operands, tags, variables and constants of one FB being read."""

    def __init__(self, fb: Node, problems: Problems, symbols: SymbolTable | None) -> None:
        self.fb = fb
        self.p = problems
        self.file = problems.file
        self.known = symbols
        self.symbols: dict[str, SymbolDecl] = {}
        self.types: dict[str, str] = {}  # symbol → type seen
        self.constants: dict[str, Const] = {}  # the block's own (Constant section)
        self.constant_vars: dict[str, str] = {}  # a constant without a value → FB variable
        self.vars: dict[str, VarDecl] = {}
        self.dbs: dict[str, SymbolDecl] = {}  # DB symbols kept in the block comment
        self.moved: set[str] = set()  # those the block's networks number otherwise
        self.step_names: dict[str, int] = {}
        self.trans_names: dict[str, int] = {}

    def at(self, node: Node) -> SourceLocation:
        return node.loc(self.file)

    def attr(self, name: str) -> str:
        node = self.fb.find("AttributeList", name)
        return node.text.strip() if node is not None else ""

    # ------------------------------------------------------------ operands

    def symbol(
        self, name: str, type_name: str | None, node: Node, informative: str = "", address: str = ""
    ) -> Operand:
        """A global tag: the symbol table's if it knows it, else declared in the chart (at
        the export's informative address, or at an allocated one)."""
        if self.known is not None and self.known.lookup(name) is not None:
            return Operand(name, True, self.at(node))
        if type_name:
            self.types.setdefault(name, type_name)
        old = self.symbols.get(name)
        if old is None or (address and not old.address):
            self.symbols[name] = SymbolDecl(
                name, address, type_name or "", informative, self.at(node)
            )
        elif type_name == "TIME" and old.type in ("", "DINT"):
            self.time_tag(old, node)
        return Operand(name, True, self.at(node))

    def time_tag(self, old: SymbolDecl, node: Node) -> None:
        """A tag compared with a time: TIME (TIA compiles a DInt or an untyped tag there as
        milliseconds; GRAPH compares only same-typed operands)."""
        self.symbols[old.name] = replace(old, type="TIME")
        self.types[old.name] = "TIME"
        if old.type == "DINT":
            self.p.warn(
                "I031",
                f'tag "{old.name}" is a DInt compared with a time: TIA compiles it as '
                "milliseconds; it is declared TIME here (the same 32 bits)",
                self.at(node),
            )

    def is_db(self, name: str) -> bool:
        """``name`` is a DB symbol: kept by the export, or of the symbol table given."""
        if name.casefold() in self.dbs:
            return True
        try:
            return self.known is not None and self.known.db_number(name) is not None
        except SymbolError:
            return False

    def member(self, parts: list[str], loc: SourceLocation) -> Operand | None:
        """``"T_S2".Q``: a variable of the DB a DB symbol names, read by name; None for
        any other path (a tag's)."""
        if len(parts) != 2 or "[" in parts[1] or not self.is_db(parts[0]):
            return None
        return Operand(parts[0], True, loc, member=parts[1])

    def access(self, node: Node, want: str | None) -> Expr:
        scope = node.get("Scope")
        loc = self.at(node)
        if scope in ("LiteralConstant", "TypedConstant"):
            value = node.find("Constant", "ConstantValue")
            text = value.text.strip() if value is not None else ""
            ctype = node.find("Constant", "ConstantType")
            if ctype is not None and ctype.text.strip().upper() == "BOOL":
                text = text.upper()
            elif ctype is None and want == "TIME" and text.isdigit():
                text = f"T#{text}MS"  # TIA reads an untyped integer compared with a time as ms
            try:
                return const(text, loc)
            except (LiteralError, S7Error):
                raise ElementError(f"constant {text!r} has no GRAPH form", node) from None
        if scope in ("GlobalConstant", "LocalConstant"):
            return self.named_constant(node, scope, want)
        sym = node.child("Symbol")
        if sym is None:
            address = node.child("Address")
            if address is not None and scope == "GlobalVariable":
                number = whole_db(address)
                if number is not None:  # %DB5 passed to a Block_DB parameter
                    return Operand(f"DB{number}", False, loc)
                return Operand(self.absolute(address, node), False, loc)
            raise ElementError(f"an operand of scope {scope} the importer does not read", node)
        parts = [component(c) for c in sym.all("Component")]
        addr = sym.child("Address")
        if scope == "GlobalVariable" and self.passed_db(parts, addr, node):
            return Operand(parts[0], True, loc)
        t = addr.get("Type").upper() if addr is not None else None
        if scope == "LocalVariable":
            if len(parts) == 2 and parts[0] in self.step_names and parts[1] in ("X", "T", "U"):
                return StepAttr(self.step_names[parts[0]], parts[1], loc)  # type: ignore[arg-type]
            if len(parts) == 2 and parts[0] in self.trans_names and parts[1] == "TT":
                return TransAttr(self.trans_names[parts[0]], "TT", loc)
            if len(parts) == 1:
                return Operand(parts[0], False, loc)
            raise ElementError(
                f"#{'.'.join(parts)} is not an FB variable, step or transition attribute", node
            )
        read = self.member(parts, loc)
        if read is not None:
            if addr is not None and addr.get("BlockNumber").isdigit():
                self.renumbered(parts[0], int(addr.get("BlockNumber")), node)
            return read
        informative, where = "", ""
        if addr is not None and addr.get("BlockNumber") and addr.get("BitOffset"):
            informative = f"TIA: DB{addr.get('BlockNumber')} bit offset {addr.get('BitOffset')}"
        elif addr is not None and addr.get("Area") in _AREAS:
            where = self.absolute(addr, node)
        name, tag_type = ".".join(parts), TIA_TYPES.get(t or "") or want
        op = self.symbol(name, tag_type, node, informative, where)
        if want == "TIME" and tag_type == "DINT":
            self.symbol(name, "TIME", node)  # compared with a time: TIA's milliseconds
        return op

    def passed_db(self, parts: list[str], addr: Node | None, node: Node) -> bool:
        """``"Recipe"`` a call passes to a Block_DB parameter: a DB symbol (kept in the
        block comment, of the symbol table given, or with the informative address of a DB
        as a whole, which declares it in the chart: ``"Recipe" : DB5 : DB5``), no tag."""
        number = whole_db(addr) if addr is not None else None
        if len(parts) != 1 or (number is None and not self.is_db(parts[0])):
            return False
        if number is not None and not self.is_db(parts[0]):
            label = f"DB{number}"
            decl = SymbolDecl(parts[0], label, label, "", self.at(node))
            self.dbs.setdefault(parts[0].casefold(), decl)
        elif number is not None:
            self.renumbered(parts[0], number, node)
        return True

    def renumbered(self, name: str, number: int, node: Node) -> None:
        """A DB symbol s7graph's block comment kept whose DB the block's own networks number
        otherwise (TIA's informative address, written when the block was exported again
        after an edit): the networks' number holds, reported (I024), as an edited PLCopen
        export is read from its SFC, not from s7graph's data."""
        kept = self.dbs.get(name.casefold())
        if kept is None or kept.address == f"DB{number}" or name.casefold() in self.moved:
            return
        self.moved.add(name.casefold())
        self.dbs[name.casefold()] = replace(kept, address=f"DB{number}")
        self.p.warn(
            "I024",
            f'"{name}" is DB{number} in the block\'s networks and {kept.address} in '
            f"s7graph's block comment, written before: the networks' DB{number} holds",
            self.at(node),
        )

    def named_constant(self, node: Node, scope: str, want: str | None) -> Expr:
        """A constant by name: the block's own (its interface's Constant section) is its
        value; a global one (the PLC's constants table, which a block export does not
        carry) becomes an FB variable of that name, of the type its use asks for, for the
        user to give the constant's value (reported)."""
        name = (node.find("Constant") or node).get("Name")
        if not name:
            raise ElementError(f"a {scope} without a name", node)
        if scope == "LocalConstant" and name in self.constants:
            return replace(self.constants[name], loc=self.at(node))
        graph = self.constant_vars.get(name)
        if graph is None:
            graph = safe_name(name, {v.upper() for v in self.vars})
            self.constant_vars[name] = graph
            graph_type = want or "BOOL"
            self.vars[graph] = VarDecl(graph, graph_type, None, self.at(node))
            where = "PLC's constants table" if scope == "GlobalConstant" else "block"
            self.p.warn(
                "I023",
                f"constant {name} is in the {where}, which a block export does not carry: "
                f"it is the FB variable {graph} : {graph_type} here — give it the "
                "constant's value as its start value",
                self.at(node),
            )
        return Operand(graph, False, self.at(node))

    def absolute(self, address: Node, at: Node) -> str:
        area = _AREAS.get(address.get("Area"))
        offset = address.get("BitOffset")
        t = TIA_TYPES.get(address.get("Type").upper(), "")
        if area is None or not offset.isdigit() or t not in _WIDTH:
            given = " ".join(f'{k}="{address.get(k)}"' for k in ("Area", "Type", "BitOffset"))
            raise ElementError(f"an absolute address the importer does not read ({given})", at)
        n = int(offset)
        width = _WIDTH[t]
        return f"{area}{n // 8}.{n % 8}" if width == "" else f"{area}{width}{n // 8}"

    def action_tag(self, node: Node) -> None:
        """A global tag an action row names by an ``Access``: declared at the I/Q/M
        address the export gives it (the row's text types it later)."""
        sym = node.child("Symbol")
        addr = sym.child("Address") if sym is not None else None
        if node.get("Scope") != "GlobalVariable" or sym is None or addr is None:
            return
        parts = [component(c) for c in sym.all("Component")]
        if self.passed_db(parts, addr, node):
            return
        if addr.get("Area") in _AREAS:
            name = ".".join(parts)
            t = TIA_TYPES.get(addr.get("Type").upper()) or None
            self.symbol(name, t, node, "", self.absolute(addr, node))

    def access_text(self, node: Node) -> str:
        scope = node.get("Scope")
        sym = node.child("Symbol")
        if sym is not None:
            parts = [component(c) for c in sym.all("Component")]
            if scope == "LocalVariable":
                return "#" + ".".join(parts)
            if self.member(parts, self.at(node)) is not None:
                return f'"{parts[0]}".{parts[1]}'
            return '"' + ".".join(parts) + '"'
        address = node.child("Address")
        number = whole_db(address) if address is not None else None
        if number is not None:  # %DB5 passed to a Block_DB parameter
            return f"DB{number}"
        value = node.find("Constant", "ConstantValue")
        return value.text.strip() if value is not None else ""

    def block_constants(self) -> None:
        """The block's own constants (``Section Name="Constant"``): their values."""
        for section in self.fb.iter("Section"):
            if section.get("Name") != "Constant" or section.parent is None:
                continue
            if section.parent.tag != "Sections" or section.parent.get("Datatype"):
                continue
            for m in section.all("Member"):
                start = m.child("StartValue")
                t = TIA_TYPES.get(m.get("Datatype").upper().strip('"'), "")
                if start is None or not start.text.strip() or not t:
                    continue
                text = start.text.strip()
                try:
                    self.constants[m.get("Name")] = const(
                        text.upper() if t == "BOOL" else text, self.at(start)
                    )
                except (LiteralError, S7Error):
                    continue

    def finish_symbols(self, used: set[int]) -> tuple[SymbolDecl, ...]:
        """The chart's symbols: a tag without an address gets a marker address in the
        CPU's M area (``markers``), away from the bytes ``used``; none left is an error."""
        for s in self.symbols.values():
            used.update(used_bytes(s.address))
        alloc = Markers(used)
        out: list[SymbolDecl] = []
        allocated: list[str] = []
        for name, s in self.symbols.items():
            t = s.type or self.types.get(name, "BOOL")
            if s.address:
                out.append(SymbolDecl(name, s.address, t, "", s.loc))
                continue
            address = alloc.take(_WIDTH.get(t, "W"))
            if address is None:
                self.p.error(
                    "I014",
                    f'no room for tag "{name}" : {t} in the CPU\'s marker area '
                    f"({alloc.size} bytes): give the tag table with --symbols",
                    s.loc,
                )
                continue
            allocated.append(address)
            comment = s.comment or "TIA tag"
            out.append(SymbolDecl(name, address, t, f"{comment}; address allocated", s.loc))
        if allocated:
            self.p.warn(
                "I032",
                f"{len(allocated)} global tag(s) have no address in a block export; "
                f"they are declared at allocated marker addresses ({allocated[0]} …, within "
                f"the CPU's {alloc.size} bytes of M): give the tag table with --symbols",
                self.at(self.fb),
            )
        return tuple(out)


def whole_db(address: Node) -> int | None:
    """The number of the DB an ``Address`` names as a whole — area DB, type Block_DB, its
    number, no bit offset, as TIA writes ``%DB5`` passed to a Block_DB parameter (TIA
    Portal Openness system manual, "Major changes", the ``Address`` node of
    ``SW.PlcBlocks.Access.xsd``) — None for any other address."""
    number = address.get("BlockNumber")
    if address.get("Area") != "DB" or address.get("Type").upper() != "BLOCK_DB":
        return None
    return int(number) if number.isdigit() and not address.get("BitOffset") else None


def component(c: Node) -> str:
    """A tag path component; an array index (``AccessModifier="Array"``) as ``[i]``, a
    named constant index by its name (``OP[C_OP10]``)."""
    index: list[str] = []
    for a in c.all("Access"):
        value = a.find("Constant", "ConstantValue")
        named = a.find("Constant")
        if value is not None:
            index.append(value.text.strip())
        elif named is not None and named.get("Name"):
            index.append(named.get("Name"))
    text = ",".join(index)
    return f"{c.get('Name')}[{text}]" if text else c.get("Name")
