"""A program of blocks on the bus (real processes): ``s7graph run PROGRAM.py --listen`` is
checked as a chart run is, answers ``s7graph status``, ``diag``, ``watch --address``,
``upload`` (nothing: a Python program), ``stop``, ``start`` and ``mres`` from a shell,
and an ``mres`` answered *applied* survives a SIGKILL; a STOP by an error is in the next
run's diagnostic buffer with its time, OB and priority class (docs/cli.md, "s7graph
diag"; docs/runtime.md, "Memory reset (MRES)")."""

from __future__ import annotations

import re
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from s7graph.web.bus.protocol import DiagBuffer, decode
from s7graph.web.cli import main
from tests.paths import ROOT
from tests.web.helpers import cpu_process, wait_until

pytestmark = pytest.mark.timeout(240)
DRILL = ROOT / "examples" / "drill"

PROGRAM = """
from s7graph.engine import ob, fb

CPU = {"max_cycle_ms": 5000}   # a busy test machine must not stop it by a time error

@fb(10, "Count", IN={"step": "INT"}, STAT={"n": "INT", "last": "ARRAY[1..2] OF INT"})
def count(ctx, db):
    db.n = min(int(db.n) + db.step, 32767)
    db.last = [db.n, db.n]

FAULT_AT = {fault_at}

@ob(1)
def main(ctx):
    out = ctx.call(count, 11, step=1)
    ctx.mem.set("MW10", min(int(ctx.mem.get("MW10")) + 1, 32767))   # retentive (MB0..MB15)
    if int(ctx.mem.get("MW10")) == FAULT_AT and not ctx.mem.get("M14.0"):
        ctx.mem.set("M14.0", True)                                      # once: retentive
        raise ZeroDivisionError("the fault of cycle 30")

def setup(cpu):
    cpu.create_instance_db(11, count)
"""


def s7graph(*args: str, check: int | None = 0) -> subprocess.CompletedProcess[str]:
    """``s7graph ARGS`` as a shell would run it; its exit status must be ``check``."""
    done = subprocess.run(
        [sys.executable, "-m", "s7graph", *args],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=60,
    )
    if check is not None:
        assert done.returncode == check, (args, done.stdout, done.stderr)
    return done


def _program(tmp_path: Path, *, fault_at: int = 0) -> list[str]:
    """The program (a ZeroDivisionError in cycle ``fault_at`` of its first run, 0: none)
    and its state file, for ``s7graph run``."""
    path = tmp_path / "count.py"
    path.write_text(textwrap.dedent(PROGRAM).replace("{fault_at}", str(fault_at)), encoding="utf-8")
    state = tmp_path / "count.sqlite"
    return [str(path), "--state", str(state), "--cycle-ms", "5", "--duration-s", "120"]


def _bus(tmp_path: Path) -> list[str]:
    return ["--connect", f"unixsock-stream/{tmp_path}/bus.sock"]


def test_a_program_on_the_bus_answers_the_shell_status_diag_watch_stop_mres_start(
    tmp_path: Path,
) -> None:
    args = _program(tmp_path)
    (tmp_path / "count.sqlite").unlink(missing_ok=True)
    with cpu_process(tmp_path, [*args, "--fresh"]) as (proc, client, _):
        bus = _bus(tmp_path)
        assert wait_until(lambda: (s := client.status()) is not None and s.cycle > 40, 30)
        status = s7graph("status", *bus).stdout
        assert status.startswith("CPU cpu1: RUN, cycle ") and "FBs none" in status
        assert s7graph("watch", *bus, "--duration-s", "5", check=2).stderr == (
            "s7graph: error: cpu1: this CPU runs no GRAPH FB: no steps to watch (--address "
            "watches operands)\n"
        )
        assert s7graph("upload", *bus, check=2).stderr == (
            "s7graph: error: cpu1: this CPU runs no GRAPH FB and no S7-SCL source: nothing "
            "to upload\n"
        )
        operands = "MW10:INT,DB11.n,DB11.last[2],DB9.x"
        watched = s7graph("watch", *bus, "--address", operands, "--duration-s", "1")
        lines = watched.stdout.splitlines()
        assert lines and lines[0].startswith("cycle ") and "DB9.x=?" in lines[0]
        assert "s7graph: DB9.x: DB9 is not loaded" in watched.stderr
        none = s7graph("watch", *bus, "--address", "MW10:FOO", "--duration-s", "1", check=2)
        assert none.stderr == (  # the operand named once, and why the watch ends
            "s7graph: MW10:FOO: unknown type 'FOO' after ':'\n"
            "s7graph: error: cpu1: no operand of --address can be read\n"
        )
        assert s7graph("mres", *bus, "--user", "eng", check=1).stderr.strip() == (
            "s7graph: mres refused: the CPU is in RUN: a memory reset needs STOP (stop it first)"
        )
        assert s7graph("stop", *bus, "--user", "eng").stdout.startswith(
            "s7graph: stop applied on cpu1 "
        )
        stopped = s7graph("status", *bus).stdout.splitlines()
        assert stopped[1] == "STOP: STOP by the switch (eng (unverified))"
        assert stopped[2].startswith("  STOP entry: 20") and "16#4304" in stopped[2]
        assert s7graph("mres", *bus, "--user", "eng").stdout.startswith(
            "s7graph: mres applied on cpu1 "
        )
        diag = s7graph("diag", *bus, "-n", "3").stdout.splitlines()
        assert diag[0] == "Diagnostic buffer of cpu1 (3 of 4 entries, newest first)"
        assert "16#4307" in diag[1] and "Memory reset started by a PG operation" in diag[1]
        assert re.match(r"  1  #\d+ +20", diag[1]) and "16#4304" in diag[2]
        addresses = ("--address", "MW10:INT", "--address", "DB11.n")  # several add up
        zero = s7graph("watch", *bus, *addresses, "--duration-s", "0.2")
        assert zero.stdout.splitlines()[0].endswith("STOP  MW10:INT=0  DB11.n=0")
        assert s7graph("start", *bus, "--user", "eng").returncode == 0
        assert wait_until(lambda: (s := client.status()) is not None and s.state == "RUN", 30)
        as_json = s7graph("diag", *bus, "--json", "-n", "2").stdout
        buffer = decode(as_json, DiagBuffer)
        assert [e.event_id for e in buffer.entries] == [0x4302, 0x4301]
        assert buffer.entries[1].ob == 100 and buffer.entries[1].priority == 27
        assert buffer.entries[0].wall_ms > 1_600_000_000_000  # a wall-clock time
        assert proc.poll() is None


def test_an_applied_mres_survives_sigkill_and_only_a_warm_restart_follows(
    tmp_path: Path,
) -> None:
    args = _program(tmp_path)
    bus = _bus(tmp_path)
    with cpu_process(tmp_path, args, user="eng") as (proc, client, token):
        assert wait_until(lambda: (s := client.status()) is not None and s.cycle > 10, 30)
        assert s7graph("stop", *bus, "--user", "eng").returncode == 0
        from s7graph.web.bus.protocol import Command

        reply = client.send(Command(op="mres", fb="cpu1", user="eng", token=token))
        assert reply.applied, reply.reason
        assert wait_until(lambda: _numbered(client.diag(100)).get(0x4307) is not None, 30)
        before = client.diag(100)
        proc.send_signal(signal.SIGKILL)
        proc.wait(30)
    hot = subprocess.run(
        [sys.executable, "-m", "s7graph", "run", *args, "--restart", "hot"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert hot.returncode == 2 and "a memory reset since" in hot.stderr, hot.stderr
    with cpu_process(tmp_path, args) as (_, client, _):
        assert wait_until(lambda: (s := client.status()) is not None and s.state == "RUN", 30)
        answer = client.watch(["MW10:INT", "DB11.n"])
        assert answer.error == "" and answer.values[0].value == answer.values[1].value
        assert 0 < int(answer.values[1].value or 0) == answer.cycle  # counted from 0 again
        buffer = client.diag(20)
        assert buffer is not None
        reset = next(e for e in buffer.entries if e.event_id == 0x4307)
        assert reset.wall_ms > 1_600_000_000_000  # read back with its time from the last run
        # every entry read before the SIGKILL is read back under its number, the new ones
        # numbered on from there
        assert before is not None
        assert wait_until(lambda: (b := client.diag(100)) is not None and b.total > before.total)
        again = {e.number: e for e in (client.diag(100) or DiagBuffer()).entries}
        for e in before.entries:
            assert again[e.number] == e
        numbers = sorted(again)
        assert numbers == list(range(numbers[0], numbers[-1] + 1))
        assert before.total == before.entries[0].number
        assert {again[n].event_id for n in numbers if n > before.total} >= {0x4301, 0x4302}


def test_a_stop_by_an_error_is_in_the_next_runs_diagnostic_buffer_with_its_cause(
    tmp_path: Path,
) -> None:
    args = _program(tmp_path, fault_at=30)
    first = subprocess.run(
        [sys.executable, "-m", "s7graph", "run", *args],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert first.returncode == 1 and "ZeroDivisionError: the fault of cycle 30" in first.stderr
    with cpu_process(tmp_path, args) as (_, client, _):
        assert wait_until(lambda: (s := client.status()) is not None and s.state == "RUN", 30)
        lines = s7graph("diag", *_bus(tmp_path)).stdout.splitlines()
    stop = next(k for k, line in enumerate(lines) if "16#4562" in line)
    cause = lines[stop + 1]
    assert "STOP caused by a programming error (OB121 not loaded)" in lines[stop]
    assert (
        "16#25FF  OB121 PK1" in cause and "OB1: ZeroDivisionError: the fault of cycle 30" in cause
    )
    assert cause.split()[1].startswith("#") and cause.split()[2].startswith(
        "20"
    )  # its date: read back from the state file
    assert any("16#4302" in line for line in lines[:stop])  # this run's start is newer


def _numbered(buffer: DiagBuffer | None) -> dict[int, int]:
    """Each event ID of ``buffer`` with the number of its newest entry."""
    out: dict[int, int] = {}
    for e in reversed(buffer.entries if buffer is not None else []):
        out[e.event_id] = e.number
    return out


def test_a_program_on_the_bus_is_refused_a_listen_a_chart_would_be_refused(
    tmp_path: Path,
) -> None:
    path = Path(_program(tmp_path)[0])
    chart = s7graph("run", str(DRILL / "drill.s7g"), "--listen", "tcp/0.0.0.0:7461", check=2)
    program = s7graph("run", str(path), "--listen", "tcp/0.0.0.0:7461", check=2)
    assert program.stderr == chart.stderr
    assert "--listen tcp/0.0.0.0:7461 is not loopback" in program.stderr
    assert s7graph("run", str(path), "--listen", "bus.sock", check=2).stderr.strip() == (
        "s7graph: error: endpoint 'bus.sock': write it as PROTOCOL/ADDRESS, e.g. tcp/127.0.0.1:7447"
    )
    assert (
        "--plant is for a chart" in s7graph("run", str(path), "--plant", str(path), check=2).stderr
    )
    other = tmp_path / "count.txt"
    other.write_text("x")
    refused = s7graph("run", str(other), check=2).stderr.strip()
    assert refused == (
        f"s7graph: error: {other}: not a program s7graph runs (.py, an S7-SCL program .scl, or "
        "a chart .s7g)"
    )


def test_the_shell_says_in_one_line_what_is_wrong_with_diag_and_watch() -> None:
    none = ["--connect", "tcp/127.0.0.1:9"]
    assert s7graph("diag", *none, "-n", "0", check=2).stderr.strip() == (
        "s7graph: error: Invalid value for '-n': from 1 to 1,000, not 0 (see s7graph diag --help)"
    )
    refused = s7graph("watch", "--address", " , ", *none, check=2).stderr
    assert "'--address': give the operands to watch, e.g. MW0,Q4.0,DB20.avg" in refused
    both = s7graph("watch", "--address", "MW0", "--fb", "X", *none, check=2).stderr
    assert "--address watches operands, --fb an FB's steps: not both" in both


@pytest.mark.parametrize(
    ("words", "reason"),
    [
        (["watch", "--address", "MW0", "--interval-ms", "nan"], "from 20 to 3,600,000 ms, not nan"),
        (["watch", "--address", "MW0", "--interval-ms", "5"], "from 20 to 3,600,000 ms, not 5"),
        (["watch", "--address", "M\udcff"], "'--address': not valid UTF-8 text"),
        (["watch", "--duration-s", "1e300"], "from 0 to 1,000,000,000 s, not 1e+300"),
        (["watch", "--duration-s", "-1"], "from 0 to 1,000,000,000 s, not -1"),
        (["web", "--duration-s", "inf"], "from 0 to 1,000,000,000 s, not inf"),
        (["opcua", "--duration-s", "nan"], "from 0 to 1,000,000,000 s, not nan"),
        (["router", "--duration-s", "-5"], "from 0 to 1,000,000,000 s, not -5"),
        (["run", "x.s7g", "--duration-s", "inf"], "from 0 to 1,000,000,000 s, not inf"),
    ],
)
def test_a_time_or_text_out_of_range_is_a_usage_error_before_the_bus(
    words: list[str], reason: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """A duration or interval that no timer can wait (NaN, infinity, 1e300: Python's own
    ``OverflowError``) or text that is not UTF-8: one line, exit 2, nothing joined."""
    assert main([*words, "--connect", "tcp/127.0.0.1:9"]) == 2
    err = capsys.readouterr().err
    assert reason in err and err.count("\n") == 1 and "Traceback" not in err


def test_a_charts_cpu_answers_diag_and_mres_initializes_its_sequencer(tmp_path: Path) -> None:
    args = [
        str(DRILL / "drill.s7g"),
        "--symbols",
        str(DRILL / "symbols.txt"),
        "--state",
        str(tmp_path / "drill.sqlite"),
        "--duration-s",
        "120",
        "--max-cycle-ms",  # the bus is tested, not the watchdog: a loaded CI's slow scan
        "5000",
    ]
    fb = "Seq_drill"
    with cpu_process(tmp_path, args, fb=fb, user="eng") as (_, client, token):
        from s7graph.web.bus.protocol import Command

        def send(op: str, **given: object) -> None:
            made = Command(op=op, fb=fb, user="eng", token=token, args=given)  # type: ignore[arg-type]
            reply = client.send(made)
            assert reply.applied, (op, reply.reason)

        send("mode", mode="MAN")
        send("step_on", step=3)
        assert wait_until(lambda: (s := client.state(fb)) is not None and 3 in s.active, 30)
        send("stop")
        send("mres")
        assert s7graph("watch", *_bus(tmp_path), "--address", "DB1.S_NO", "--duration-s", "0.1")
        nope = s7graph("watch", *_bus(tmp_path), "--fb", "../x", "--duration-s", "5", check=2)
        assert (
            nope.stderr == "s7graph: error: cpu1: this CPU runs no FB '../x'; it runs Seq_drill\n"
        )
        send("start")
        assert wait_until(lambda: (s := client.state(fb)) is not None and s.active == [1], 30)
        state = client.state(fb)
        assert state is not None and state.mode == "AUTO"  # initial values: mode, steps
        lines = s7graph("diag", *_bus(tmp_path), "-n", "10").stdout
        assert "16#4307" in lines and "16#4304" in lines
        cleared = next(line for line in lines.splitlines() if "16#5F01" in line)
        assert "memory reset clears Seq_drill/DB1, in S1 'Ready'" in cleared  # written before
        assert "S3 'Coolant'" in cleared and "(mode MAN)" in cleared
