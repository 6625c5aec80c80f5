"""Shared helpers of the web tests, imported as ``tests.web.helpers``: polling with a
deadline, one headless Chromium page through playwright, a compiled chart's session on
the virtual clock, and an online CPU on a real bus with a client logged in to it."""

from __future__ import annotations

import os
import queue
import re
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar

import pytest

from s7graph.engine.clock import VirtualClock
from s7graph.engine.persistence import StateStore
from s7graph.engine.symbols import SymbolTable
from s7graph.web.harness.session import ChartSession, load_chart
from tests.paths import ROOT

if TYPE_CHECKING:
    from playwright.sync_api import Locator, Page

    from s7graph.engine.cpu import Cpu
    from s7graph.engine.record import ScanRecord
    from s7graph.engine.runner import Runner
    from s7graph.web.bus.client import BusClient
    from s7graph.web.bus.online import OnlineChange
    from s7graph.web.bus.protocol import CommandReply
    from s7graph.web.bus.session import TlsFiles
    from s7graph.web.harness.scl import Loadable
    from s7graph.web.view.edge import ViewSide
    from s7graph.web.wiring.live_edge import LiveEdge
    from tests.conftest import BusCerts

CHROMIUM = "/usr/bin/chromium"
ARGS = [
    "--no-sandbox",
    "--headless",
    "--enable-unsafe-swiftshader",
    "--use-angle=swiftshader",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
]
needs_chromium = pytest.mark.skipif(
    not os.path.exists(CHROMIUM), reason=f"no browser at {CHROMIUM}"
)


def wait_until(predicate: Callable[[], object], timeout: float = 10.0, poll: float = 0.05) -> bool:
    """Poll ``predicate`` every ``poll`` s until it holds or ``timeout`` s have passed."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(poll)
    return bool(predicate())


@contextmanager
def chromium_page(url: str) -> Iterator[Page]:
    """A 1280x800 page at ``url`` in one headless Chromium (skips without playwright)."""
    sync_api = pytest.importorskip("playwright.sync_api", reason="playwright is not installed")
    with sync_api.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, headless=True, args=ARGS)
        try:
            page = browser.new_page(viewport={"width": 1280, "height": 800})
            page.goto(url)
            yield page
            page.close()
        finally:
            browser.close()


def block_source(page: Page) -> str:
    """The S7-SCL source a page's read-only window shows now ("" when none is open)."""
    shown = page.locator("pre.s7-block-source")
    return str(shown.inner_text()) if shown.count() else ""


def page_point(
    client: object, x: float, y: float, *, left: float = 0.0, page: Page | None = None
) -> tuple[int, int]:
    """Where the scene point ``(x, y)`` shows on ``client``'s page: its camera as the page
    reports it (looking straight down, viser's vertical field of view), on its canvas
    (``left``: pixels of the page left of the canvas, a panel docked there). With ``page``
    the canvas is measured on the page itself (the size the page last reported may be one
    it had while its panel was still being docked)."""
    import math

    cam = client.camera  # type: ignore[attr-defined]
    cx, cy, z = (float(v) for v in cam.position)
    half = z * math.tan(cam.fov / 2)
    w, h = float(cam.image_width), float(cam.image_height)
    if page is not None:
        left, w, h = canvas_box(page)
    return round(left + w / 2 + (x - cx) / half * h / 2), round(h / 2 - (y - cy) / half * h / 2)


def canvas_box(page: Page) -> tuple[float, float, float]:
    """The left, width and height of the page's WebGL canvas, in page pixels."""
    box = page.evaluate(
        """() => {
            const all = Array.from(document.querySelectorAll('canvas'));
            const c = all.sort((a, b) => b.width * b.height - a.width * a.height)[0];
            const r = c.getBoundingClientRect();
            return [r.left, r.width, r.height];
        }"""
    )
    return float(box[0]), float(box[1]), float(box[2])


def field(page: Page, label: str) -> Locator:
    """The text input of a viser GUI field by its label (viser's label does not name it)."""
    row = "ancestor::div[contains(@class,'mantine-Flex-root')][1]"
    xpath = f"//label[text()='{label}']/{row}//input"
    return page.locator(f"xpath={xpath}").first


GUI_SETTLE_MS = 250
"""viser's page sends one GUI update per 50 ms and keeps only the newest of those that
wait (viser 1.1.1, ``makeThrottledMessageSender``): a field filled, then another field or
a button within that window, and the first never reaches the view. A test lets this much
pass between two inputs (more than 50 ms: the page's timer runs late on a loaded machine)."""


def fill(page: Page, label: str, text: str) -> None:
    """Type ``text`` into the viser field ``label`` and let it reach the view."""
    box = field(page, label)
    box.fill(text)
    box.press("Tab")
    page.wait_for_timeout(GUI_SETTLE_MS)


def log_in(page: Page, user: str, password: str = "") -> None:
    """Log the page in through its Login panel and wait until it says so."""
    fill(page, "User", user)
    if password:
        fill(page, "Password", password)
    page.get_by_role("button", name="Log in", exact=True).click()
    page.get_by_text(f"logged in as {user}").first.wait_for(timeout=30_000)


@contextmanager
def scanning(
    session: ChartSession, edge: LiveEdge, on_record: Callable[[ScanRecord], object] | None = None
) -> Iterator[threading.Event]:
    """Start ``session`` and scan it every 10 ms of its virtual clock in a thread, each
    record through ``on_record`` (if given) and ``edge``; set the event to stop early."""
    session.start()
    stop = threading.Event()

    def scan_loop() -> None:
        clock = session.clock
        assert isinstance(clock, VirtualClock)
        while not stop.is_set():
            clock.advance(10)
            record = session.scan()
            if on_record is not None:
                on_record(record)
            edge.on_record(record, stats=session.cpu.stats)
            time.sleep(0.005)

    thread = threading.Thread(target=scan_loop, daemon=True)
    thread.start()
    try:
        yield stop
    finally:
        stop.set()
        thread.join(timeout=5)


def chart_session(
    tmp_path: Path, name: str, chart: str
) -> tuple[ChartSession, SymbolTable, VirtualClock, StateStore]:
    """``chart`` written to ``tmp_path / name`` and compiled, in a (not yet started)
    session on a virtual clock, and a state store ``state.sqlite`` beside it (close it)."""
    path = tmp_path / name
    path.write_text(chart, encoding="utf-8")
    cc, table = load_chart(path)
    clock = VirtualClock()
    session = ChartSession(cc, table, clock)
    store = StateStore(tmp_path / "state.sqlite")
    return session, table, clock, store


CALLS_FB17 = """FUNCTION_BLOCK "Seq" FB 1 DB 1
SEQUENCE 1 "S"
  INITIAL_STEP S1 "count":
    CALL FB 17, DB 10 (go := TRUE);
  END_STEP
  STEP S2 "never": END_STEP
  TRANSITION T1 FROM S1 TO S2 := FALSE;
END_SEQUENCE
END_FUNCTION_BLOCK
"""
"""A chart whose initial step calls FB 17 with DB 10 (``go := TRUE``) and never leaves:
the S7-SCL blocks' tests give FB 17 in their own source."""

PASSWORD = "correct horse"
PREVIEW_MS = 90_000
"""How long a page may wait for a download's preview ("What changes"): it is compiled in a
process of its own, which a loaded machine (a CI run beside other test processes) may keep
waiting for a processor for tens of seconds."""


@dataclass
class OnlineRig:
    """A CPU running a chart file on the virtual clock, scanned in a thread, on a real bus
    (``endpoint``) with its online change; ``edge.url`` is its page when served. A client
    joins with ``tls`` (open_session) or the options ``bus`` (a shell's)."""

    session: ChartSession
    edge: LiveEdge
    online: OnlineChange
    path: Path
    state: Path
    endpoint: str
    scans: list[int]
    tls: TlsFiles
    bus: list[str]


def free_port() -> int:
    """A TCP port free on 127.0.0.1 now."""
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@contextmanager
def online_cpu(
    tmp_path: Path,
    chart: str,
    *,
    serve: bool,
    users: dict[str, str],
    certs: BusCerts,
    name: str = "chart.s7g",
    operands: bool = False,
    messages: bool = False,
    blocks: dict[str, str] | None = None,
    program: Loadable | None = None,
) -> Iterator[OnlineRig]:
    """``chart`` written to ``tmp_path / name`` and run with a users file (name → role,
    password ``PASSWORD``), its bus on TLS on loopback with the certificates ``certs`` (as
    ``s7graph run`` insists with a users file: a client joins as ``client.olga``), the view
    when ``serve``; the CPU takes force jobs as ``s7graph run`` does, and publishes its
    operands when ``operands`` (``web.bus.operands``) and keeps its message list on the bus
    when ``messages`` (the page's Alarms); ``blocks``: S7-SCL sources (file name → text)
    written beside the chart and run with it, and served on the bus, as ``--blocks`` does;
    ``program``: a program of blocks (a Python program's) loaded beside the chart instead,
    the chart compiled with its interfaces."""
    from s7graph.sequencer.checks.interfaces import program_blocks
    from s7graph.sfb.alarms import message_list
    from s7graph.web.access.audit import AuditStore
    from s7graph.web.access.login import Authenticator
    from s7graph.web.access.users import UsersFile
    from s7graph.web.bus.forcing import Forcing
    from s7graph.web.bus.gate import Gate
    from s7graph.web.bus.live import LiveGraph
    from s7graph.web.bus.online import OnlineChange
    from s7graph.web.bus.operands import OperandFeed
    from s7graph.web.bus.session import BusEnds
    from s7graph.web.wiring.live_edge import LiveEdge

    path = tmp_path / name
    path.write_text(chart, encoding="utf-8")
    users_file = UsersFile(tmp_path / "users.json")
    for user, role in users.items():
        users_file.add(user, role, PASSWORD)
    state = tmp_path / "state.sqlite"
    audit = AuditStore(state)
    sources = []
    for file, text in (blocks or {}).items():
        sources.append(tmp_path / file)
        sources[-1].write_text(text, encoding="utf-8")
    if program is not None:
        held = program_blocks(program.blocks)
        cc, table = load_chart(path, None, blocks=lambda _: held)
        session = ChartSession(cc, table, VirtualClock(), blocks=[program])
    else:
        session = ChartSession.load(path, None, VirtualClock(), blocks=sources)
    kept = message_list(session.cpu) if messages else None
    live = LiveGraph(session.graph, read=session.get, messages=kept)
    gate = Gate(Authenticator(users_file), audit)
    online = OnlineChange(session, live, gate, path=path, blocks=sources)
    endpoint = f"tls/localhost:{free_port()}"
    bus = ["--connect", endpoint, *certs.args("client.olga")]
    scans: list[int] = []
    try:
        edge = LiveEdge(
            live,
            port=0,
            serve=serve,
            bus=True,
            gate=gate,
            online=online,
            ends=BusEnds(listen=[endpoint], tls=certs.tls("cpu.cpu1")),
            forcing=Forcing(session.cpu),
            operands=OperandFeed(session, fb=live.fb) if operands else None,
        )
        if sources and edge.publisher is not None:  # as s7graph run serves --blocks
            from s7graph.web.bus.block_sources import serve_blocks
            from s7graph.web.harness.scl import scl_of

            serve_blocks(edge.publisher, lambda: scl_of(session.blocks))
        with edge, scanning(session, edge, lambda record: scans.append(record.cycle)):
            client = certs.tls("client.olga")
            yield OnlineRig(session, edge, online, path, state, endpoint, scans, client, bus)
    finally:
        audit.close()


@dataclass
class OnlineClient:
    """A bus client of an online CPU (``rig``) on a session of its own, joined as
    ``client.olga``, logged in as ``user`` with ``token`` ("" for both: not logged in). Its
    commands go to the chart ``FB`` and wait ``TIMEOUT`` s at the most for the reply."""

    rig: OnlineRig
    client: BusClient
    token: str = ""
    user: str = ""

    FB: ClassVar[str] = "Seq"
    TIMEOUT: ClassVar[float] = 60.0

    @property
    def session(self) -> ChartSession:
        return self.rig.session

    @property
    def path(self) -> Path:
        return self.rig.path

    def send(self, op: str, **args: object) -> CommandReply:
        """``op`` with ``args`` on the chart ``FB`` as ``user``: the CPU's reply."""
        from s7graph.web.bus.protocol import Command

        command = Command(op=op, fb=self.FB, user=self.user, token=self.token, args=args)
        return self.client.send(command, timeout=self.TIMEOUT)


def logged_in(client: BusClient, user: str, *, origin: str = "") -> str:
    """The token of ``user`` (password ``PASSWORD``) logged in at ``client``'s CPU."""
    login = client.login(user, PASSWORD, origin=origin)
    assert login.ok, login.reason
    return login.token


@contextmanager
def online_client(
    tmp_path: Path,
    chart: str,
    *,
    certs: BusCerts,
    users: dict[str, str] | None = None,
    user: str | None = "eng",
    serve: bool = False,
    **options: Any,
) -> Iterator[OnlineClient]:
    """:func:`online_cpu` of ``chart`` (``users``: ``{"eng": "engineer"}`` unless given;
    ``options``: its others) and a bus client of it on a session of its own, joined with
    the rig's ``tls``, logged in as ``user`` once the CPU answers its status (None:
    neither waits nor logs in)."""
    from s7graph.web.bus.client import BusClient
    from s7graph.web.bus.session import open_session

    roles = {"eng": "engineer"} if users is None else users
    with (
        online_cpu(tmp_path, chart, serve=serve, users=roles, certs=certs, **options) as rig,
        open_session(connect=[rig.endpoint], tls=rig.tls) as session,
        BusClient(session, "cpu1") as client,
    ):
        token = ""
        if user is not None:
            assert wait_until(lambda: client.status() is not None)
            token = logged_in(client, user)
        yield OnlineClient(rig, client, token, user or "")


@contextmanager
def cpu_process(
    tmp_path: Path,
    args: list[str],
    *,
    fb: str | None = None,
    user: str | None = None,
    terminate: bool = False,
) -> Iterator[tuple[subprocess.Popen[str], BusClient, str]]:
    """``s7graph run ARGS --listen`` on a unix socket in ``tmp_path`` as a real process,
    with a bus client once it is on the bus; with ``fb``, once that FB's state is served,
    and with ``user``, logged in as that user: (process, client, token or ""). Killed at the
    end if still running (``terminate``: ended as by SIGTERM); its pipes stay readable."""
    from s7graph.web.bus.client import BusClient
    from s7graph.web.bus.session import open_session

    endpoint = f"unixsock-stream/{tmp_path}/bus.sock"
    proc = subprocess.Popen(
        [sys.executable, "-m", "s7graph", "run", *args, "--listen", endpoint],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    session = None
    try:
        assert proc.stdout is not None
        line = proc.stdout.readline()
        assert "on the bus" in line, (line, proc.stderr.read() if proc.stderr else "")
        session = open_session(connect=[endpoint])
        client = BusClient(session, "cpu1")
        if fb is not None:
            assert wait_until(lambda: client.state(fb) is not None, 30)
        token = ""
        if user is not None:
            login = client.login(user)
            assert login.ok, login.reason
            token = login.token
        yield proc, client, token
        client.close()
    finally:
        if session is not None:
            session.close()  # type: ignore[no-untyped-call]
        if proc.poll() is None:
            proc.terminate() if terminate else proc.kill()
        proc.wait(30)


def view_line(proc: subprocess.Popen[str], stderr: Path, timeout: float = 30) -> re.Match[str]:
    """The ``view URL (bus ENDPOINT)`` line ``s7graph run --web`` prints; its stdout is
    read by a thread from here on. Fails with its ``stderr`` file if it ends first."""
    lines: queue.Queue[str] = queue.Queue()
    assert proc.stdout is not None
    out = proc.stdout
    threading.Thread(target=lambda: [lines.put(line) for line in out], daemon=True).start()
    found = None
    deadline = time.monotonic() + timeout
    while found is None and time.monotonic() < deadline:
        try:
            found = re.search(r"view (\S+) \(bus (\S+)\)", lines.get(timeout=1))
        except queue.Empty:
            assert proc.poll() is None, stderr.read_text()
    assert found is not None, "no view URL printed"
    return found


@dataclass
class ProgramRun:
    """A program's CPU scanned by its runner, its scans going to a ``ProgramEdge`` on the bus
    at ``endpoint`` (TCP on loopback, no users file); ``store``: its state file (logins, the
    audit)."""

    cpu: Cpu
    runner: Runner
    store: StateStore
    endpoint: str


@contextmanager
def program_run(cpu: Cpu, tmp_path: Path, *, duration_s: float = 60) -> Iterator[ProgramRun]:
    """``cpu`` run on its own clock for at most ``duration_s`` s by a runner with the state
    file ``tmp_path / "state.sqlite"``, on the bus through a ``ProgramEdge``; shut down at
    the end."""
    from s7graph.engine.runner import Runner
    from s7graph.web.bus.gate import cpu_gate
    from s7graph.web.bus.session import BusEnds
    from s7graph.web.wiring.program_edge import ProgramEdge

    store = StateStore(tmp_path / "state.sqlite")
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    edge = ProgramEdge(cpu, ends=BusEnds(listen=[endpoint]), gate=cpu_gate(None, store))
    runner: Runner

    def on_record(record: ScanRecord) -> None:
        edge.on_record(record, stats=cpu.stats, runner=runner)

    runner = Runner(cpu, store=store, on_record=on_record, rt_priority=None, idle_gc=False)
    runner.startup()
    runner.start_thread(duration_s=duration_s)
    try:
        yield ProgramRun(cpu, runner, store, endpoint)
    finally:
        runner.shutdown("test ended")
        edge.close()
        store.close()


@contextmanager
def program_client(cpu: Cpu, tmp_path: Path) -> Iterator[tuple[ProgramRun, BusClient]]:
    """:func:`program_run` of ``cpu`` and a bus client of it, once the CPU answers."""
    from s7graph.web.bus.client import BusClient
    from s7graph.web.bus.session import open_session

    with (
        program_run(cpu, tmp_path) as run,
        open_session(connect=[run.endpoint]) as session,
        BusClient(session, "cpu1") as client,
    ):
        assert wait_until(lambda: client.status() is not None, 30)
        yield run, client


@dataclass
class ProgramPage:
    """A program's CPU scanned by its runner, on a bus, and the view serving its page;
    ``state``: its state file (logins, the audit)."""

    runner: Runner
    view: ViewSide
    state: Path


@contextmanager
def program_page(cpu: Cpu, tmp_path: Path) -> Iterator[ProgramPage]:
    """``cpu`` run on the system clock by a runner whose scans go to a ``ProgramEdge`` on
    TCP on loopback (no users file), with a ``ViewSide`` serving its page on a free port."""
    from s7graph.web.bus.session import BusEnds
    from s7graph.web.view.edge import ViewSide

    with program_run(cpu, tmp_path, duration_s=200) as run:
        view = ViewSide(cpu="cpu1", fb=None, ends=BusEnds(connect=[run.endpoint]), port=0)
        try:
            yield ProgramPage(run.runner, view, run.store.path)
        finally:
            view.close()
