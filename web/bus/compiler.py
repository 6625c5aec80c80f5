"""Charts parsed, checked and compiled in a process of their own, never in the CPU's.

A chart sent to the CPU (a download, its preview, a save, an open) is parsed, validated
and compiled by a warm child process (``python -m s7graph.web.bus.compiler``): compiling
holds the interpreter's lock in long C calls (``compile()``, the parser), and a thread of
the CPU's process would hold the scan up for as long; a second process does not share the
lock. The rules:

- the size limit first: a text over ``MAX_SOURCE`` characters is refused before anything
  parses it (and before it is sent to the child);
- the time limit: a request the child has not answered within ``time_limit_s`` is refused
  and the child killed and replaced (a fresh one starts at once, warm for the next);
- a child found ended before it had the whole request (gone while idle, its pipe closed) is
  replaced and the request sent once more; one that ends with the request is replaced and
  the request refused;
- the child runs on the processors of the thread that made the :class:`Compiler` (the chart
  runner makes it off the processor it keeps for the scan: ``engine.cores.kept_free``), at
  the normal scheduling policy even when started from a real-time thread;
- what comes back for a download is the compiled chart without its code objects (pickled),
  the code objects marshalled one batch at a time (``sequencer.compile._batches``), and
  the view's layout of it (``web.bus.live.prepare_chart``): the CPU's process never
  compiles source; it unpickles with the cyclic collector paused and, when the runner
  collects in the scan's idle time (automatic collections off), freezes each piece as it
  comes (``gc.freeze``) so that the scan's idle collections do not walk the new chart;
- S7-SCL sources sent with a download (``blocks``) are compiled there too, after the
  chart, and come back as bytes (``steps.scl.portable``): the CPU's process runs each
  source's generated module once to make its blocks, and parses or compiles nothing; it
  loads them as a chart, the collector paused, and freezes them after. One source is one
  pickle, loaded in one piece: the end of a very large one still holds the interpreter
  for a moment (about 50 ms for a 740 kB source of 12,000 IF statements: docs/scl.md).
  A request without sources carries the interfaces of the blocks the CPU holds
  (``sequencer.checks.interfaces.ProgramBlocks``, small): the chart reads their FBs'
  variables by name (``"Motor_DB".Running``) as it did when the CPU started;
- a preview, a save and an open bring back text only (the change summary, the chart) —
  but a preview's S7-SCL sources, which come back as a download's do: the CPU's process
  says from them what the download would carry over (``web.harness.scl_reload``).

Used by ``web.bus.online.OnlineChange`` from its one worker thread.
"""

from __future__ import annotations

import contextlib
import dataclasses
import gc
import marshal
import os
import pickle
import select
import signal
import struct
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any, Final

from s7graph.engine.cores import allowed_cpus
from s7graph.engine.switching import SWITCH_S, switching
from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.change.base import MAX_SOURCE
from s7graph.sequencer.change.diff import removal_line
from s7graph.sequencer.change.online import Needs
from s7graph.sequencer.checks.interfaces import ProgramBlocks
from s7graph.sequencer.collector import collector_paused
from s7graph.sequencer.compiled import CompiledChart
from s7graph.web.bus import compile_jobs
from s7graph.web.bus.live import LiveChart
from s7graph.web.bus.pieces import loads_in_pieces
from s7graph.web.harness.scl import SclSources, load_texts

__all__ = [
    "MAX_SOURCE",
    "START_LIMIT_S",
    "TIME_LIMIT_S",
    "CompileRefused",
    "Compiled",
    "Compiler",
    "Opened",
    "Summary",
]

TIME_LIMIT_S: Final = 20.0
"""A request the child has not answered by then is refused (and the child replaced): well
within the 30 s the view and ``s7graph download`` wait for a download's answer, which also
writes the file and waits for a scan boundary."""
START_LIMIT_S: Final = 120.0  # a fresh child imports s7graph within this
_HEADER = struct.Struct("<Q")
_PR_SET_PDEATHSIG = 1
_READY = b"s7graph-compiler ready"


class CompileRefused(Exception):
    """A request refused: ``reason`` (one line naming the limit or the place) and the
    diagnostics (``lines``)."""

    def __init__(self, reason: str, lines: list[str] | tuple[str, ...] = ()) -> None:
        super().__init__(reason)
        self.reason = reason
        self.lines = list(lines)


@dataclass(frozen=True, slots=True)
class Summary:
    """A change summary as text (``sequencer.diff.ChangeSummary`` without the model values):
    its lines, the active steps the change removes, and how many changes."""

    text: tuple[str, ...]
    removed_active: tuple[int, ...]
    count: int
    blocks: SclSources | None = None  # a preview's S7-SCL sources, compiled (if sent)
    needs: Needs | None = None  # what the chart needs of the CPU (None: an undo's summary)

    @property
    def unchanged(self) -> bool:
        return self.count == 0

    def lines(self, *, done: bool = False) -> tuple[str, ...]:
        """Its lines; ``done``: as the reply of a download made lists them, without the
        question of each removed active step (the swap's report says what was done)."""
        if not done:
            return self.text
        asked = {removal_line(n) for n in self.removed_active}
        return tuple(line for line in self.text if line not in asked)


@dataclass(frozen=True, slots=True)
class Compiled:
    """A chart compiled by the child: the compiled chart, its symbol table, the view's
    description of it and the change summary against the running chart."""

    cc: CompiledChart
    table: SymbolTable
    live: LiveChart
    summary: Summary
    blocks: SclSources | None = None  # the S7-SCL sources compiled with it, if sent


@dataclass(frozen=True, slots=True)
class Opened:
    """A file imported for the editor's *Open*: the chart's ``.s7g`` text, the import's
    notes, the SCL source of the FCs it calls for its ST bodies (``Imported.blocks_scl``,
    "" for none) and those FCs as (number, source)."""

    text: str
    lines: list[str]
    scl: str = ""
    functions: tuple[tuple[int, str], ...] = ()


class Compiler:
    """The warm compiler process of one CPU (see the module). Call from one long-lived
    thread (the child is killed when the thread that started it ends); only :meth:`close`
    may come from another. ``time_limit_s``: the longest a request may take;
    ``cpus``: the processors the child runs on (default: the calling thread's now)."""

    def __init__(
        self,
        *,
        time_limit_s: float = TIME_LIMIT_S,
        start_limit_s: float = START_LIMIT_S,
        cpus: set[int] | None = None,
    ) -> None:
        self.time_limit_s = time_limit_s
        self.start_limit_s = start_limit_s
        self.cpus = set(cpus) if cpus is not None else allowed_cpus()
        self.started = 0  # children started (a replacement counts)
        self._proc: subprocess.Popen[bytes] | None = None
        self._ready = False
        self._lock = threading.Lock()  # _proc against close()
        self._closed = False

    # ------------------------------------------------------------ the child

    @property
    def pid(self) -> int | None:
        proc = self._proc
        return proc.pid if proc is not None and proc.poll() is None else None

    def start(self) -> None:
        """Start the child unless one runs (it imports while the caller goes on)."""
        with self._lock:
            if self._closed or (self._proc is not None and self._proc.poll() is None):
                return
            cpus = ",".join(map(str, sorted(self.cpus)))
            self._proc = subprocess.Popen(  # a Ctrl-C at the terminal is the CPU's to handle
                [sys.executable, "-m", "s7graph.web.bus.compiler", "--cpus", cpus],
                stdin=subprocess.PIPE,
                stdout=subprocess.PIPE,
                close_fds=True,
                env=_child_env(),
                start_new_session=True,
            )
            self._ready = False
            self.started += 1

    def close(self) -> None:
        """End the child (its input closed; killed if it does not end at once)."""
        with self._lock:
            self._closed = True
            proc, self._proc = self._proc, None
        if proc is not None:
            _end(proc)

    def _replace(self) -> None:
        """Kill the child and start a fresh one, warm for the next request."""
        with self._lock:
            proc, self._proc = self._proc, None
        if proc is not None:
            _end(proc, at_once=True)
        self.start()

    def _call(self, request: dict[str, Any], what: str) -> tuple[dict[str, Any], list[bytes]]:
        """Send ``request``, wait for the answer (a small header, then as many raw pieces
        as it says) within the time limit. A child found ended before it had the whole
        request (gone while idle, its pipe closed) is replaced and the request sent once
        more to the fresh one: every request is a pure function of its text, so sending it
        again changes nothing but who answers."""
        data = pickle.dumps(request, protocol=pickle.HIGHEST_PROTOCOL)
        for again in (True, False):
            proc = self._started(what)
            try:
                self._send(proc, data, what)
                break
            except (OSError, EOFError, ValueError) as exc:
                self._replace()
                if not again:
                    reason = f"{what} refused: the compiler process ended ({exc})"
                    raise CompileRefused(reason) from None
        return self._answer(proc, what)

    def _started(self, what: str) -> subprocess.Popen[bytes]:
        """The child, started if none runs."""
        self.start()
        proc = self._proc
        if proc is None or proc.stdin is None or proc.stdout is None:
            raise CompileRefused(f"{what} refused: the CPU's compiler is closed")
        return proc

    def _send(self, proc: subprocess.Popen[bytes], data: bytes, what: str) -> None:
        """``data`` to the child, once it said it is ready (refused when it does not
        within ``start_limit_s``)."""
        assert proc.stdin is not None and proc.stdout is not None
        if not self._ready:
            try:
                ready = _read(proc.stdout, self.start_limit_s)
            except TimeoutError:
                self._replace()
                raise CompileRefused(
                    f"{what} refused: the compiler process did not start within "
                    f"{self.start_limit_s:g} s"
                ) from None
            if ready != _READY:
                raise EOFError("it did not start")
            self._ready = True
        proc.stdin.write(_HEADER.pack(len(data)) + data)
        proc.stdin.flush()

    def _answer(
        self, proc: subprocess.Popen[bytes], what: str
    ) -> tuple[dict[str, Any], list[bytes]]:
        """The child's answer to the request just sent, within the time limit."""
        assert proc.stdout is not None
        try:
            deadline = time.monotonic() + self.time_limit_s
            reply: dict[str, Any] = pickle.loads(_read(proc.stdout, self.time_limit_s))
            blobs = [
                _read(proc.stdout, deadline - time.monotonic())
                for _ in range(int(reply.get("blobs", 0)))
            ]
        except TimeoutError:
            self._replace()
            raise CompileRefused(
                f"{what} refused: not compiled within {self.time_limit_s:g} s (the time "
                "limit); the compiler process was stopped"
            ) from None
        except (OSError, EOFError, ValueError) as exc:
            self._replace()
            raise CompileRefused(f"{what} refused: the compiler process ended ({exc})") from None
        if "refused" in reply:
            raise CompileRefused(str(reply["refused"]), list(reply.get("lines", ())))
        return reply, blobs

    # ------------------------------------------------------------ requests

    def compile(
        self,
        text: str,
        file: str,
        *,
        symbols: str,
        running: str,
        active: tuple[int, ...],
        fb: str,
        version: int,
        preview: bool = False,
        blocks: list[tuple[str, str]] | None = None,
        interfaces: ProgramBlocks | None = None,
    ) -> Compiled | Summary:
        """``text`` compiled as version ``version`` of FB ``fb`` with the symbol table text
        ``symbols``, its change summary against the ``running`` chart's text with the
        ``active`` steps; a ``preview`` brings back the summary only (with the compiled
        ``blocks``, if sent). ``blocks``: the S7-SCL sources (file, text) the chart's calls
        reach, compiled with it in that order (made in this process of the child's bytes:
        ``web.harness.scl.load_texts``); ``interfaces``: those of the blocks the CPU holds,
        whose FBs' variables the chart reads by name when no ``blocks`` replace them."""
        _size_limit(text, "the chart")
        if blocks is not None:
            _size_limit("".join(t for _, t in blocks), "the S7-SCL sources (together)")
        request = {
            "op": "preview" if preview else "compile",
            "text": text,
            "file": file,
            "symbols": symbols,
            "running": running,
            "active": active,
            "fb": fb,
            "version": version,
            "blocks": blocks,
            "interfaces": interfaces,
        }
        reply, blobs = self._call(request, "download")
        said, removed, count = reply["summary"]
        summary = Summary(said, removed, count, needs=reply.get("needs"))
        if blocks is None:
            return summary if preview else _loaded(blobs, reply["parts"], summary)
        files, warnings, n = reply["blocks"]
        cut = len(blobs) - 2 * n
        pairs = [(blobs[k], blobs[k + 1]) for k in range(cut, len(blobs), 2)]
        done = None if preview else _loaded(blobs[:cut], reply["parts"], summary)
        with _loading():  # as ``_loaded`` loads a chart
            sources = load_texts(files, pairs, warnings, [t for _, t in blocks])
        if done is None:
            return dataclasses.replace(summary, blocks=sources)
        return dataclasses.replace(done, blocks=sources)

    def summarize(self, *, running: str, target: str, active: tuple[int, ...]) -> Summary:
        """The change summary from the ``running`` chart's text to ``target``'s, with the
        ``active`` steps (an undo: the target compiled before)."""
        request = {"op": "summary", "running": running, "target": target, "active": active}
        reply, _ = self._call(request, "undo_download")
        return Summary(*reply["summary"])

    def check(self, text: str, file: str) -> None:
        """``text`` parses as a chart within the editor's limits (CompileRefused if not)."""
        _size_limit(text, "the chart")
        self._call({"op": "check", "text": text, "file": file}, "save")

    def open(self, path: Path, *, symbols: str, pou: str | None = None) -> Opened:
        """The chart of file ``path`` (any format ``sequencer.exchange`` imports) as
        ``.s7g`` text, the import's notes and the SCL FCs the chart calls for its ST bodies;
        ``pou`` picks one chart of a file that holds several (refused without: its lines
        name each chart, ``CHART_CHOICE``)."""
        request = {"op": "open", "path": str(path), "symbols": symbols, "pou": pou}
        reply, _ = self._call(request, "open")
        functions = tuple((int(n), str(src)) for n, src in reply.get("functions", ()))
        return Opened(
            str(reply["text"]), list(reply["lines"]), str(reply.get("scl", "")), functions
        )


def _size_limit(text: str, what: str) -> None:
    if len(text) > MAX_SOURCE:
        raise CompileRefused(
            f"{what} has {len(text):,} characters; at most {MAX_SOURCE:,} are compiled "
            "(the size limit)"
        )


def _loaded(blobs: list[bytes], parts: tuple[int, int], summary: Summary) -> Compiled:
    """The child's compiled chart in this process (``blobs``: ``parts`` pickled pieces of
    it, ``web.bus.pieces``; as many code objects, marshalled; its generated source in
    pieces, UTF-8), loaded piece by piece with the collector paused. Between two pieces the
    interpreter may switch to the scan thread, and does so within ``SWITCH_S`` of its asking
    (not the interpreter's usual 5 ms). Where the runner keeps automatic collections off and
    collects in the scan's idle time, each piece is frozen (``gc.freeze``) as it comes: an
    idle-time collection of the scan thread between two pieces would otherwise walk the
    chart loaded so far (13 ms seen for a 1,000-step chart)."""
    n_chart, n_code = parts
    with _loading() as settle:
        cc, table, live = loads_in_pieces(blobs[:n_chart], settle)
        code = []
        for piece in blobs[n_chart : n_chart + n_code]:
            code.append(marshal.loads(piece))
        source = []
        for piece in blobs[n_chart + n_code :]:
            source.append(piece.decode())
        object.__setattr__(cc, "code", tuple(code))
        object.__setattr__(cc, "source", "".join(source))
    return Compiled(cc, table, live, summary)


@contextlib.contextmanager
def _loading() -> Iterator[Callable[[], None] | None]:
    """Loading what the child compiled, beside the scan: the collector paused, the switch
    interval short (``SWITCH_S``); where the runner keeps automatic collections off and
    collects in the scan's idle time, ``gc.freeze`` is given (to freeze pieces as they
    come) and called at the end, so that those collections never walk what was loaded."""
    settle = gc.freeze if not gc.isenabled() else None
    with collector_paused(), switching(SWITCH_S):
        yield settle
    if settle is not None:
        settle()


def _child_env() -> dict[str, str]:
    """The environment with this process's ``s7graph`` first on the child's path."""
    import s7graph

    env = dict(os.environ)
    roots = [str(Path(p).resolve().parent) for p in s7graph.__path__]
    env["PYTHONPATH"] = os.pathsep.join([*roots, *filter(None, [env.get("PYTHONPATH")])])
    return env


def _end(proc: subprocess.Popen[bytes], *, at_once: bool = False) -> None:
    with contextlib.suppress(OSError, ValueError):
        if proc.stdin is not None:
            proc.stdin.close()
    if at_once:
        proc.kill()
    try:
        proc.wait(2.0)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()
    if proc.stdout is not None:
        proc.stdout.close()


def _read(stream: IO[bytes], limit_s: float) -> bytes:
    """One message (length, then bytes) from ``stream`` within ``limit_s``: TimeoutError
    when it does not come, EOFError when the child ended."""
    fd = stream.fileno()
    deadline = time.monotonic() + limit_s
    buf = bytearray()
    need = _HEADER.size
    size: int | None = None
    while True:
        while len(buf) < need:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([fd], [], [], left)[0]:
                raise TimeoutError
            chunk = os.read(fd, min(1 << 20, need - len(buf)))
            if not chunk:
                raise EOFError("no answer")
            buf += chunk
        if size is not None:
            return bytes(buf[_HEADER.size :])
        (size,) = _HEADER.unpack_from(buf)
        need = _HEADER.size + size


# ---------------------------------------------------------------------------- the child


def _serve(cpus: str) -> int:
    """The child: requests from stdin, answers to stdout, one at a time, until stdin ends."""
    _own_processor(cpus)
    inp, out = sys.stdin.buffer, sys.stdout.buffer
    out.write(_HEADER.pack(len(_READY)) + _READY)
    out.flush()
    while True:
        head = inp.read(_HEADER.size)
        if len(head) < _HEADER.size:
            return 0
        (size,) = _HEADER.unpack(head)
        request = pickle.loads(inp.read(size))
        answer, blobs = compile_jobs.answer(request)
        data = pickle.dumps({**answer, "blobs": len(blobs)}, protocol=pickle.HIGHEST_PROTOCOL)
        for message in (data, *blobs):
            out.write(_HEADER.pack(len(message)) + message)
        out.flush()


def _own_processor(cpus: str) -> None:
    """The normal scheduling policy (a real-time parent thread's is inherited) on
    ``cpus`` (comma-separated processor numbers); killed when the CPU's process ends, even
    in the middle of a compile (Linux: ``PR_SET_PDEATHSIG``)."""
    with contextlib.suppress(OSError, AttributeError):
        import ctypes

        ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, signal.SIGKILL)
    if os.getppid() == 1:  # the parent ended before the line above
        sys.exit(0)
    with contextlib.suppress(OSError, AttributeError):
        os.sched_setscheduler(0, os.SCHED_OTHER, os.sched_param(0))
    wanted = {int(c) for c in cpus.split(",") if c.strip().isdigit()}
    if wanted:
        with contextlib.suppress(OSError, AttributeError, ValueError):
            os.sched_setaffinity(0, wanted)


if __name__ == "__main__":
    sys.exit(_serve(sys.argv[sys.argv.index("--cpus") + 1] if "--cpus" in sys.argv else ""))
