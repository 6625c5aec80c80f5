"""Online change through the bus into a real ``s7graph run`` process: for a few seeds, random
sequences of edits from the editor's table of operations are downloaded (with every choice
for removed active steps) between manual step commands. The CPU never goes to STOP, every
download is answered as a local simulation of the same downloads says (applied, or refused
for removed active steps without a choice), and the active steps the CPU publishes are
those of the local simulation.

The sequencer runs in manual mode (MAN: steps switch by command only, not by transitions),
so its position does not depend on how many scans the process made between two commands."""

from __future__ import annotations

import random
import subprocess
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest

from s7graph.engine.clock import VirtualClock
from s7graph.sequencer.change.diff import summarize
from s7graph.sequencer.change.edit import Session, make_edit
from s7graph.sequencer.change.online import SwapRefused, swap
from s7graph.sequencer.text.format import format_chart
from s7graph.sequencer.text.parse import parse_chart
from s7graph.web.bus.client import BusClient
from s7graph.web.bus.protocol import Command, CommandReply
from s7graph.web.harness.session import ChartSession, compile_text
from tests.sequencer.change.test_online_change_properties import EDITS, ROWS, TEXTS, _numbers
from tests.sequencer.helpers import CHARTS
from tests.web.helpers import cpu_process, wait_until

pytestmark = pytest.mark.timeout(120)
DOWNLOADS = 12  # per seed
NAME_KEPT = [op for op in EDITS if op.name != "set_source"]  # a download keeps the block


def _edit(rng: random.Random, editor: Session) -> Session:
    """One random edit from the table (a refused one changes nothing)."""
    op = rng.choice(NAME_KEPT)
    c = editor.chart
    args: dict[str, Any] = {}
    for a in op.arguments:
        if a.type == "RowFields":
            args[a.name] = rng.choice(ROWS)
        elif a.type == "bool":
            args[a.name] = rng.random() < 0.5
        elif a.type == "str":
            args[a.name] = rng.choice(TEXTS[a.name])
        elif a.type.endswith("None") and rng.random() < 0.3:
            args[a.name] = None
        else:
            args[a.name] = rng.choice(_numbers(c, a.name))
    return editor.apply(make_edit(op.name, args))


@contextmanager
def running(
    tmp_path: Path, text: str, stderr: list[str]
) -> Iterator[tuple[subprocess.Popen[str], BusClient]]:
    """``s7graph run`` of the chart ``text`` as a process on a unix socket, a client; what
    the process wrote to stderr into ``stderr`` once it ended."""
    path = tmp_path / "chart.s7g"
    path.write_text(text, encoding="utf-8")
    # downloads are tested here, not a loaded machine's cycle time (a compile never holds
    # a scan up: test_compile_process.py): a generous maximum cycle time
    args = [str(path), "--state", str(tmp_path / "s.sqlite"), "--duration-s", "110"]
    args += ["--max-cycle-ms", "1000"]
    with cpu_process(tmp_path, args, terminate=True) as (proc, client, _):
        yield proc, client
    if proc.stderr is not None:
        stderr.append(proc.stderr.read())
    for pipe in (proc.stdout, proc.stderr):
        if pipe is not None:
            pipe.close()


class Local:
    """The same chart and downloads on a virtual clock: what the CPU must show."""

    def __init__(self, text: str) -> None:
        cc, table = compile_text(text, "chart.s7g")
        self.session = ChartSession(cc, table, VirtualClock())
        self.session.start()

    def command(self, pin: str, step: int | None = None) -> None:
        self.session.graph.command(pin, step)
        self.scan()

    def scan(self, n: int = 3) -> None:
        for _ in range(n):
            self.session.clock.advance(10)  # type: ignore[attr-defined]
            assert self.session.scan().mode.name == "RUN"

    def download(self, text: str, removed: str | None) -> bool:
        new, table = compile_text(text, "chart.s7g", self.session.symbols)
        try:
            swap(self.session.graph, new, self.session.cpu, removed=removed)
        except SwapRefused:
            return False
        self.session.symbols = table  # the chart is the GraphFB's own
        self.scan()
        return True

    @property
    def active(self) -> list[int]:
        g = self.session.graph
        return sorted(g.cc.step_numbers[i] for i in g.state.active)


@pytest.mark.parametrize(
    ("seed", "start"), [(1, "linear"), (2, "simultaneous"), (3, "two_sequencers")]
)
def test_downloads_through_the_bus_keep_the_cpu_running_as_a_local_simulation(
    tmp_path: Path, seed: int, start: str
) -> None:
    rng = random.Random(seed)
    text = (CHARTS / f"{start}.s7g").read_text(encoding="utf-8")
    editor = Session.open(parse_chart(text, "chart.s7g"))
    fb = editor.chart.name
    local = Local(text)
    stderr: list[str] = []
    with running(tmp_path, text, stderr) as (proc, client):
        assert wait_until(lambda: client.state(fb) is not None, 30)
        token = client.login("eng").token

        def send(op: str, **args: object) -> CommandReply:
            command = Command(op=op, fb=fb, user="eng", token=token, args=args)  # type: ignore[arg-type]
            return client.send(command, timeout=20)

        def published() -> list[int] | None:
            update = client.state(fb)
            return None if update is None else sorted(update.active)

        def agrees() -> None:
            assert wait_until(lambda: published() == local.active, 10), (
                published(),
                local.active,
                format_chart(editor.chart),
            )
            status = client.status()
            assert proc.poll() is None and status is not None and status.state == "RUN"

        assert send("mode", mode="MAN").applied
        local.command("SW_MAN")
        agrees()
        applied = 0
        history: list[str] = []  # the texts the downloads replaced, for Undo download
        for _ in range(DOWNLOADS):
            running_chart = editor.chart
            removed = rng.choice([None, "keep", "init"])
            chosen = {"removed": removed} if removed else {}
            undo = bool(history) and rng.random() < 0.25
            if undo:  # Undo download: the same swap, the other way round
                source = history[-1]
                reply = send("undo_download", **chosen)
                editor = Session.open(parse_chart(source, "chart.s7g"))
            else:
                for _ in range(rng.randint(1, 4)):
                    editor = _edit(rng, editor)
                if summarize(running_chart, editor.chart, ()).unchanged:
                    continue  # refused: nothing changes
                source = format_chart(editor.chart)
                reply = send("download", source=source, **chosen)
            assert reply.applied == local.download(source, removed), reply.reason
            applied += reply.applied
            if not reply.applied:
                assert "keep" in reply.reason, reply.reason
                editor = Session.open(running_chart)
            elif undo:
                history.pop()
            else:
                history.append(format_chart(running_chart))
            agrees()
            for _ in range(rng.randint(0, 3)):
                on = rng.random() < 0.6 or not local.active
                steps = local.session.graph.cc.step_numbers
                pick = [n for n in steps if (n in local.active) != on]
                if not pick:
                    continue
                step = rng.choice(pick)
                op, pin = ("step_on", "S_ON") if on else ("step_off", "S_OFF")
                reply = send(op, step=step)
                assert reply.applied, reply.reason
                local.command(pin, step)
                agrees()
        assert applied >= DOWNLOADS // 2
    assert "Traceback" not in stderr[0], stderr[0]
