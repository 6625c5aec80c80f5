"""Changed S7-SCL sources downloaded into a running CPU at a scan boundary, their DBs' values
kept by name (docs/scl.md, "On the command line"; docs/online-change.md).

``reload_sources(cpu, graphs, old, new)`` is the blocks' part of an online change: the new
sources' FBs, FCs and OBs replace those of the same label (blocks the new sources no longer
write stay loaded, as a download leaves the blocks it does not bring); every instance DB of
a changed FB is made again from the new FB with its values carried over by name where the
type is the same (``steps.scl.state.SclState.adapt``), the others at their initial values;
a global DB whose declared structure is the same keeps its bytes, one whose structure
changed comes back with its new initial values; the charts' OB1, OB100 and OB102 are chained
to the new sources' again. It returns one note per change of a DB, as a state file's
carry-over does; ``BlockError`` (nothing changed then is not promised: call it between two
scans, the CPU's program as the sources left it) when the new sources cannot be loaded.
``carry_notes(cpu, old, new)`` makes those notes without changing anything: a preview's.

``refusals(cpu, new)`` says what an online change of the bus refuses before it reloads
(docs/online-change.md, "S7-SCL blocks"): an instance DB of a changed FB where a variable
changes type in a way its value does not survive (``steps.scl.state.carried``), or one the
new sources make the instance of another FB. Where nothing is refused, a changed FB's
instances keep every variable by name, converted where the type widens losslessly
(``CarryPlan``); the notes say which variables went and which came new.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from s7graph.engine.blocks import FB, InstanceDB
from s7graph.sequencer.fb import GraphFB
from s7graph.steps.scl.state import CarryPlan, SclState
from s7graph.web.harness.scl import SclSources, chain_obs

__all__ = ["carry_notes", "refusals", "reload_sources"]


def reload_sources(
    cpu: Any, graphs: Sequence[GraphFB], old: SclSources | None, new: SclSources
) -> list[str]:
    """Download ``new`` in place of ``old`` into the running ``cpu`` (see the module
    docstring); the notes of what the DBs did not keep (:func:`carry_notes`)."""
    fbs = _fbs(new)
    notes = carry_notes(cpu, old, new)  # the instances as they are before the load
    saved = {
        number: (idb.fb, idb.snapshot())
        for number, idb in cpu.instance_dbs.items()
        if idb.fb.label in fbs and idb.fb is not fbs[idb.fb.label]
    }
    kept_dbs = _same_global_dbs(cpu, old, new)
    new.load(cpu)
    for number in saved:
        idb = cpu.instance_dbs[number]
        if idb.fb is not fbs[idb.fb.label]:
            cpu.replace_instance_db(number, fbs[idb.fb.label], name=idb.name)
    for number, (before, data) in sorted(saved.items()):
        _carry(cpu.instance_dbs[number], before, data)
    for number, data in kept_dbs.items():
        cpu.mem.dbs[number].data[:] = data
    if graphs:
        chain_obs(cpu, graphs, new.blocks)
    return notes


def carry_notes(cpu: Any, old: SclSources | None, new: SclSources) -> list[str]:
    """What a download of ``new`` in place of ``old`` does to the DBs of the running
    ``cpu``, one note per change — said by its preview before and by :func:`reload_sources`
    when it is made: which variables of each instance DB of a changed FB are kept by name,
    dropped or new at their initial values, and each global DB whose structure changed.
    Nothing: every value stays. Reads the CPU, changes nothing."""
    fbs = _fbs(new)
    notes: list[str] = []
    for _, idb in sorted(cpu.instance_dbs.items()):
        fb = fbs.get(idb.fb.label)
        if fb is not None and fb is not idb.fb:
            notes += _instance_notes(idb, fb)
    before = _global_types(old)
    for label, t in sorted(_global_types(new).items()):
        if label in before and before[label] != t:
            notes.append(f"{label}: its structure changed; at its new initial values")
    return notes


def refusals(cpu: Any, new: SclSources) -> list[str]:
    """Why ``new`` cannot replace the running sources of ``cpu`` with every instance's
    values carried: one line per instance DB (nothing: it can)."""
    fbs = _fbs(new)
    out: list[str] = []
    for number, label in sorted(new.instances.items()):
        have = cpu.instance_dbs.get(number)
        if have is not None and have.fb.label != label:
            out.append(
                f"DB{number} is the instance DB of {have.fb.label} in the CPU; the new "
                f"sources make it one of {label}"
            )
    for number, idb in sorted(cpu.instance_dbs.items()):
        fb = fbs.get(idb.fb.label)
        if fb is None or fb is idb.fb:
            continue
        old_fmt, fmt = idb.fb.state_format, fb.state_format
        if isinstance(old_fmt, SclState) and isinstance(fmt, SclState):
            refused = CarryPlan.between(old_fmt, fmt).refused
            if refused:
                out.append(
                    f"DB{number} ({fb.label}): {'; '.join(refused)}: the value cannot be "
                    "carried over (rename the variable to start it afresh)"
                )
    return out


def _global_types(sources: SclSources | None) -> dict[str, Any]:
    if sources is None:
        return {}
    return {k: v for k, v in sources.types.items() if k.startswith("DB")}


def _same_global_dbs(cpu: Any, old: SclSources | None, new: SclSources) -> dict[int, bytes]:
    """The bytes of each global DB whose declared structure the new sources keep."""
    out: dict[int, bytes] = {}
    before = _global_types(old)
    for label, t in _global_types(new).items():
        number = int(label[2:])
        if before.get(label) == t and number in cpu.mem.dbs:
            out[number] = bytes(cpu.mem.dbs[number].data)
    return out


def _fbs(sources: SclSources) -> dict[str, FB]:
    return {b.label: b for b in sources.blocks if isinstance(b, FB)}


def _plan(before: FB, fb: FB) -> CarryPlan | None:
    """The carry by name from an instance of ``before`` to one of ``fb`` when both are S7-SCL
    FBs and it refuses nothing (None: the state format's own ``adapt``)."""
    old_fmt, fmt = before.state_format, fb.state_format
    if isinstance(old_fmt, SclState) and isinstance(fmt, SclState):
        plan = CarryPlan.between(old_fmt, fmt)
        return None if plan.refused else plan
    return None


def _same_format(before: FB, fb: FB) -> bool:
    """The instance data of ``before`` fits ``fb`` whole (or neither says how it is made)."""
    old_fmt, fmt = before.state_format, fb.state_format
    return fmt is None or old_fmt is None or old_fmt.fingerprint == fmt.fingerprint


def _instance_notes(idb: InstanceDB, fb: FB) -> list[str]:
    """What instance ``idb`` keeps of its values when its FB becomes ``fb``."""
    before = idb.fb
    if _same_format(before, fb):
        return []
    plan = _plan(before, fb)
    if plan is not None:
        names = {v.name for v in before.stored}
        kept = [n for n in plan.kept if n in names]  # those a snapshot holds
        notes = [f"interface changed; variables kept by name ({len(kept)})", *plan.notes()]
    else:
        assert fb.state_format is not None and before.state_format is not None
        notes = fb.state_format.adapt(before.state_format.shape(), idb.snapshot())[1]
    return [f"DB{idb.number} {fb.label} {fb.name!r}: {note}" for note in notes]


def _carry(idb: InstanceDB, before: FB, data: dict[str, object]) -> None:
    """``data`` (a snapshot under FB ``before``) into ``idb`` of the new FB: whole when the
    FB's state format is the same, else by name and type (:func:`_instance_notes` says
    what)."""
    fb = idb.fb
    if _same_format(before, fb):
        idb.restore(data)
        return
    plan = _plan(before, fb)
    if plan is not None:
        idb.restore(plan.apply(data))
        return
    assert fb.state_format is not None and before.state_format is not None
    idb.restore(fb.state_format.adapt(before.state_format.shape(), data)[0])
