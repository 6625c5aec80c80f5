"""Modifying a DB variable by name — ``DB20.avg``, ``DB10.ctu.PV``, ``"Data".temps[2]`` —
as TIA Portal's watch table modifies ``"Data".temps[2]``: the names the watch table reads
(``web.bus.watch``), written once at the scan boundary (docs/runtime.md, "Modify").

- In a global DB with a layout (declared in S7-SCL): the variable's address and declared
  type go to ``Cpu.modify`` — its bytes, the rules of a value of its type, a forced
  operand refused — and the audit shows both (``DB20.avg (DB20.DBD4) = 2.5``).
- In an instance DB: the FB's variable — a chart's own variable in its GraphFB's instance
  DB too (``"Seq_mix".count``), into multi-instances, an ARRAY's element by its declared
  bounds — is set to the value of its declared type, by the same rules
  (``engine.modify.typed_value``). A field of a STRUCT inside an instance, whose type the
  CPU does not keep, is refused with the reason, and so is a type wider than a double
  word.

Nothing is written when the name does not resolve or the value does not fit.
"""

from __future__ import annotations

from typing import Any

from s7graph.engine.blocks import InstanceDB
from s7graph.engine.cpu import Cpu
from s7graph.engine.modify import ModifyError, typed_value
from s7graph.web.bus.watch import (
    Segment,
    array_bounds,
    db_by_name,
    element_slot,
    element_type,
    instance_slot,
    layout_address,
    parse_item,
)

__all__ = ["modify_variable"]


def modify_variable(cpu: Cpu, text: str, value: object) -> str | None:
    """Write ``value`` once into the DB variable ``text`` (call at a scan boundary): what
    was written, as the audit shows it; None when ``text`` is no DB variable's name (an
    address or a symbol, ``Cpu.modify``'s). ``ModifyError`` or ``WatchError`` names what
    is wrong; nothing is written then."""
    item = parse_item(text)
    if item.error or (item.db is None and not item.db_name):
        return None
    if item.type:
        raise ModifyError(f"{text}: a modify writes the variable in its own type (no ':TYPE')")
    number = item.db if item.db is not None else db_by_name(cpu, item.db_name)
    idb = cpu.instance_dbs.get(number)
    if idb is not None:
        holder, key, type_name = _instance_slot(idb, item.path, f"DB{number}")
        typed, shown = typed_value(type_name, item.target, value)
        holder[key] = typed
        return f"{item.target} = {shown}"
    db = cpu.mem.dbs.get(number)
    if db is None:
        raise ModifyError(f"{item.target}: DB{number} is not loaded")
    address, type_name = layout_address(db, item.path, "modify")
    return str(cpu.modify(address, value, type_name=type_name, variable=item.target))


def _instance_slot(idb: InstanceDB, path: tuple[Segment, ...], where: str) -> tuple[Any, Any, str]:
    """(the list or dict holding the variable ``path`` of ``idb``, its key there, its
    declared type): into multi-instances and ARRAYs by their declared bounds."""
    holder: Any = None
    key: Any = None
    value: Any = idb
    type_name = ""
    for step in path:
        if isinstance(value, InstanceDB):
            if not isinstance(step, str):
                raise ModifyError(f"{where} is an instance DB: it takes no index")
            holder, key, type_name = instance_slot(value, step, where)
            where = f"{where}.{key}"
        elif isinstance(step, str):
            raise ModifyError(
                f"{where}.{step}: the CPU keeps no type for a field of {where}; "
                "modify it by its address"
            )
        else:
            holder, key = _element(value, step, array_bounds(type_name), where)
            where = f"{where}[{','.join(map(str, step))}]"
            type_name = element_type(type_name)
        value = holder[key]
    if isinstance(value, InstanceDB):
        raise ModifyError(f"{where} is a multi-instance: modify one of its variables")
    if not type_name or type_name.upper().startswith(("ARRAY", "STRUCT")):
        raise ModifyError(f"{where} is {type_name or 'no elementary variable'}: modify one element")
    return holder, key, type_name


def _element(
    value: object, index: tuple[int, ...], bounds: list[tuple[int, int]] | None, where: str
) -> tuple[list[Any], int]:
    """(the list holding ``value[index]``, its position there), by the declared bounds,
    every dimension indexed (``web.bus.watch.element_slot``)."""
    if not isinstance(value, list) or bounds is None or len(index) != len(bounds):
        spelled = ",".join(map(str, index))
        raise ModifyError(f"{where} is no ARRAY of that shape: it takes no index [{spelled}]")
    holder, position = element_slot(value, index, bounds, where)
    if not isinstance(holder, list):
        raise ModifyError(f"{where} cannot be written element by element")
    return holder, position
