"""``s7graph run`` and its state file: a file it cannot trust is refused in one line naming
the file and the problem, with the way out (``--fresh``), exit 2; ``--fresh`` keeps the old
file as ``FILE.old-N``; ``--restart`` and ``CPU = {"restart": …}`` choose the startup; a
state file that cannot be written (a full disk) stops the CPU with one line, exit 1 —
with the view as without."""

from __future__ import annotations

import errno
import os
import resource
import signal
import sqlite3
import subprocess
import sys
import textwrap
import threading
from pathlib import Path

import pytest

from s7graph.engine.persistence import Batch, StateStore
from s7graph.web.cli import main
from tests.paths import ROOT
from tests.web.helpers import free_port

DRILL = ROOT / "examples" / "drill"
CHART = ["run", str(DRILL / "drill.s7g"), "--symbols", str(DRILL / "symbols.txt")]


def _errors(err: str) -> list[str]:
    return [line for line in err.splitlines() if line.startswith("s7graph: error")]


def test_an_empty_state_file_is_refused_in_one_line_pointing_to_fresh(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    state = tmp_path / "drill.sqlite"
    state.write_bytes(b"")
    assert main([*CHART, "--state", str(state), "--duration-s", "0.1"]) == 2
    err = capsys.readouterr().err
    assert err.splitlines() == [
        f"s7graph: error: {state}: empty file (0 bytes), not a state file; start anew with "
        f"--fresh (keeps this file as {state}.old-N)"
    ]


def test_the_state_file_of_another_chart_is_refused_and_kept(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    state = tmp_path / "s.sqlite"
    mixing = ROOT / "examples" / "mixing"
    assert (
        main(
            [
                "run",
                str(mixing / "mixing.s7g"),
                "--symbols",
                str(mixing / "symbols.txt"),
                "--state",
                str(state),
                "--duration-s",
                "0.1",
            ]
        )
        == 0
    )
    capsys.readouterr()
    assert main([*CHART, "--state", str(state), "--duration-s", "0.1"]) == 2
    (line,) = capsys.readouterr().err.splitlines()
    assert line.startswith(
        f"s7graph: error: {state}: the state of another program: the chart mixing.s7g's, not "
        "the chart drill.s7g's; run drill.s7g with a state file of its own (--state FILE)"
    )
    assert "--fresh" in line
    with sqlite3.connect(state) as con:
        assert con.execute("SELECT count(*) FROM instances").fetchone() == (1,)
    con.close()


def test_fresh_keeps_the_old_file_aside_and_starts_anew(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    state = tmp_path / "drill.sqlite"
    state.write_bytes(b"not a database at all")
    assert main([*CHART, "--state", str(state), "--duration-s", "0.1", "--fresh"]) == 0
    assert (tmp_path / "drill.sqlite.old-1").read_bytes() == b"not a database at all"
    assert main([*CHART, "--state", str(state), "--duration-s", "0.1", "--fresh"]) == 0
    assert (tmp_path / "drill.sqlite.old-2").exists()
    err = capsys.readouterr().err
    assert f"fresh start, state in {state}; the old file is kept as {state}.old-2" in err


def test_the_state_file_is_its_owners_alone_and_one_others_could_read_is_made_so(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """It holds the audit (who did what, from where): made mode 600 with its -wal and -shm
    whatever the umask; one found readable by others is made so, and the run says it."""
    state = tmp_path / "drill.sqlite"
    assert main([*CHART, "--state", str(state), "--duration-s", "0.1"]) == 0
    made = [p for p in tmp_path.iterdir() if p.name.startswith("drill.sqlite")]
    assert made and {oct(p.stat().st_mode & 0o777) for p in made} == {"0o600"}
    assert "made its owner's alone" not in capsys.readouterr().err
    for p in made:
        p.chmod(0o644)
    assert main([*CHART, "--state", str(state), "--duration-s", "0.1"]) == 0
    err = capsys.readouterr().err
    assert f"warm restart from {state}; others could read it: made its owner's alone" in err
    assert {oct(p.stat().st_mode & 0o777) for p in made if p.exists()} == {"0o600"}


def test_restart_must_be_warm_hot_or_cold(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main([*CHART, "--state", str(tmp_path / "s.sqlite"), "--restart", "tepid"]) == 2
    assert "--restart must be warm, hot or cold" in capsys.readouterr().err


def test_a_programs_cpu_dict_chooses_its_restart(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    program = tmp_path / "prog.py"
    program.write_text(
        textwrap.dedent("""
        from s7graph.engine import ob
        CPU = {"restart": "hot"}

        @ob(1)
        def main(ctx):
            ctx.mem.set("MW100", ctx.mem.get("MW100") + 1)   # not retentive
    """)
    )
    state = str(tmp_path / "s.sqlite")
    for _ in range(2):
        assert main(["run", str(program), "--state", state, "--duration-s", "0.2"]) == 0
    err = capsys.readouterr().err
    assert f"in RUN (hot restart from {state})" in err
    with sqlite3.connect(state) as con:
        assert con.execute("SELECT value FROM meta WHERE key='last_restart'").fetchone() == ("hot",)
    con.close()


def _no_room(limit: int) -> None:
    """In the child: files may not grow beyond ``limit`` bytes (as on a full disk)."""
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))


@pytest.mark.timeout(120)
@pytest.mark.parametrize("web", [False, True], ids=["alone", "with the view"])
def test_a_state_file_that_cannot_grow_stops_the_run_with_one_line(
    tmp_path: Path, web: bool
) -> None:
    state = tmp_path / "drill.sqlite"
    # the disk fills; a loaded CI machine must not stop the CPU by a time error first
    cmd = [
        sys.executable,
        "-m",
        "s7graph",
        *CHART,
        "--plant",
        str(DRILL / "demo_plant.py"),
        "--state",
        str(state),
        "--duration-s",
        "60",
        "--max-cycle-ms",
        "5000",
    ]
    if web:
        cmd += ["--web", "--port", str(free_port())]
    # room for the start (with the view, the audit store's tables share the file and its
    # write-ahead log), none for an hour of running
    room = 80_000 if web else 40_000
    proc = subprocess.run(
        cmd,
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=100,
        preexec_fn=lambda: _no_room(room),
    )
    assert proc.returncode == 1, proc.stderr
    (line,) = _errors(proc.stderr)  # said when it stopped, not again at the end
    assert line.startswith(
        "s7graph: error: drill.s7g (Seq_drill): the CPU went to STOP: the state file could not "
        "be written: "
    )
    assert "disk I/O error" in line or "disk full (database or disk is full" in line
    assert line.endswith(f", {state}") and "Traceback" not in proc.stderr
    assert (
        f"s7graph: note: the STOP is recorded in {state}" in proc.stderr
        or f"s7graph: note: the STOP could not be recorded in {state} either" in proc.stderr
    )


def test_the_next_start_says_the_last_run_stopped_on_a_full_disk(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """The writer's first commit meets a full disk (ENOSPC); the disk has room again by the
    end of the run, which writes the STOP's entry into the file: the next start says why."""
    state = tmp_path / "drill.sqlite"
    write = StateStore.write
    failed: list[bool] = []

    def full_once(store: StateStore, batch: Batch) -> None:
        if threading.current_thread().name == "s7graph-writer" and not failed:
            failed.append(True)
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(store.path))
        write(store, batch)

    monkeypatch.setattr(StateStore, "write", full_once)
    why = f"the state file could not be written: disk full (No space left on device), {state}"
    assert main([*CHART, "--state", str(state), "--duration-s", "30"]) == 1
    err = capsys.readouterr().err
    assert _errors(err) == [f"s7graph: error: drill.s7g (Seq_drill): the CPU went to STOP: {why}"]
    assert f"s7graph: note: the STOP is recorded in {state}: its next start says why" in err
    monkeypatch.undo()
    assert main([*CHART, "--state", str(state), "--duration-s", "0.1"]) == 0
    err = capsys.readouterr().err
    assert f"s7graph: note: the last run went to STOP: {why}\n" in err
    assert f"in RUN (warm restart from {state} after an unclean stop)" in err


def test_fresh_sets_a_write_ahead_log_without_its_file_aside(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A ``-wal`` whose file was deleted is refused (not read as a fresh start); ``--fresh``
    keeps it as ``FILE.old-N-wal``, so no new file picks it up."""
    state = tmp_path / "drill.sqlite"
    Path(f"{state}-wal").write_bytes(b"x" * 4096)
    assert main([*CHART, "--state", str(state), "--duration-s", "0.1"]) == 2
    (line,) = _errors(capsys.readouterr().err)
    assert "missing, but its write-ahead log drill.sqlite-wal is there" in line
    assert main([*CHART, "--state", str(state), "--duration-s", "0.1", "--fresh"]) == 0
    assert Path(f"{state}.old-1-wal").read_bytes() == b"x" * 4096 and state.is_file()
    assert f"the old file is kept as {state}.old-1-wal" in capsys.readouterr().err


def test_a_state_file_on_a_full_disk_is_not_read_and_not_called_unreadable(
    tmp_path: Path,
) -> None:
    """Opening a state file writes to it: on a full disk (here: files may not grow) the run
    is refused saying so, and the way out is to free space, never ``--fresh`` (which would
    set the good file aside and start anew)."""
    state = tmp_path / "drill.sqlite"
    assert main([*CHART, "--state", str(state), "--duration-s", "0.2"]) == 0
    proc = subprocess.run(
        [sys.executable, "-m", "s7graph", *CHART, "--state", str(state), "--duration-s", "5"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=60,
        preexec_fn=lambda: _no_room(state.stat().st_size),
    )
    assert proc.returncode == 2, proc.stderr
    (line,) = _errors(proc.stderr)
    assert line.startswith(f"s7graph: error: {state}: the disk ")
    assert "it was not read; free space on its disk" in line and "--fresh" not in line
    assert "Traceback" not in proc.stderr and not Path(f"{state}.old-1").exists()


def test_restart_hot_that_cannot_be_honoured_is_one_line_exit_2_and_never_a_warm_start(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A warm run killed (no hot-restart image on disk), then ``--restart hot``: why, and
    what to do, in one line; nothing started, nothing written."""
    state = tmp_path / "drill.sqlite"
    assert main([*CHART, "--state", str(state), "--duration-s", "0.1"]) == 0
    with sqlite3.connect(state) as con:  # as a warm run leaves its file when killed
        con.execute("DELETE FROM meta WHERE key='hot_memory'")
        con.execute("UPDATE meta SET value='0' WHERE key='clean'")
        entries = con.execute("SELECT count(*) FROM diagnostics").fetchone()
    con.close()
    capsys.readouterr()
    assert main([*CHART, "--state", str(state), "--duration-s", "0.1", "--restart", "hot"]) == 2
    assert capsys.readouterr().err.splitlines() == [
        f"s7graph: error: {state}: cannot restart hot: the last run kept no hot-restart image "
        "(a run keeps one when started with --restart hot, or when it stops cleanly); restart "
        "warm with --restart warm (each sequencer starts in its initial steps; where it was "
        "goes to the diagnostic buffer)"
    ]
    with sqlite3.connect(state) as con:
        assert con.execute("SELECT count(*) FROM diagnostics").fetchone() == entries
    con.close()


HOLDER = """
import sqlite3, sys
con = sqlite3.connect(sys.argv[1], isolation_level=None)
con.execute("PRAGMA locking_mode=EXCLUSIVE")
con.execute("BEGIN EXCLUSIVE")
con.execute("UPDATE meta SET value=value WHERE key='format'")
print("locked", flush=True)
sys.stdin.read()
"""


@pytest.mark.timeout(60)
def test_a_state_file_locked_by_another_process_is_refused_as_in_use_not_unreadable(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    state = tmp_path / "drill.sqlite"
    assert main([*CHART, "--state", str(state), "--duration-s", "0.1"]) == 0
    capsys.readouterr()
    holder = subprocess.Popen(
        [sys.executable, "-c", HOLDER, str(state)],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert holder.stdout is not None and holder.stdout.readline() == "locked\n"
        assert main([*CHART, "--state", str(state), "--duration-s", "0.1"]) == 2
    finally:
        holder.communicate("")
    assert capsys.readouterr().err.splitlines() == [
        f"s7graph: error: {state}: in use by another process (database is locked): it was not "
        "read; stop the process that holds it (or wait until it ends), then run again"
    ]


@pytest.mark.timeout(90)
def test_a_second_run_on_a_state_file_another_run_writes_is_refused_as_in_use(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """SQLite locks the file only while a transaction is written: without a lock of its own
    a second run would read the first's state and both would write it."""
    state = tmp_path / "drill.sqlite"
    first = subprocess.Popen(
        [sys.executable, "-m", "s7graph", *CHART, "--state", str(state)],
        cwd=ROOT,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert first.stderr is not None and " in RUN (" in first.stderr.readline()
        assert main([*CHART, "--state", str(state), "--duration-s", "0.1"]) == 2
        # nor with --fresh, which would move the running CPU's file aside under it
        assert main([*CHART, "--state", str(state), "--duration-s", "0.1", "--fresh"]) == 2
        assert not list(tmp_path.glob("drill.sqlite.old-*"))
    finally:
        first.send_signal(signal.SIGTERM)
        assert first.wait(30) == 0
    in_use = (
        f"s7graph: error: {state}: in use by another process (another run holds it); stop the "
        "process that holds it (or wait until it ends), then run again"
    )
    assert capsys.readouterr().err.splitlines() == [in_use, in_use]
    assert main([*CHART, "--state", str(state), "--duration-s", "0.1"]) == 0  # its turn now
