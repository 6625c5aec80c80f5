"""The key space of the zenoh bus between a CPU and its views (docs/bus.md, "Keys").

The CPU serves and publishes these keys (:class:`~web.bus.publisher.BusPublisher`), a view
or a command line reads and commands through them (:class:`~web.bus.client.BusClient`); a
session meets the bus as :mod:`web.bus.session` configures it.

Key space, all under ``s7graph/<cpu>/``:

- ``status`` — :class:`CpuStatus`, published on change and at most once a second
  (also a queryable, for late joiners);
- ``fb/<name>/chart`` — queryable: the :class:`ChartLayout`;
- ``fb/<name>/state`` — queryable: the latest :class:`StepStateUpdate` with its ``seq``;
- ``fb/<name>/delta`` — the :class:`StepStateUpdate` of every scan that changed the FB,
  put here besides ``deltas`` only while something subscribes to this key (a zenoh
  matching listener says so); ``seq`` counts the FB's changes, so a late joiner does
  ``get(state)`` and applies newer deltas only, and a gap in ``seq`` means a missed delta.
  The scan thread only decides and queues; the publisher's
  :class:`~web.bus.outbox.Outbox` thread encodes and puts (deltas, status, alarms), so a
  congested bus never holds up a scan;
- ``deltas`` — one :class:`ScanDeltas` per scan in which an FB changed: every changed FB's
  :class:`StepStateUpdate` (with the ``seq`` of ``fb/<name>/delta``), encoded in one go;
  its own ``seq`` counts these messages, so a gap means one was lost (``BusClient.follow``
  reads this key and gets ``state`` again);
- ``alarms`` — the :class:`AlarmList` (the CPU's message list), published on change;
  ``alarms/list`` — queryable: the current one (``seq`` orders the two);
- ``alarms/history`` — queryable: the last 200 message events (:class:`AlarmHistory`);
- ``forces`` — the :class:`ForceList` (the CPU's force jobs), published on change and a
  queryable; ``status`` counts them (the FRCE LED);
- ``operands`` — :class:`OperandValues`: the symbol table's operands and each FB's
  variables and pins, read at a scan boundary, published on change at most 10 times a
  second (``web.bus.operands``; also a queryable); ``operands/list`` — queryable: their
  :class:`OperandCatalog` (names, types, addresses);
- ``cmd`` — queryable: a :class:`Command` in, one :class:`CommandReply` out. Valid commands
  go on a thread-safe queue; the scan loop drains it at a scan boundary, where the
  :class:`~web.bus.gate.Gate` checks who sent each and whether their role allows it,
  applies and audits it. The reply leaves once the command's effect and its audit row
  are durable (``apply_commands(..., durable=runner)``: from the writer thread's callback
  when the next scan's state is committed; never does the scan thread wait), or, if the
  state file has not confirmed it ``REPLY_WITHIN_S`` after the command came, as not
  confirmed. Unreadable ones are refused (and audited) at once with the reason;
- ``login`` — queryable: a :class:`LoginRequest` in, a :class:`LoginReply` (a token) out;
- ``audit`` — each :class:`AuditEntry` as it is written; ``audit/list`` — queryable: the
  last 50 (:class:`AuditList`); ``audit/acked`` — queryable: of each message, its newest
  applied ``ack_msg`` row with a comment, however old (:class:`AuditList`);
- ``diag`` — queryable: the CPU's diagnostic buffer, newest first (:class:`DiagBuffer`; the
  newest 100, or ``?n=N``); ``diag/new`` — the entries written since the last publication,
  published at the scan boundary after they were written;
- ``watch`` — queryable: a :class:`WatchRequest` in, the :class:`WatchValues` read at the
  next scan boundary out (only a query for its exact key);
- ``blocks`` — queryable: the S7-SCL blocks the CPU runs, as source
  (:class:`BlockSources`, ``web.bus.block_sources``);
- ``alive`` — a liveliness token while the CPU's bus is up (a view greys its chart when it
  goes).

A wildcard query (``s7graph/**``) gets the read-only answers, each under its own key;
``cmd``, ``login`` and ``watch`` answer only a query for their exact key. Sessions talk
only to the given endpoints (``web.bus.session``), and only the CPU's own identity may
serve or publish its keys (``web.bus.acl``). docs/bus.md shows every message.
"""

from __future__ import annotations

from dataclasses import dataclass

from s7graph.web.bus.protocol import valid_name

__all__ = ["ROOT", "keys"]

ROOT = "s7graph"


@dataclass(frozen=True, slots=True)
class keys:
    """Key expressions of one CPU."""

    cpu: str

    def __post_init__(self) -> None:
        if not valid_name(self.cpu):
            raise ValueError(f"invalid CPU name {self.cpu!r} for a key expression")

    @property
    def status(self) -> str:
        return f"{ROOT}/{self.cpu}/status"

    @property
    def deltas(self) -> str:
        return f"{ROOT}/{self.cpu}/deltas"

    @property
    def alarms(self) -> str:
        return f"{ROOT}/{self.cpu}/alarms"

    @property
    def alarm_list(self) -> str:
        return f"{ROOT}/{self.cpu}/alarms/list"

    @property
    def alarm_history(self) -> str:
        return f"{ROOT}/{self.cpu}/alarms/history"

    @property
    def forces(self) -> str:
        return f"{ROOT}/{self.cpu}/forces"

    @property
    def operands(self) -> str:
        return f"{ROOT}/{self.cpu}/operands"

    @property
    def operand_list(self) -> str:
        return f"{ROOT}/{self.cpu}/operands/list"

    @property
    def cmd(self) -> str:
        return f"{ROOT}/{self.cpu}/cmd"

    @property
    def login(self) -> str:
        return f"{ROOT}/{self.cpu}/login"

    @property
    def audit(self) -> str:
        return f"{ROOT}/{self.cpu}/audit"

    @property
    def audit_list(self) -> str:
        return f"{ROOT}/{self.cpu}/audit/list"

    @property
    def audit_acked(self) -> str:
        return f"{ROOT}/{self.cpu}/audit/acked"

    @property
    def diag(self) -> str:
        return f"{ROOT}/{self.cpu}/diag"

    @property
    def diag_new(self) -> str:
        return f"{ROOT}/{self.cpu}/diag/new"

    @property
    def watch(self) -> str:
        return f"{ROOT}/{self.cpu}/watch"

    @property
    def blocks(self) -> str:
        return f"{ROOT}/{self.cpu}/blocks"

    @property
    def alive(self) -> str:
        return f"{ROOT}/{self.cpu}/alive"

    def fb(self, name: str, leaf: str) -> str:
        if not valid_name(name):
            raise ValueError(f"invalid FB name {name!r} for a key expression")
        return f"{ROOT}/{self.cpu}/fb/{name}/{leaf}"
