"""The state file deleted or overwritten while ``s7graph run`` runs (a real process on the
bus): the CPU goes on, builds the file anew from what it holds, answers a command *applied*
only once it is in the new file, and after SIGKILL a hot restart resumes from it — before,
the commits went to a deleted file (or log) and the restart started fresh or came back from
the last checkpoint, the answered commands lost."""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

import pytest

from s7graph.web.access.audit import read_audit
from s7graph.web.bus.protocol import Command
from s7graph.web.cli import main
from tests.paths import ROOT
from tests.real_process import kill_run
from tests.web.helpers import cpu_process

pytestmark = pytest.mark.timeout(180)
DRILL = ROOT / "examples" / "drill"
FB = "Seq_drill"
USER = "tess (unverified)"
CHART = [
    str(DRILL / "drill.s7g"),
    "--symbols",
    str(DRILL / "symbols.txt"),
    "--plant",
    str(DRILL / "demo_plant.py"),
]


def _garble(state: Path) -> None:
    with open(state, "r+b") as f:
        f.write(os.urandom(state.stat().st_size))


@pytest.mark.parametrize(
    "damage",
    [Path.unlink, lambda s: Path(f"{s}-wal").unlink(), _garble],
    ids=["file deleted", "write-ahead log deleted", "file overwritten"],
)
def test_a_state_file_lost_under_a_running_cpu_is_written_anew_and_survives_sigkill(
    tmp_path: Path, damage: Callable[[Path], None]
) -> None:
    state = tmp_path / "drill.sqlite"
    assert main(["run", *CHART, "--state", str(state), "--duration-s", "0.3"]) == 0
    args = [*CHART, "--state", str(state), "--restart", "hot", "--duration-s", "120"]
    with cpu_process(tmp_path, args, fb=FB, user="tess") as (proc, client, token):
        as_tess = {"fb": FB, "user": "tess", "token": token}
        damage(state)
        reply = client.send(Command(op="mode", args={"mode": "MAN"}, **as_tess))
        assert reply.applied, reply.reason
        kill_run(proc)  # at once, on the reply
        assert proc.stderr is not None
        err = proc.stderr.read()
    assert "Traceback" not in err and "error" not in err, err  # (its warning may not be out yet)
    assert (USER, "mode", "applied") in [(r.user, r.op, r.outcome) for r in read_audit(state)]
    assert list(tmp_path.glob("drill.sqlite.damaged-1*"))  # what was there, kept aside

    with cpu_process(tmp_path, args, fb=FB) as (_, client, _):
        snapshot = client.state(FB)
        assert snapshot is not None and snapshot.mode == "MAN"  # resumed, hot
