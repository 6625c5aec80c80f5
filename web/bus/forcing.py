"""The CPU's force table on the bus: ``force`` commands in at the scan boundary, the list out.

:class:`Forcing` is the CPU-side adapter of ``Cpu.force``/``Cpu.unforce`` (``engine/force.py``).
It sees only commands the gate (``web.bus.gate``) let through — the role table makes
``force`` an engineer's op, and the gate writes the audit row, applied or refused — and
applies them in the scan thread between two scans; the next scan acts on them and writes
the diagnostic entry. ``{"address": "I0.3", "value": true}`` forces (``value`` may be a
number or an S7 literal text: ``-5``, ``16#00FF``, ``T#5S``; a symbol's value in its type),
``"value": null`` unforces that address, ``{"all": true}`` every job. Forcing does not wait
for RUN: a force job set in STOP acts from the first cycle in RUN, as on S7.
:meth:`Forcing.changed` gives the list whenever the table changed (the bus publishes it on
``forces`` and counts the jobs in ``status``). ``modify`` (``{"address": "M10.0",
"value": true}``, engineers too) writes a value once through ``Cpu.modify``
(``engine/modify.py``) — a DB variable by name (``DB20.avg``, ``"Data".temps[2]``)
through ``web.bus.modify_vars`` —: not held, no diagnostic entry, the audit row says what.
It never raises: a hostile command is refused with the reason.
"""

from __future__ import annotations

from s7graph.engine.cpu import Cpu
from s7graph.engine.errors import internal_error
from s7graph.engine.force import Force, ForceError
from s7graph.engine.modify import ModifyError
from s7graph.web.bus.modify_vars import modify_variable
from s7graph.web.bus.protocol import Command, ForceEntry, ForceList, Refusal
from s7graph.web.bus.watch import WatchError

__all__ = ["Forcing", "force_entry"]


def force_entry(force: Force) -> ForceEntry:
    """A force job as a bus message."""
    return ForceEntry(
        address=str(force.address),
        value=force.shown[:256],
        symbol=force.symbol[:256],
        user=force.user[:80],
    )


class Forcing:
    """The force table of ``cpu`` seen from the bus (use it in the scan thread only)."""

    def __init__(self, cpu: Cpu) -> None:
        self.cpu = cpu
        self._seen = -1  # the table version last listed

    def apply(self, command: Command) -> tuple[bool, str, str]:
        """Apply a ``force`` or ``modify`` command as ``command.user``: (applied, reason,
        detail)."""
        try:
            return self._apply(command)
        except ForceError as exc:
            return False, exc.message[:4096], ""
        except Exception as exc:  # a bad command must not stop the scan loop
            why = internal_error(f"in the CPU while applying {command.op}", exc)
            return False, f"{command.op} refused: {why}"[:4096], ""

    def _apply(self, command: Command) -> tuple[bool, str, str]:
        if command.op == "modify":
            return self._modify(command)
        if command.op != "force":
            return False, Refusal("not_found", f"not a force command: {command.op!r}"), ""
        args, user, cpu = command.args, command.user or "?", self.cpu
        if args.get("all") is True:
            gone = cpu.unforce(user=user)
            listed = ", ".join(str(f) for f in gone[:16]) or "none was active"
            return True, "", f"unforce all ({listed})"
        address, value = args.get("address"), args.get("value")
        if not isinstance(address, str):
            return False, Refusal("argument", "force needs an address"), ""
        if value is None:
            (force,) = cpu.unforce(address, user=user)
            return True, "", f"unforce {force}"
        force = cpu.force(address, value, user=user)
        return True, "", f"force {force}; {len(cpu.forces)} active"

    def _modify(self, command: Command) -> tuple[bool, str, str]:
        """``modify``: the value written once (``Cpu.modify``); the detail says what."""
        address, value = (
            getattr(command.args, "address", None),
            getattr(command.args, "value", None),
        )
        if not isinstance(address, str) or value is None:
            return False, Refusal("argument", "modify needs an address and a value"), ""
        try:
            done = modify_variable(self.cpu, address, value)
            if done is None:
                done = str(self.cpu.modify(address, value))
        except (ModifyError, WatchError) as exc:
            return False, exc.message[:4096], ""
        return True, "", f"modify {done}"

    def listing(self) -> ForceList:
        """The force jobs now."""
        return ForceList(entries=[force_entry(f) for f in self.cpu.forces])

    def changed(self) -> ForceList | None:
        """The force jobs if the table changed since the last call (first call: always)."""
        version = self.cpu.forces.version
        if version == self._seen:
            return None
        self._seen = version
        return self.listing()
