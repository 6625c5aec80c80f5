"""Every command of the role table that acts on the CPU, answered *applied*, survives a
SIGKILL right after the reply: ``s7graph run`` of the drill chart (no plant: its inputs
stay as forced) is a real process on the bus, killed the moment each reply arrives, and
restarted with ``--restart hot`` from the state file it left; the restarted CPU shows the
effect (the state file holds it and its audit row).

A download rewrites the chart file and the instance DB's row with the new chart's
fingerprint, so the hot restart resumes the new chart in the step it was in (a warm
restart would initialize it); ``undo_download`` likewise puts the old one back."""

from __future__ import annotations

import resource
import shutil
import sqlite3
import subprocess
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import pytest

from s7graph.sequencer.change.carry import fingerprint
from s7graph.web.access.audit import read_audit
from s7graph.web.bus.client import BusClient
from s7graph.web.bus.protocol import Command, CommandReply, StepStateUpdate
from s7graph.web.harness.session import load_chart
from tests.paths import ROOT
from tests.real_process import descendants, kill_run
from tests.web.helpers import cpu_process, wait_until

pytestmark = pytest.mark.timeout(600)
DRILL = ROOT / "examples" / "drill"
FB = "Seq_drill"
USER = "tess (unverified)"
S2_SV = "Seq_drill/DB1/S2/SV"


@dataclass
class Cpu:
    """One run of the drill chart on the bus, a client logged in as the demo engineer."""

    proc: subprocess.Popen[str]
    client: BusClient
    token: str

    def command(self, op: str, **args: object) -> Command:
        return Command(op=op, fb=FB, user="tess", token=self.token, args=args)  # type: ignore[arg-type]

    def send(self, op: str, **args: object) -> CommandReply:
        reply = self.client.send(self.command(op, **args))
        assert reply.applied, (op, args, reply.reason)
        return reply

    def send_until_applied(self, op: str, **args: object) -> CommandReply:
        """Send until applied (a refusal changes nothing): the FB must first have seen
        the inputs that make ``op`` act."""
        replies: list[CommandReply] = []

        def applied() -> bool:
            replies.append(self.client.send(self.command(op, **args)))
            return replies[-1].applied

        assert wait_until(applied, 20, poll=0.1), replies[-1].reason
        return replies[-1]

    def kill_on(self, op: str, **args: object) -> CommandReply:
        """Send ``op`` and SIGKILL the CPU the moment its reply arrives."""
        reply = self.client.send(self.command(op, **args))
        kill_run(self.proc)
        assert reply.applied, (op, args, reply.reason)
        return reply

    def state(self) -> StepStateUpdate:
        assert wait_until(lambda: self.client.state(FB) is not None, 30)
        snapshot = self.client.state(FB)
        assert snapshot is not None
        return snapshot

    def until(self, what: Callable[[StepStateUpdate], bool]) -> StepStateUpdate:
        assert wait_until(lambda: what(self.state()), 20), self.state()
        return self.state()


@contextmanager
def run(tmp_path: Path) -> Iterator[Cpu]:
    """The drill chart of ``tmp_path`` restarted hot from its state file."""
    args = [
        str(tmp_path / "drill.s7g"),
        "--symbols",
        str(tmp_path / "symbols.txt"),
        "--state",
        str(tmp_path / "drill.sqlite"),
        "--restart",
        "hot",
        "--duration-s",
        "300",
        "--max-cycle-ms",
        "5000",
    ]
    with cpu_process(tmp_path, args, fb=FB, user="tess") as (proc, client, token):
        yield Cpu(proc, client, token)
    for stream in (proc.stdout, proc.stderr):
        if stream is not None:
            if stream is proc.stderr:
                assert "Traceback" not in stream.read()
            stream.close()


@pytest.fixture
def drill(tmp_path: Path) -> Path:
    """A copy of the drill example: a download rewrites its chart file."""
    for name in ("drill.s7g", "symbols.txt"):
        shutil.copy(DRILL / name, tmp_path / name)
    return tmp_path


def _acknowledged(state: Path, msg_id: str) -> int:
    """How many rows of the alarm log say ``msg_id`` was acknowledged by the test's user."""
    with sqlite3.connect(f"file:{state}?mode=ro", uri=True) as con:
        rows = con.execute(
            "SELECT count(*) FROM alarms WHERE key=? AND state='acknowledged' AND user=?",
            (msg_id, USER),
        ).fetchone()
    con.close()
    return int(rows[0])


def _audited(state: Path) -> list[tuple[str, str]]:
    return [(r.op, r.outcome) for r in read_audit(state) if r.user == USER]


def _row_fingerprint(state: Path) -> str:
    with sqlite3.connect(f"file:{state}?mode=ro", uri=True) as con:
        (value,) = con.execute("SELECT fingerprint FROM instances WHERE number=1").fetchone()
    con.close()
    return str(value)


def test_every_applied_command_survives_sigkill_and_a_hot_restart(drill: Path) -> None:
    state = drill / "drill.sqlite"
    with run(drill) as cpu:
        assert cpu.state().active == [1]
        cpu.kill_on("mode", mode="MAN")
    with run(drill) as cpu:
        assert cpu.state().mode == "MAN"
        cpu.kill_on("step_on", step=2)
    with run(drill) as cpu:
        assert cpu.state().active == [1, 2]
        cpu.kill_on("step_off", step=1)
    with run(drill) as cpu:
        assert cpu.state().active == [2]
        cpu.until(lambda s: s.latched == [2])  # S2.U passes 500 ms: its message comes
        before = _acknowledged(state, S2_SV)
        reply = cpu.kill_on("ack_msg", msg_id=S2_SV)
        assert "the cause of S2 persists" in reply.reason  # in MAN, S2.U stays over 500 ms
    assert _acknowledged(state, S2_SV) == before + 1
    with run(drill) as cpu:
        history = cpu.client.history()
        assert history is not None
        assert [e for e in history.entries if e.msg_id == S2_SV and e.user == USER]
        cpu.send("force", address="I0.0", value=True)  # Dr_mot_running
        cpu.kill_on("force", address="I0.4", value=True)  # Cl_press_ok: T3 is satisfied
    with run(drill) as cpu:
        forces = cpu.client.forces()
        assert forces is not None
        assert {(f.address, f.value) for f in forces.entries} == {
            ("I0.0", "TRUE"),
            ("I0.4", "TRUE"),
        }
        assert cpu.until(lambda s: s.latched == [2]).values["Cl_press_ok"] is True
        cpu.send("mode", mode="AUTO")
        cpu.send_until_applied("ack_step", step=2)  # released, S2 switches by T3
        kill_run(cpu.proc)
    with run(drill) as cpu:
        assert (cpu.state().active, cpu.state().latched) == ([4], [])
        cpu.send("mode", mode="MAN")
        cpu.kill_on("set_steps", steps=[2])  # S4 leaves, S2 enters: one call
    with run(drill) as cpu:
        assert (cpu.state().active, cpu.state().mode) == ([2], "MAN")
        cpu.until(lambda s: s.latched == [2])
        cpu.send("mode", mode="AUTO")
        before = _acknowledged(state, S2_SV)
        cpu.send_until_applied("ack")
        kill_run(cpu.proc)
    assert _acknowledged(state, S2_SV) == before + 1  # ACK_EF acknowledged it, as tess
    with run(drill) as cpu:
        assert (cpu.state().active, cpu.state().latched) == ([4], [])
        cpu.send("force", all=True)
        cpu.kill_on("init")
    with run(drill) as cpu:
        assert cpu.state().active == [1]
        cpu.kill_on("off")
    with run(drill) as cpu:
        assert cpu.state().active == []
        cpu.send("init")
        cpu.send("mode", mode="TOP")
        cpu.until(lambda s: s.active == [1] and s.mode == "TOP")
        cpu.kill_on("t_push")  # T1 is not satisfied: TOP switches it on the push
    with run(drill) as cpu:
        assert cpu.state().active == [2]
        cpu.kill_on("halt", on=True)
    with run(drill) as cpu:
        assert cpu.state().overrides == {"HALT_SQ": True} and cpu.state().halted
        cpu.kill_on("en_il", on=False)
    with run(drill) as cpu:
        assert cpu.state().overrides == {"HALT_SQ": True, "EN_IL": False}
        cpu.kill_on("en_sv", on=False)
    with run(drill) as cpu:
        snapshot = cpu.state()
        assert snapshot.overrides == {"HALT_SQ": True, "EN_IL": False, "EN_SV": False}
        assert not snapshot.il_enabled and not snapshot.sv_enabled
        assert snapshot.active == [2] and snapshot.mode == "TOP"
    ops = [
        "mode",
        "step_on",
        "step_off",
        "set_steps",
        "ack_msg",
        "force",
        "ack_step",
        "ack",
        "init",
        "off",
        "t_push",
        "halt",
        "en_il",
        "en_sv",
    ]
    assert {op for op, outcome in _audited(state) if outcome == "applied"} >= set(ops)


def test_after_a_download_a_hot_restart_resumes_the_new_chart(drill: Path) -> None:
    state, path = drill / "drill.sqlite", drill / "drill.s7g"
    old = path.read_text(encoding="utf-8")
    new = old.replace("SUPERVISION := S3.U > T#2S;", "SUPERVISION := S3.U > T#3S;")
    newer = new.replace("T#3S", "T#4S")
    with run(drill) as cpu:
        cpu.send("mode", mode="MAN")
        cpu.send("step_on", step=4)
        cpu.send("step_off", step=1)
        cpu.until(lambda s: s.active == [4])
        assert cpu.kill_on("download", source=new, base=1).version == 2
    assert path.read_text(encoding="utf-8") == new
    assert _row_fingerprint(state) == fingerprint(
        load_chart(path, drill / "symbols.txt")[0]
    )  # the new chart's
    with run(drill) as cpu:
        assert (cpu.state().active, cpu.state().mode) == ([4], "MAN")  # hot: not initialized
        source = cpu.client.source(FB)
        assert source is not None and source.text == new
        assert cpu.send("download", source=newer, base=1).version == 2
        assert cpu.kill_on("undo_download", base=2).version == 3
    assert path.read_text(encoding="utf-8") == new  # the chart before the last download
    assert _row_fingerprint(state) == fingerprint(load_chart(path, drill / "symbols.txt")[0])
    with run(drill) as cpu:
        assert (cpu.state().active, cpu.state().mode) == ([4], "MAN")
        source = cpu.client.source(FB)
        assert source is not None and source.text == new
    audited = _audited(state)
    assert ("download", "applied") in audited and ("undo_download", "applied") in audited


def test_a_download_the_disk_has_not_confirmed_is_answered_not_confirmed(drill: Path) -> None:
    """Another connection holds the state file's lock (a backup tool, a stalled disk): the
    CPU runs the new chart, but the reply does not say *applied* before the commit."""
    state, path = drill / "drill.sqlite", drill / "drill.s7g"
    new = path.read_text(encoding="utf-8").replace("T#2S;", "T#3S;")
    with run(drill) as cpu:
        lock = sqlite3.connect(state, timeout=10, isolation_level=None)
        lock.execute("BEGIN IMMEDIATE")
        try:
            reply = cpu.client.send(cpu.command("download", source=new, base=1), timeout=20)
        finally:
            lock.rollback()
            lock.close()
        assert not reply.applied
        assert reply.reason.startswith("not confirmed: version 2 runs (was 1)"), reply.reason
        assert reply.reason.endswith("but the state file has not committed it within 5 s")
        assert wait_until(lambda: ("download", "applied") in _audited(state), 20)
        kill_run(cpu.proc)
    assert _row_fingerprint(state) == fingerprint(load_chart(path, drill / "symbols.txt")[0])


def _still(state: Path, quiet_s: float = 1.5) -> Callable[[], bool]:
    """A poll: whether the state file's write-ahead log has not grown for ``quiet_s``
    (three of the running chart's 500 ms time marks): nothing is being committed."""
    seen: list[tuple[float, bytes]] = []

    def still() -> bool:
        now, head = time.monotonic(), Path(f"{state}-shm").read_bytes()[:48]
        if not seen or seen[-1][1] != head:
            seen.append((now, head))
        return now - seen[-1][0] >= quiet_s

    return still


# A chart this short fits below the limit the test sets, so its file is written and the
# download reaches the commit; no frame of the state file's log does (see the test).
SHORT = """FUNCTION_BLOCK "Seq_drill" FB 1 DB 1
SEQUENCE 1
  INITIAL_STEP S1: END_STEP
  STEP S2: END_STEP
  TRANSITION T1 FROM S1 TO S2 := "Start_button";
  TRANSITION T2 FROM S2 TO S1 := S2.T >= T#2S;
END_SEQUENCE
END_FUNCTION_BLOCK
"""


def test_a_download_the_disk_cannot_take_is_answered_not_confirmed_saying_why(
    drill: Path,
) -> None:
    """The disk full once the chart file is written (here: the CPU's files may not grow
    past one page of the state file): the reply says so at once, not that the commit is
    late.

    RLIMIT_FSIZE refuses a write at or past the limit, wherever the file ends. A frame of
    SQLite's write-ahead log (a 24-byte head and a page) starts after the log's 32-byte
    head, so even the first frame of a log started over from its head ends past one page:
    with the limit at one page, no commit can be written, wherever the log is; the short
    chart (old and new) is written below it. The CPU is in STOP first, so that no commit
    but the download's comes after the limit: a running chart commits its step times
    every 500 ms, and a commit that fails before the download ends the run."""
    state, path = drill / "drill.sqlite", drill / "drill.s7g"
    path.write_text(SHORT, encoding="utf-8")
    new = SHORT.replace("T#2S;", "T#3S;")
    with run(drill) as cpu:
        cpu.send("stop")
        assert wait_until(_still(state), 20)
        with sqlite3.connect(f"file:{state}?mode=ro", uri=True) as con:
            (room,) = con.execute("PRAGMA page_size").fetchone()
        con.close()
        assert len(new.encode()) < room and len(SHORT.encode()) < room
        for pid in descendants(cpu.proc.pid):
            resource.prlimit(pid, resource.RLIMIT_FSIZE, (room, room))
        reply = cpu.client.send(cpu.command("download", source=new, base=1), timeout=20)
        assert not reply.applied
        assert reply.reason.startswith("not confirmed: version 2 runs (was 1)"), reply.reason
        assert f"{state}: cannot write the state: " in reply.reason
        assert "within 5 s" not in reply.reason
        kill_run(cpu.proc)
