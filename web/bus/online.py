"""The CPU's side of editing in the browser: the running chart's versions, its source and
project files on the bus, and the engineering commands — ``download``, ``undo_download``,
``save``, ``open`` — that never hold a scan up.

The bus routes these commands here (``BusPublisher.route``) instead of the scan boundary's
queue. One worker thread takes them in order: the gate establishes who sent each and
whether their role allows it (refusals audited like every command), the chart is parsed,
checked against the editor's limits and compiled with the CPU's symbol table, and the
change summary made — all in the compiler's process (``web.bus.compiler``: a size limit
before parsing, a time limit), never in the CPU's; its diagnostics name the file the sender
names (``file``; else "the edited chart"). What the swap would refuse in this CPU (an
operand beyond its memory, a call of a block it lacks: ``chart_refusal``) is refused here
already, with the swap's reason. ``preview`` answers with that summary and stops there. A
real download first writes the chart file (the old one kept as a numbered backup, the new
one flushed to the disk: ``web.harness.project``), then hands the compiled chart to the scan
thread, which swaps it in between two scans (:meth:`OnlineChange.at_boundary`,
``sequencer.online.swap``: the state carried over by step number); only then does the
reply say *applied* — the CPU runs the new chart and a restart would too. A swap refused at
the boundary (active steps removed without a choice, the CPU not scanning) puts the old file
back. Every outcome is one audit row with the user, the chart version and the change
summary. The chart before each download is kept: ``undo_download`` swaps it back the same
way. The CPU keeps running the old chart through any refusal; nothing a sender writes
reaches the scan but a compiled chart.

A download may bring changed S7-SCL sources of the blocks the chart calls (``blocks``):
compiled with the chart in the compiler's process, written beside it, swapped in with it at
the same boundary (``web.bus.online_blocks``), kept with its version for ``undo_download``.
With the chart unchanged (its summary empty) only the blocks change: the chart that runs,
its state and its file stay, and the reply says so as the preview does. The chart reads
the FBs' variables by name (``"Motor_DB".Running``) in those sources, or, when a download
brings none, in the blocks the CPU holds (``online_blocks.HeldInterfaces``, kept until the
blocks change): a variable the FB lacks refuses it (E048), and so does a call of those
blocks that does not fit them (E047, ``sequencer.calls.unfit_calls``), its preview alike.
Its preview (and an undo's) says what the instance DBs would keep, drop and start afresh
— the notes the download's reply gives, made by the same function
(``web.harness.scl_reload.carry_notes``) — or the reason it would be refused.

Reads (``fb/<fb>/source``: :class:`ChartSource`; ``project``: :class:`ProjectFiles`) are
queryables like the chart and the state. The source carries the S7-SCL sources the CPU
runs and, when those do not give every block it holds (a Python program's, sources too
large to come along), the held interfaces (``ChartSource.interfaces``), which an editor
checks the chart's calls against as the download does.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import threading
from collections.abc import Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path, PurePath
from typing import Any, Final, Protocol

import msgspec

from s7graph.engine.errors import BlockError, internal_error
from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.change.online import Needs, SwapRefused, SwapReport, swap
from s7graph.sequencer.checks.interfaces import ProgramBlocks
from s7graph.sequencer.compiled import CompiledChart
from s7graph.sequencer.text.format import format_chart
from s7graph.web.access.audit import Facts
from s7graph.web.bus.block_sources import MAX_TEXT_BYTES, source_files
from s7graph.web.bus.compiler import Compiled, Compiler, CompileRefused, Opened, Summary
from s7graph.web.bus.gate import Gate, with_note
from s7graph.web.bus.live import LiveChart, LiveGraph
from s7graph.web.bus.online_blocks import (
    BlockFiles,
    BlocksRefused,
    HeldInterfaces,
    chart_refusal,
    swap_blocks,
)
from s7graph.web.bus.protocol import (
    MAX_MESSAGE_BYTES,
    BlockInterfaces,
    ChartSource,
    Command,
    CommandReply,
    ProjectFile,
    ProjectFiles,
    Refusal,
    encode,
    refusal_reply,
)
from s7graph.web.bus.publisher import BusPublisher, PendingCommand
from s7graph.web.commands import COMMAND_TYPES, op_of
from s7graph.web.harness.project import (
    MAX_READ,
    ProjectError,
    chart_file,
    project_file,
    project_files,
    restore_backup,
    write_chart,
)
from s7graph.web.harness.scl import SclSources
from s7graph.web.harness.scl_reload import carry_notes, refusals
from s7graph.web.harness.session import ChartSession

__all__ = ["ENGINEERING_OPS", "MAX_WAITING", "Durability", "OnlineChange", "Version"]

# the ops the online change carries out (web.commands: ``where`` is ``online``)
ENGINEERING_OPS: Final = tuple(op_of(c) for c in COMMAND_TYPES if c.where == "online")
MAX_WAITING: Final = 4  # engineering commands queued at once; more are refused (busy)
BOUNDARY_TIMEOUT_S: Final = 5.0  # the scan loop takes a swap within this, or it is refused
MAX_LINES: Final = 400  # lines of a reply (a change summary, diagnostics)
MAX_HISTORY: Final = 20  # charts kept for undo_download (the oldest go first)
EDITED: Final = "the edited chart"  # a download's chart in its diagnostics, unless it names it
UNCHANGED: Final = "the chart does not change"  # a download of S7-SCL blocks alone
SAME: Final = "no change: the CPU runs this chart"


@dataclass(frozen=True, slots=True)
class Version:
    """One chart the FB ran: its number (1 at start, one more per download), the compiled
    chart, its symbol table and its source text."""

    number: int
    cc: CompiledChart
    table: SymbolTable
    text: str
    live: LiveChart | None = None  # the view's description, when the compiler made it
    scl: SclSources | None = None  # the S7-SCL blocks beside it (None: none)
    scl_texts: Mapping[str, str] = field(default_factory=dict)  # their sources by file name


@dataclass(eq=False)
class _Swap:
    """A compiled chart waiting for the scan boundary, and what became of it."""

    target: Version
    live: LiveChart
    removed: str | None
    user: str
    blocks: SclSources | None = None  # S7-SCL blocks swapped in with the chart
    chart: bool = True  # the chart changes (False: the blocks alone; the chart stays)
    done: threading.Event = field(default_factory=threading.Event)
    ok: bool = False  # made (``report``: the chart's swap, when it changed)
    report: SwapReport | None = None
    notes: list[str] = field(default_factory=list)  # what the blocks' DBs did not keep
    refusal: str = ""
    cancelled: bool = False
    mark: int | None = None  # the scan whose commit makes the swap durable


class Durability(Protocol):
    """When the state of a scan is on disk (``engine.runner.Runner``)."""

    def durable_mark(self) -> int: ...

    def wait_durable(self, mark: int, timeout: float | None = None) -> bool: ...

    def write_problem(self) -> str | None: ...


_NO_UNDO = "no download to undo (the charts of the last 20 downloads are kept)"


class _Refused(Exception):
    """An engineering command refused: its reason (a :class:`Refusal` when the kind is
    said) and lines."""

    def __init__(self, reason: str, lines: list[str] | tuple[str, ...] = ()) -> None:
        super().__init__(reason)
        self.reason = reason
        self.lines = list(lines)[:MAX_LINES]


class OnlineChange:
    """Online change of the GraphFB of ``session`` (viewed by ``live``), its commands
    checked and audited by ``gate``; ``path`` is the chart file (None: no file: a download
    writes nothing, there is no project directory), ``symbols`` the text of the symbol
    table file the chart was compiled with; ``compiler``: the process that compiles (by
    default one of its own, started by :meth:`attach`); ``blocks``: the S7-SCL source
    files the chart's calls reach (``--blocks``), which a download may bring changed
    (``web.bus.online_blocks``). :meth:`attach` puts it on a bus publisher; call
    :meth:`at_boundary` between two scans (the scan thread)."""

    def __init__(
        self,
        session: ChartSession,
        live: LiveGraph,
        gate: Gate,
        *,
        path: Path | None,
        symbols: str = "",
        boundary_timeout_s: float = BOUNDARY_TIMEOUT_S,
        compiler: Compiler | None = None,
        blocks: Sequence[Path] = (),
    ) -> None:
        self.session = session
        self.live = live
        self.gate = gate
        self.path = Path(path) if path is not None else None
        self.directory = self.path.parent if self.path is not None else None
        self.symbols_text = symbols
        self._timeout = boundary_timeout_s
        text = format_chart(session.cc.chart)
        if self.path is not None:
            with contextlib.suppress(OSError, UnicodeDecodeError):
                text = self.path.read_text(encoding="utf-8")
        self.block_files = BlockFiles(blocks)
        self.held_interfaces = HeldInterfaces(session)
        scl = next((b for b in session.blocks if isinstance(b, SclSources)), None)
        texts = dict(self.block_files.texts)
        self.current = Version(1, session.cc, session.symbols, text, None, scl, texts)
        self.history: list[Version] = []  # the charts before each download, oldest first
        self.publisher: BusPublisher | None = None
        self.durability: Durability | None = None  # the runner: when a scan is on disk
        self._worker = ThreadPoolExecutor(max_workers=1, thread_name_prefix="s7graph-online")
        self._waiting = 0
        self._lock = threading.Lock()  # _waiting, _swap
        self._swap: _Swap | None = None
        self._closed = False
        self.compiler = compiler if compiler is not None else Compiler()
        self._formatted: tuple[Version, str] | None = None  # _source_of version 1

    # ------------------------------------------------------------ the bus

    def attach(self, publisher: BusPublisher) -> None:
        """Take the engineering commands of ``publisher`` and serve the source and the
        project directory on its bus."""
        self.publisher = publisher
        publisher.route(ENGINEERING_OPS, self.submit)
        publisher.serve("source", self._source_bytes, fb=self.live.fb)
        publisher.serve("project", self._project_bytes)
        with contextlib.suppress(RuntimeError):  # warm before the first download
            self._worker.submit(self.compiler.start)

    def _source_bytes(self) -> bytes:
        v = self.current
        name = self.path.name if self.path is not None else f"{v.cc.name}.s7g"
        room = MAX_TEXT_BYTES - len(v.text.encode()) - len(self.symbols_text.encode())
        blocks, left_out = source_files(v.scl, room=room)
        source = ChartSource(
            fb=self.live.fb,
            version=v.number,
            file=name[:256],
            text=v.text,
            symbols=self.symbols_text,
            blocks=blocks,
            left_out=left_out,
        )
        data = encode(source)
        held = self._held_beside(v, left_out)
        if held is None:
            return data
        fuller = encode(msgspec.structs.replace(source, interfaces=BlockInterfaces.of(held)))
        return fuller if len(fuller) <= MAX_MESSAGE_BYTES else data

    def _held_beside(self, v: Version, left_out: list[str]) -> ProgramBlocks | None:
        """The interfaces of the blocks the CPU holds, for an editor, when the S7-SCL
        sources of chart version ``v`` do not give them all: a program of blocks that is
        not those sources (a Python program's), sources left out; else None. Their
        sources by file name, no directory, as the sources themselves go."""
        programs = list(self.session.blocks)
        if not left_out and all(p is v.scl for p in programs):
            return None
        held = self.held_interfaces()
        if held is None:
            return None
        names = [PurePath(f).name for p in programs for f in getattr(p, "files", ())]
        return dataclasses.replace(held, sources=", ".join(names))

    def _project_bytes(self) -> bytes | None:
        if self.directory is None:
            return None
        try:
            files = project_files(self.directory)
        except ProjectError:
            files = []
        listed = [ProjectFile(name=n[:256], format=f) for n, f in files[:4096]]
        return encode(ProjectFiles(directory=str(self.directory)[:4096], files=listed))

    def submit(self, pending: PendingCommand) -> None:
        """Queue an engineering command for the worker (the zenoh thread: never blocks)."""
        with self._lock:
            busy = self._waiting >= MAX_WAITING or self._closed
            if not busy:
                self._waiting += 1
        if busy:
            reason = Refusal("busy", "the CPU is busy with other engineering commands; retry")
            self.gate.consume(pending.command)  # never applied later, if sent again
            self._finish(pending, None, "", refusal_reply(reason))
            return
        try:
            self._worker.submit(self._handle, pending)
        except RuntimeError:  # shut down meanwhile
            with self._lock:
                self._waiting -= 1
            closed = Refusal("communication", "CPU bus closed")
            self._finish(pending, None, "", refusal_reply(closed))

    def close(self) -> None:
        """Refuse what still waits and stop the worker."""
        with self._lock:
            self._closed = True
            swap_ = self._swap
        if swap_ is not None:
            swap_.done.set()
        self.compiler.close()
        self._worker.shutdown(wait=True, cancel_futures=True)

    # ------------------------------------------------------------ the worker

    def _handle(self, pending: PendingCommand) -> None:
        try:
            command = pending.command
            who, refusal = self.gate.check(command)
            if who is None or refusal:
                self._finish(pending, None, "", refusal_reply(refusal))
                return
            as_user = msgspec.structs.replace(command, user=who.label, token="")
            try:
                reply, detail = self._run(as_user)
            except (_Refused, CompileRefused) as exc:
                lines = exc.lines[:MAX_LINES]
                reply, detail = refusal_reply(exc.reason, lines=lines), ""
            except Exception as exc:  # a bad command must never stop the worker
                where = f"in the CPU while applying {command.op} to {command.fb}"
                why = internal_error(where, exc)
                reason = f"{command.op} refused: {why}"[:4096]
                reply, detail = CommandReply(applied=False, reason=reason), ""
            self._finish(pending, who, detail, reply)
        finally:
            with self._lock:
                self._waiting -= 1

    def _finish(
        self, pending: PendingCommand, who: object, detail: str, reply: CommandReply
    ) -> None:
        """Audit the command (applied or refused) and answer its sender."""
        command = pending.command
        reply = msgspec.structs.replace(reply, op=command.op, fb=command.fb)
        if who is None:  # refused before its sender was checked (busy), or not authenticated
            who = self.gate.sender(command)
        label = getattr(who, "label", command.user or "?")
        role = getattr(who, "role", "")
        facts = Facts(
            label,
            role,
            command.origin,
            command.op,
            command.fb,
            _audited_args(command),
            reply.applied,
            reply.reason,
            with_note(detail, pending.note),
        )
        anonymous = who is None and not reply.applied
        with contextlib.suppress(Exception):  # the audit must not keep the answer back
            self.gate.record(facts, anonymous=anonymous)
        durability = self.durability
        # the row commits with the next scan, after the swap's: one wait covers both
        if (
            reply.applied
            and durability is not None
            and not durability.wait_durable(durability.durable_mark(), self._timeout)
        ):
            reply = _unconfirmed(reply, self._timeout, durability.write_problem())
        pending.answer(reply)

    def _run(self, command: Command) -> tuple[CommandReply, str]:
        op = command.op
        if op == "open":
            pou = command.args.get("pou")
            return self._open(str(command.args["file"]), pou if isinstance(pou, str) else None), ""
        if op == "save":
            return self._save(str(command.args["file"]), str(command.args["source"]))
        preview = command.args.get("preview") is True
        base = command.args.get("base")
        removed = command.args.get("removed")
        if isinstance(base, int) and base != self.current.number:
            moved = (
                f"the CPU runs chart version {self.current.number} now, not {base}: someone "
                "downloaded meanwhile — look at the CPU's chart again and redo the change"
            )
            raise _Refused(Refusal("state", moved))
        target: Version | None
        scl_texts: Mapping[str, str]
        if op == "undo_download":
            if not self.history:
                raise _Refused(Refusal("state", _NO_UNDO))
            back = self.history[-1]
            target = Version(
                self.current.number + 1,
                back.cc,
                back.table,
                back.text,
                None,
                back.scl,
                back.scl_texts,
            )
            summary = self.compiler.summarize(
                running=self._source_of(self.current),
                target=self._source_of(back),
                active=self._active(),
            )
            scl_changed = back.scl is not self.current.scl
            scl_texts, new_scl = back.scl_texts, back.scl
            needs = None if summary.unchanged else Needs.of(back.cc)
        else:
            sent = self._sent_blocks(command)
            file = str(command.args.get("file") or EDITED)
            target, summary = self._compile(str(command.args["source"]), preview, sent, file)
            scl_changed, scl_texts = bool(sent), {**self.current.scl_texts, **sent}
            new_scl = summary.blocks if target is None else target.scl
            needs = summary.needs
        lines = list(summary.lines()) or [UNCHANGED if scl_changed else SAME]
        if scl_changed:
            lines.append(_blocks_line(scl_texts, self.current))
        if scl_changed and new_scl is not None:
            notes = self._carried(op, new_scl)  # the notes the download's reply gives
            lines += notes if preview else []
        if not summary.unchanged and needs is not None:  # what the swap would refuse
            why = chart_refusal(self.session, needs, new_scl if scl_changed else None)
            if why is not None:
                raise _Refused(f"{op} refused: {why}; the CPU keeps the old chart")
        if preview:
            reply = CommandReply(
                applied=True,
                lines=lines[:MAX_LINES],
                version=self.current.number,
                removed=list(summary.removed_active),
            )
            return reply, f"preview of version {self.current.number + 1}: {summary.count} changes"
        if op == "download" and summary.unchanged and not scl_changed:
            same = f"nothing changes: the CPU runs this chart (version {self.current.number})"
            raise _Refused(Refusal("state", same))
        assert target is not None  # compiled: not a preview
        return self._download(command, target, summary, str(removed) if removed else None)

    def _carried(self, op: str, new: SclSources) -> list[str]:
        """What a download of ``new`` carries over, read off the running CPU from this
        thread (the scan boundary checks again): the notes its reply gives
        (``carry_notes``); ``_Refused`` with its reason when an instance DB cannot carry
        its values."""
        cpu = self.session.cpu
        try:
            refused, notes = refusals(cpu, new), carry_notes(cpu, self.current.scl, new)
        except RuntimeError:  # the CPU's DBs changed while read: the boundary checks again
            return []
        if refused:
            raise _Refused(f"{op} refused: {'; '.join(refused)}; the CPU keeps the old blocks")
        return notes

    def _active(self) -> tuple[int, ...]:
        cc, st = self.current.cc, self.session.graph.state
        return tuple(n for n, x in zip(cc.step_numbers, list(st.x), strict=False) if x)

    def _sent_blocks(self, command: Command) -> dict[str, str]:
        """The S7-SCL sources a download brings that differ from the CPU's."""
        sent = command.args.get("blocks") or {}
        try:
            self.block_files.merged(sent)
        except BlocksRefused as exc:
            raise _Refused(f"{command.op} refused: {exc}") from None
        return self.block_files.changes(sent)

    def _compile(
        self, text: str, preview: bool, sent: dict[str, str], file: str
    ) -> tuple[Version | None, Summary]:
        """``text`` compiled with the CPU's symbol table in the compiler's process, with the
        changed S7-SCL sources ``sent`` (and the CPU's others) — or, without, with the
        interfaces of the blocks the CPU holds (the chart reads their FBs' variables by
        name) — and its change summary (a preview: the summary only); its diagnostics name
        it ``file`` (the sender's)."""
        v = self.current
        blocks = self.block_files.merged(sent) if sent else None
        held = None if sent else self.held_interfaces()
        done = self.compiler.compile(
            text,
            file,
            symbols=self.symbols_text,
            running=self._source_of(v),
            active=self._active(),
            fb=self.live.fb,
            version=v.number + 1,
            preview=preview,
            blocks=blocks,
            interfaces=held,
        )
        if not isinstance(done, Compiled):
            return None, done
        scl, texts = (done.blocks, {**v.scl_texts, **sent}) if sent else (v.scl, v.scl_texts)
        return Version(v.number + 1, done.cc, done.table, text, done.live, scl, texts), done.summary

    def _source_of(self, v: Version) -> str:
        """Chart version ``v`` as ``.s7g`` text (the first, when imported from another
        format, as the text it formats to, made once)."""
        if v.number > 1 or self.path is None or self.path.suffix == ".s7g":
            return v.text
        if self._formatted is None or self._formatted[0] is not v:
            self._formatted = (v, format_chart(v.cc.chart))
        return self._formatted[1]

    def _download(
        self, command: Command, target: Version, summary: Summary, removed: str | None
    ) -> tuple[CommandReply, str]:
        """Write the files, swap at the boundary, keep the old version; undo when refused.
        S7-SCL blocks alone (the chart unchanged: its summary empty) leave the chart that
        runs, its state and its file as they are."""
        chart = not summary.unchanged
        if not chart:
            v = self.current
            target = dataclasses.replace(target, cc=v.cc, table=v.table, text=v.text)
        backup = None
        written = False
        blocks = target.scl if target.scl is not self.current.scl else None
        files = self._write_blocks(command, target) if blocks is not None else []
        if chart and self.path is not None:
            try:
                backup = write_chart(self.path, target.text)
                written = True
            except ProjectError as exc:
                self.block_files.restore(files)
                raise _Refused(
                    f"{command.op} refused: {exc}; the CPU keeps the old chart"
                ) from None
        live = target.live or self.live.prepare(target.cc, version=target.number)
        pending = _Swap(target, live, removed, command.user, blocks, chart)
        with self._lock:
            self._swap = pending
        pending.done.wait(self._timeout)
        with self._lock:
            if not pending.done.is_set():  # the scan thread will not take it any more
                pending.cancelled = True
            self._swap = None
        if not pending.ok:
            reason = pending.refusal or (
                f"the CPU reached no scan boundary within {self._timeout:g} s"
            )
            if written:
                try:
                    restore_backup(self.path, backup)  # type: ignore[arg-type]
                except ProjectError as exc:
                    reason += f"; and {exc}"
            if problem := self.block_files.restore(files):
                reason += f"; and {problem}"
            raise _Refused(f"{command.op} refused: {reason}; the CPU keeps the old chart")
        old = self.current
        if command.op == "undo_download":
            self.history.pop()
        else:
            self.history = [*self.history, old][-MAX_HISTORY:]
        self.current = target
        self.block_files.adopt(target.scl_texts)
        if self.publisher is not None:
            self.publisher.set_chart(self.live.fb, live.layout)
        lines = _reply_lines(pending, summary)
        if blocks is not None:
            lines += [_blocks_line(target.scl_texts, old), *pending.notes]
        where = f"; {self.path.name} written" if written and self.path is not None else ""
        kept = f", the old file kept as {backup.name}" if backup is not None else ""
        head = f"version {target.number} runs (was {old.number}){where}{kept}"
        digest = hashlib.sha256(target.text.encode()).hexdigest()[:12]
        detail = f"{head}; chart sha256 {digest}; " + "; ".join(lines)
        removed_now = list(pending.report.removed_active) if pending.report is not None else []
        reply = CommandReply(
            applied=True,
            lines=[head, *lines][:MAX_LINES],
            version=target.number,
            removed=removed_now,
        )
        return reply, detail[:4096]

    # ------------------------------------------------------------ the scan boundary

    def at_boundary(self) -> None:
        """Swap a compiled chart in, if one waits (the scan thread, between two scans)."""
        pending = self._swap
        if pending is None:
            return
        with self._lock:
            if pending.cancelled or pending.done.is_set() or self._swap is not pending:
                return
            try:
                session = self.session
                back = None
                if pending.blocks is not None:
                    pending.notes, back = swap_blocks(session, pending.blocks)
                try:
                    report = None
                    if pending.chart:
                        report = swap(
                            session.graph,
                            pending.target.cc,
                            session.cpu,
                            removed=pending.removed,
                            user=pending.user,
                        )
                except Exception:
                    if back is not None:
                        back()  # the old blocks with the old chart
                    raise
                session.symbols = pending.target.table
                self.live.switch(pending.live)
                pending.report, pending.ok = report, True
                if self.durability is not None:
                    pending.mark = self.durability.durable_mark()
            except (SwapRefused, BlocksRefused) as exc:
                pending.refusal = str(exc)
            except Exception as exc:  # the old chart keeps running
                where = f"in the CPU while switching {self.live.fb} to the new chart"
                pending.refusal = internal_error(where, exc)
            pending.done.set()

    # ------------------------------------------------------------ files

    def _write_blocks(self, command: Command, target: Version) -> list[tuple[Path, Path | None]]:
        """Write the S7-SCL sources ``target`` changes into the CPU's files (none without
        a chart file: a CPU that writes nothing)."""
        if self.path is None:
            return []
        was = self.current.scl_texts
        changed = {n: t for n, t in target.scl_texts.items() if was.get(n) != t}
        try:
            return self.block_files.write(changed)
        except BlocksRefused as exc:
            raise _Refused(f"{command.op} refused: {exc}") from None

    def _file(self, name: str) -> Path:
        if self.directory is None:
            why = "this CPU has no project directory (it runs no chart file)"
            raise _Refused(Refusal("refused", why))
        try:
            return project_file(self.directory, name)
        except ProjectError as exc:
            raise _Refused(str(exc)) from None

    def _open(self, name: str, pou: str | None = None) -> CommandReply:
        path = self._file(name)
        try:
            if not path.is_file():
                raise _Refused(Refusal("not_found", f"no file {name!r} in the project directory"))
            if path.stat().st_size > MAX_READ:
                raise _Refused(
                    f"{name} has {path.stat().st_size:,} bytes; at most {MAX_READ:,} are read"
                )
        except OSError as exc:
            raise _Refused(f"cannot open {name}: {exc}") from None
        opened = self.compiler.open(path, symbols=self.symbols_text, pou=pou)
        lines = opened.lines
        if opened.functions:
            lines = [*_functions_beside(self.session, path, pou, opened), *lines]
        return CommandReply(applied=True, text=opened.text, lines=lines[:MAX_LINES])

    def _save(self, name: str, text: str) -> tuple[CommandReply, str]:
        if not name.endswith(".s7g"):
            why = f"{name!r}: Save writes .s7g charts (a name ending in .s7g)"
            raise _Refused(Refusal("argument", why))
        path = self._file(name)
        self.compiler.check(text, name)
        try:
            backup = write_chart(path, text)
        except ProjectError as exc:
            raise _Refused(str(exc)) from None
        kept = f" (the old file kept as {backup.name})" if backup is not None else ""
        line = f"{name} written{kept}"
        return CommandReply(applied=True, lines=[line]), line


def _functions_beside(
    session: ChartSession, path: Path, pou: str | None, opened: Opened
) -> list[str]:
    """The SCL FCs an imported chart calls for its ST bodies, written beside the file
    as ``<stem>.scl`` (``chart_file``: as ``s7graph import -o <stem>.s7g`` writes them,
    beside the ``.s7g`` the editor proposes; the file it replaces kept as a backup); the
    notes saying so and which of them this CPU lacks.
    Refused when this CPU has an FC of such a number that is another block: the chart
    would call that one."""
    cpu = session.cpu
    loaded = _loaded_sources(session.blocks)
    lacking: list[int] = []
    other: list[int] = []
    for number, source in opened.functions:
        try:
            cpu.block(f"FC{number}")
        except BlockError:
            lacking.append(number)
            continue
        if _squeezed(source) not in loaded:
            other.append(number)
    if other:
        shown = ", ".join(f"FC {n}" for n in other)
        raise _Refused(
            f"{path.name}: its chart calls {shown} for ST bodies (SCL FCs the import "
            f"makes), and this CPU's {shown} comes from another source: a download "
            "would call it; import the file with s7graph import and renumber the FCs, "
            "or run the CPU without them"
        )
    scl = path.with_name(chart_file(path.name, pou, ".scl"))
    numbers = ", ".join(f"FC {n}" for n, _ in opened.functions)
    note = f"{scl.name}: the SCL FCs the chart calls for its ST bodies ({numbers})"
    try:
        same = scl.is_file() and scl.read_text(encoding="utf-8") == opened.scl
        backup = None if same else write_chart(scl, opened.scl)
    except (OSError, UnicodeDecodeError, ProjectError) as exc:
        raise _Refused(
            f"{path.name}: cannot write {scl.name}, the SCL FCs its chart calls: {exc}"
        ) from None
    kept = f", the old file kept as {backup.name}" if backup is not None else ""
    lines = [f"{note}, {'unchanged' if same else 'written'}{kept}"]
    if lacking:
        shown = ", ".join(f"FC {n}" for n in lacking)
        lines.append(
            f"this CPU does not have {shown}: a download of the chart is refused until "
            f"the CPU runs with --blocks {scl.name}"
        )
    return lines


def _loaded_sources(blocks: list[Any]) -> str:
    """The text of the S7-SCL sources the CPU loaded (``--blocks``), whitespace squeezed."""
    texts: list[str] = []
    for b in blocks:
        for name in getattr(b, "files", ()):
            with contextlib.suppress(OSError, UnicodeDecodeError):
                texts.append(Path(name).read_text(encoding="utf-8"))
    return _squeezed("\n".join(texts))


def _squeezed(text: str) -> str:
    return " ".join(text.split())


def _unconfirmed(reply: CommandReply, timeout_s: float, problem: str | None) -> CommandReply:
    """``reply`` of a command that acts, but whose commit the state file has not confirmed
    in time, or could not write (``problem``: a full disk): not *applied* (a restart might
    not see it), as the bus answers the others."""
    head = reply.lines[0] if reply.lines else "applied"
    if problem is not None:
        reason = f"not confirmed: {head}, but {problem}"
    else:
        reason = f"not confirmed: {head}, but the state file has not committed it within "
        reason += f"{timeout_s:g} s"
    return msgspec.structs.replace(reply, applied=False, reason=reason, kind="timeout")


def _audited_args(command: Command) -> dict[str, object]:
    """A command's arguments for the audit: a chart's and each S7-SCL source's text by its
    size and hash."""
    args: dict[str, object] = dict(command.args)
    source = args.get("source")
    if isinstance(source, str):
        args["source"] = _sized(source)
    blocks = args.get("blocks")
    if isinstance(blocks, dict):
        args["blocks"] = {name: _sized(str(text)) for name, text in blocks.items()}
    return args


def _sized(text: str) -> str:
    digest = hashlib.sha256(text.encode()).hexdigest()[:12]
    return f"{len(text):,} characters, sha256 {digest}"


def _blocks_line(texts: Mapping[str, str], old: Version) -> str:
    """Which S7-SCL sources a change to ``texts`` brings."""
    was = old.scl_texts
    changed = [n for n, t in texts.items() if was.get(n) != t]
    return f"S7-SCL blocks changed: {', '.join(changed) or 'the same sources, compiled again'}"


def _reply_lines(pending: _Swap, summary: Summary) -> list[str]:
    """What a download made did to the chart: the swap's report, then the summary's lines
    it does not already give (a variable that restarts, a new sequencer: said alike by
    both); or that the chart does not change (S7-SCL blocks alone)."""
    if pending.report is None:
        return [UNCHANGED]
    done = pending.report.lines()
    return [*done, *(line for line in summary.lines(done=True) if line not in done)]
