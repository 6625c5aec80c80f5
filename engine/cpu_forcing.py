"""Force jobs of the CPU (``force``/``unforce``) and the texts of their diagnostic entries;
a modify (``modify``: a value written once).

``Forcing`` is a part of ``engine.cpu.Cpu``, which owns the attributes it declares; the
table itself and how a job is applied live in ``engine/force.py``, a modify in
``engine/modify.py``.
"""

from __future__ import annotations

from s7graph.engine.address import Address
from s7graph.engine.diagnostics import EventId
from s7graph.engine.force import Force, ForceTable, force_target, make_force
from s7graph.engine.memory import Memory
from s7graph.engine.modify import Modify, make_modify, write_modify

__all__ = ["Forcing", "jobs_text", "listed"]


class Forcing:
    """Adding and deleting force jobs; their diagnostic entries wait for the next scan."""

    mem: Memory
    forces: ForceTable
    _force_notes: list[tuple[int, str, str]]

    def force(self, target: str | Address, value: object, *, user: str = "") -> Force:
        """Force ``target`` — an I, Q or M address or a symbol — to ``value`` from the next
        cycle on, until ``unforce`` (``engine/force.py``); call at a scan boundary. Replaces
        the job of the same address; ``ForceError`` names what is wrong."""
        force = make_force(self.mem, target, value, user=user)
        old = self.forces.add(force)
        was = f" (was {old.shown})" if old is not None else ""
        by = f" by {user}" if user else ""
        text = f"force {force}{was}{by}; {jobs_text(len(self.forces))} active"
        self._force_notes.append((EventId.FORCE_STARTED, str(force.address), text))
        return force

    def modify(
        self,
        target: str | Address,
        value: object,
        *,
        type_name: str | None = None,
        variable: str = "",
    ) -> Modify:
        """Write ``value`` once into ``target`` — an I, Q, M or DB address or a symbol —
        where ``engine.modify.MODIFY_POINTS`` says; call at a scan boundary. Not held: the
        program and the modules may write it again. An address may come with its type and
        the DB variable it is (``make_modify``). ``ModifyError`` names what is wrong (a
        forced operand included); nothing is written then."""
        modify = make_modify(self.mem, target, value, type_name=type_name, variable=variable)
        write_modify(self.mem, self.forces, modify)
        return modify

    def unforce(self, target: str | Address | None = None, *, user: str = "") -> list[Force]:
        """Delete the force job of ``target`` (an address or symbol; None: every job) from
        the next cycle on; the program and the modules decide again. Returns the jobs
        deleted; ``ForceError`` when ``target`` is not forced."""
        by = f" by {user}" if user else ""
        if target is None:
            gone = self.forces.clear()
            if gone:
                text = f"unforce all{by}: {jobs_text(len(gone))} deleted ({listed(gone)})"
                self._force_notes.append((EventId.FORCE_ENDED, "", text))
            return gone
        force = self.forces.remove(force_target(self.mem, target)[0])
        left = jobs_text(len(self.forces)) if self.forces else "no force job"
        text = f"unforce {force.address} (was {force.shown}){by}; {left} active"
        self._force_notes.append((EventId.FORCE_ENDED, str(force.address), text))
        return [force]


def jobs_text(n: int) -> str:
    """``n force job(s)``."""
    return f"{n} force job{'s' if n != 1 else ''}"


def listed(forces: list[Force], limit: int = 8) -> str:
    """The addresses of ``forces``, the first ``limit`` of them."""
    shown = ", ".join(str(f.address) for f in forces[:limit])
    return shown + (f" and {len(forces) - limit} more" if len(forces) > limit else "")
