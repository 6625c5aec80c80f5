"""Online change through the virtual clock and a real zenoh bus on a unix socket: a changed chart is
downloaded into the running GraphFB (docs/online-change.md) — compiled off the scan thread, swapped
in at a scan boundary, the state carried over by step number
(``sequencer.change.carry.carry_over``), the file rewritten with a numbered backup, every download
audited — and undone the same way. Refusals leave the CPU running the old chart."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from s7graph.engine.clock import VirtualClock
from s7graph.engine.persistence import StateStore
from s7graph.sequencer.change.online import SwapRefused, swap
from s7graph.sequencer.exchange import import_file
from s7graph.sequencer.fb import GraphFB
from s7graph.web.access.audit import read_audit
from s7graph.web.bus.protocol import Command
from s7graph.web.cli import main
from s7graph.web.harness.persist import open_state
from s7graph.web.harness.scl import compile_sources
from s7graph.web.harness.session import ChartSession, compile_text, load_chart
from tests.sequencer.exchange.helpers import synthetic
from tests.web.helpers import PASSWORD, OnlineClient, online_client, wait_until

if TYPE_CHECKING:
    from tests.conftest import BusCerts

pytestmark = pytest.mark.timeout(90)

CHART = """FUNCTION_BLOCK "Seq_fill" FB 1 DB 1
VAR
  go : BOOL;
  full : BOOL;
  empty : BOOL;
  pieces : INT := 0;
END_VAR
SEQUENCE 1 "Fill"
  INITIAL_STEP S1 "Idle":
  END_STEP
  STEP S2 "Fill":
    S1 N pieces := pieces + 1;
    N Q0.0;
  END_STEP
  STEP S3 "Drain":
    N Q0.1;
  END_STEP
  TRANSITION T1 "Go" FROM S1 TO S2 := go;
  TRANSITION T2 "Full" FROM S2 TO S3 := full;
  TRANSITION T3 "Empty" FROM S3 TO S1 := empty;
END_SEQUENCE
END_FUNCTION_BLOCK
"""


WITHOUT_S2 = (
    CHART.replace(
        '  STEP S2 "Fill":\n    S1 N pieces := pieces + 1;\n    N Q0.0;\n  END_STEP\n', ""
    )
    .replace("FROM S1 TO S2 := go;", "FROM S1 TO S3 := go;")
    .replace('  TRANSITION T2 "Full" FROM S2 TO S3 := full;\n', "")
)


class Cpu(OnlineClient):
    FB = "Seq_fill"
    TIMEOUT = 20.0

    def set(self, name: str, value: object) -> None:
        self.session.set(name, value)

    def active(self) -> list[int]:
        g = self.session.graph
        return [n for n, x in zip(g.cc.step_numbers, g.state.x, strict=True) if x]


@pytest.fixture
def cpu(tmp_path: Path, bus_certs: BusCerts) -> Iterator[Cpu]:
    users = {"eng": "engineer", "olga": "operator"}
    with online_client(tmp_path, CHART, certs=bus_certs, users=users, name="fill.s7g") as on:
        yield Cpu(on.rig, on.client, on.token, on.user)


def test_download_swaps_the_chart_at_a_scan_boundary_keeping_the_active_step_and_its_time(
    cpu: Cpu,
) -> None:
    cpu.set("go", True)
    assert wait_until(lambda: cpu.active() == [2])
    g: GraphFB = cpu.session.graph
    before_t = g.state.step_t_ms(g.cc.step_index[2])
    pieces = cpu.session.get("pieces")
    edited = CHART.replace(":= full;", ":= full OR empty;").replace(
        'STEP S3 "Drain":', 'STEP S3 "Drain it":'
    )
    preview = cpu.send("download", source=edited, preview=True)
    assert preview.applied and preview.version == 1 and preview.removed == []
    assert any("T2" in line and "condition" in line for line in preview.lines), preview.lines
    assert cpu.active() == [2] and g.cc.name == "Seq_fill"  # a preview changes nothing

    reply = cpu.send("download", source=edited, base=1)
    assert reply.applied, reply.reason
    assert reply.version == 2
    assert cpu.active() == [2]  # the active step stays active ...
    assert g.state.step_t_ms(g.cc.step_index[2]) >= before_t  # ... its time goes on
    assert cpu.session.get("pieces") == pieces  # variables keep their values by name
    assert cpu.path.read_text(encoding="utf-8") == edited
    assert (cpu.path.parent / "fill.s7g.~1~").read_text(encoding="utf-8") == CHART
    layout = cpu.client.chart("Seq_fill")
    assert layout is not None and layout.version == 2
    source = cpu.client.source("Seq_fill")
    assert source is not None and source.version == 2 and source.text == edited

    cpu.set("empty", True)  # the sequence follows the new condition: S2 -> S3 on empty
    assert wait_until(lambda: cpu.active() in ([3], [1]))
    rows = read_audit(cpu.rig.state)
    download = [r for r in rows if r.op == "download" and r.outcome == "applied"]
    assert len(download) == 2  # the preview and the download, both as eng (engineer)
    assert download[-1].user == "eng" and download[-1].role == "engineer"
    assert "version 2 runs (was 1)" in download[-1].detail
    assert "T2" in download[-1].detail and "sha256" in download[-1].args


def test_a_removed_active_step_is_refused_without_a_choice_then_kept_or_initialized(
    cpu: Cpu,
) -> None:
    cpu.set("go", True)
    assert wait_until(lambda: cpu.active() == [2])
    without_s2 = WITHOUT_S2
    preview = cpu.send("download", source=without_s2, preview=True)
    assert preview.applied and preview.removed == [2]
    refused = cpu.send("download", source=without_s2)
    assert not refused.applied and "S2" in refused.reason and "keep" in refused.reason
    assert cpu.active() == [2] and cpu.path.read_text(encoding="utf-8") == CHART  # unchanged

    kept = cpu.send("download", source=without_s2, removed="keep")
    assert kept.applied, kept.reason
    assert cpu.active() == []  # S2 went; the other steps (none) go on
    assert "active steps removed: S2; the other steps go on" in kept.lines
    assert not any("would be removed" in line for line in kept.lines)  # that was the preview

    back = cpu.send("undo_download")
    assert back.applied, back.reason  # the old chart again (nothing active to remove)
    assert cpu.session.graph.cc.step_index.get(2) is not None and cpu.active() == []


def test_initialize_when_an_active_step_is_removed(cpu: Cpu) -> None:
    cpu.set("go", True)
    assert wait_until(lambda: cpu.active() == [2])
    cpu.set("go", False)
    without_s2 = WITHOUT_S2
    reply = cpu.send("download", source=without_s2, removed="init")
    assert reply.applied, reply.reason
    assert (
        "active steps removed: S2; the sequencer is initialized in its next call (the kept "
        "steps leave, the initial steps become the active ones)"
    ) in reply.lines
    assert not any("would be removed" in line for line in reply.lines)
    assert wait_until(lambda: cpu.active() == [1])  # INIT_SQ in the next call: S1 again


def test_undo_download_restores_the_old_chart_with_its_state_carried_back(cpu: Cpu) -> None:
    cpu.set("go", True)
    assert wait_until(lambda: cpu.active() == [2])
    added = CHART.replace(
        '  TRANSITION T1 "Go"', '  STEP S4 "Spare":\n  END_STEP\n  TRANSITION T1 "Go"'
    ).replace("END_SEQUENCE", '  TRANSITION T4 "Spare" FROM S4 TO S1 := FALSE;\nEND_SEQUENCE')
    assert cpu.send("download", source=added).applied
    assert cpu.session.graph.cc.step_index.get(4) is not None
    undone = cpu.send("undo_download", base=2)
    assert undone.applied, undone.reason
    assert undone.version == 3
    assert cpu.session.graph.cc.step_index.get(4) is None  # the old chart runs
    assert cpu.active() == [2]  # with S2 still active
    assert cpu.path.read_text(encoding="utf-8") == CHART
    assert not cpu.send("undo_download").applied  # nothing more to undo


def test_broken_or_hostile_downloads_are_refused_and_the_cpu_keeps_the_old_chart(
    cpu: Cpu, tmp_path: Path
) -> None:
    cc = cpu.session.graph.cc
    syntax = cpu.send("download", source=CHART.replace(":= full;", ":= full AND;"))
    assert not syntax.applied and "does not parse" in syntax.reason
    assert any("the edited chart:19:49: error" in line for line in syntax.lines), syntax.lines
    unknown = cpu.send("download", source=CHART.replace("N Q0.1;", "N Q99999.0;"))
    assert not unknown.applied and "does not compile" in unknown.reason
    steps = "".join(f"  STEP S{n}:\n  END_STEP\n" for n in range(10, 10_010))
    many = cpu.send("download", source=CHART.replace("  TRANSITION T1", steps + "  TRANSITION T1"))
    assert not many.applied and "at most 1,000" in many.reason, many.reason
    paste = b'{"op":"download","fb":"Seq_fill","args":{"source":"' + b"x" * 10_000_000 + b'"}}'
    raw = cpu.client.send_raw(paste, timeout=10)
    assert raw is not None and not raw.applied and "too large" in raw.reason
    stale = cpu.send("download", source=CHART.replace("full;", "empty;"), base=7)
    assert not stale.applied and "version 1" in stale.reason
    assert cpu.session.graph.cc is cc  # the CPU kept its chart through all of it
    assert cpu.path.read_text(encoding="utf-8") == CHART
    assert not list(tmp_path.glob("fill.s7g.~*~"))
    count = len(cpu.rig.scans)
    assert wait_until(lambda: len(cpu.rig.scans) > count + 5)  # and keeps scanning


def test_an_operator_may_not_download_and_the_refusal_is_audited(cpu: Cpu) -> None:
    login = cpu.client.login("olga", PASSWORD)
    command = Command(
        op="download", fb="Seq_fill", user="olga", token=login.token, args={"source": CHART}
    )
    reply = cpu.client.send(command, timeout=20)
    assert not reply.applied and "needs engineer" in reply.reason
    rows = [r for r in read_audit(cpu.rig.state) if r.op == "download"]
    assert rows and rows[-1].user == "olga" and rows[-1].outcome == "refused"


def test_save_and_open_use_the_project_directory_with_backups(cpu: Cpu) -> None:
    saved = cpu.send("save", file="copy.s7g", source=CHART)
    assert saved.applied, saved.reason
    assert (cpu.path.parent / "copy.s7g").read_text(encoding="utf-8") == CHART
    again = cpu.send("save", file="copy.s7g", source=CHART.replace("Idle", "Rest"))
    assert again.applied and (cpu.path.parent / "copy.s7g.~1~").exists()
    listed = cpu.client.project()
    assert listed is not None and {"fill.s7g", "copy.s7g"} <= {f.name for f in listed.files}
    opened = cpu.send("open", file="copy.s7g")
    assert opened.applied and '"Rest"' in opened.text
    for bad in ("../escape.s7g", ".hidden.s7g", "sub/x.s7g"):
        assert not cpu.send("save", file=bad, source=CHART).applied, bad
    assert not cpu.send("open", file="missing.s7g").applied


def test_open_of_an_import_with_st_bodies_writes_their_scl_fcs_beside_it(cpu: Cpu) -> None:
    """The FCs an imported chart calls for its ST bodies are kept: written as <stem>.scl
    beside the file (as ``import -o`` writes them), a note that this CPU lacks them."""
    source = synthetic("codesys_scl_bodies.xml")
    shutil.copy(source, cpu.path.parent / "bodies.xml")
    opened = cpu.send("open", file="bodies.xml")
    assert opened.applied, opened.reason
    scl = cpu.path.parent / "bodies.scl"
    made = import_file(cpu.path.parent / "bodies.xml")
    assert made.functions and scl.read_text(encoding="utf-8") == made.blocks_scl
    assert "CALL FC 1 (" in opened.text and "CALL FC 2 (" in opened.text
    assert opened.lines[0] == (
        "bodies.scl: the SCL FCs the chart calls for its ST bodies (FC 1, FC 2), written"
    )
    assert opened.lines[1] == (
        "this CPU does not have FC 1, FC 2: a download of the chart is refused until the "
        "CPU runs with --blocks bodies.scl"
    )
    assert any("I033" in line for line in opened.lines[2:])
    again = cpu.send("open", file="bodies.xml")
    assert again.applied and again.lines[0].endswith("(FC 1, FC 2), unchanged")


def test_open_is_refused_when_the_cpu_has_another_fc_of_an_imported_body_s_number(
    cpu: Cpu,
) -> None:
    """An FC of the CPU by the number the import gives a body, from another source, would be
    what the chart calls: refused; the FCs of the written source itself are no conflict."""
    shutil.copy(synthetic("codesys_scl_bodies.xml"), cpu.path.parent / "bodies.xml")
    other = cpu.path.parent / "mine.scl"
    other.write_text(
        "FUNCTION FC1 : VOID\nVAR_INPUT\n  x : INT;\nEND_VAR\nBEGIN\nEND_FUNCTION\n",
        encoding="utf-8",
    )
    cpu.session.blocks = [compile_sources([other])]
    cpu.session.blocks[0].load(cpu.session.cpu)
    refused = cpu.send("open", file="bodies.xml")
    assert not refused.applied
    assert "calls FC 1 for ST bodies" in refused.reason
    assert "comes from another source" in refused.reason
    assert not (cpu.path.parent / "bodies.scl").exists()
    # the CPU runs with the import's own source: nothing lacks, nothing conflicts
    scl = cpu.path.parent / "bodies.scl"
    scl.write_text(import_file(cpu.path.parent / "bodies.xml").blocks_scl, encoding="utf-8")
    cpu.session.blocks = [compile_sources([scl])]
    cpu.session.blocks[0].load(cpu.session.cpu)
    opened = cpu.send("open", file="bodies.xml")
    assert opened.applied, opened.reason
    assert opened.lines[0].endswith("(FC 1, FC 2), unchanged")
    assert not any("does not have" in line for line in opened.lines)


def test_open_of_a_file_with_several_charts_names_them_and_opens_the_one_chosen(
    cpu: Cpu,
) -> None:
    """Without a chart the open is refused, each chart a line (``two.st » Blink``); with
    ``pou`` that chart opens."""
    shutil.copy(synthetic("il_beside_chart.st"), cpu.path.parent / "two.st")
    refused = cpu.send("open", file="two.st")
    assert not refused.applied
    assert refused.reason == "two.st holds 2 charts (Blink, Count): choose one"
    assert refused.lines == ["two.st » Blink", "two.st » Count"]
    opened = cpu.send("open", file="two.st", pou="Count")
    assert opened.applied, opened.reason
    assert 'FUNCTION_BLOCK "Count"' in opened.text
    assert not cpu.send("open", file="two.st", pou="Nosuch").applied


def _shell(bus: list[str], *args: str) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "S7GRAPH_PASSWORD": PASSWORD}
    return subprocess.run(
        [sys.executable, "-m", "s7graph", *args, "--cpu", "cpu1", *bus],
        capture_output=True,
        text=True,
        timeout=60,
        env=env,
        stdin=subprocess.DEVNULL,
    )


def test_s7graph_download_shows_the_change_asks_and_downloads(cpu: Cpu, tmp_path: Path) -> None:
    """``s7graph download CHART.s7g --cpu NAME``: the same path as the bus command."""
    cpu.set("go", True)
    assert wait_until(lambda: cpu.active() == [2])
    edited = tmp_path / "edited.s7g"
    edited.write_text(WITHOUT_S2, encoding="utf-8")
    asked = _shell(cpu.rig.bus, "download", str(edited), "--user", "eng")
    assert asked.returncode == 1 and "S2 would be removed" in asked.stderr, asked.stderr
    assert "S2" in asked.stdout  # the change summary came first
    unconfirmed = _shell(cpu.rig.bus, "download", str(edited), "--user", "eng", "--removed", "keep")
    assert unconfirmed.returncode == 1 and "not confirmed" in unconfirmed.stderr
    assert cpu.active() == [2]  # nothing downloaded yet
    done = _shell(
        cpu.rig.bus, "download", str(edited), "--user", "eng", "--removed", "keep", "--yes"
    )
    assert done.returncode == 0, done.stderr
    assert "version 2 runs" in done.stdout
    assert cpu.session.graph.cc.step_index.get(2) is None
    refused = _shell(cpu.rig.bus, "download", str(edited), "--user", "olga", "--yes")
    assert refused.returncode == 1 and "needs engineer" in refused.stderr
    # send undo_download: the preview's summary and the version, never "cycle None"
    preview = _shell(cpu.rig.bus, "send", "undo_download", "preview=true", "--user", "eng")
    assert preview.returncode == 0, preview.stderr
    assert "S2" in preview.stdout and "cycle None" not in preview.stdout, preview.stdout
    assert "undo_download applied on cpu1/Seq_fill: version 2 runs" in preview.stdout


def test_a_download_and_a_restart_with_the_downloaded_file_carry_the_state_alike(
    tmp_path: Path,
) -> None:
    """Starting ``s7graph run`` with an edited chart and an old state file carries the
    state over with the same function as a download (``sequencer.change.carry.carry_over``)."""
    edited = CHART.replace(":= full;", ":= full OR empty;")
    path = tmp_path / "fill.s7g"
    path.write_text(CHART, encoding="utf-8")
    cc, table = load_chart(path)

    def in_s2() -> ChartSession:
        session = ChartSession(cc, table, VirtualClock())
        session.start()
        session.set("go", True)
        for _ in range(30):
            session.clock.advance(10)  # type: ignore[attr-defined]
            session.scan()
        return session

    online = in_s2()
    store = StateStore(tmp_path / "state.sqlite")
    store.save(online.cpu)
    new_cc, _ = compile_text(edited, str(path))
    swap(online.graph, new_cc, online.cpu)  # the download, at a scan boundary
    store.close()

    path.write_text(edited, encoding="utf-8")  # the restart with the edited file
    restarted = ChartSession(*load_chart(path), VirtualClock())
    opened = open_state(tmp_path / "state.sqlite", restarted.cpu)
    try:
        assert opened.report is not None and opened.report.changed == [1]
        a, b = online.graph.state, restarted.graph.state
        assert sorted(a.active) == sorted(b.active) == [new_cc.step_index[2]]
        assert a.vars == b.vars and a.t_ns == b.t_ns and a.x == b.x
    finally:
        opened.store.close()


def test_the_preview_reports_operands_left_set_by_s_rows_of_removed_steps(cpu: Cpu) -> None:
    with_s = CHART.replace("    N Q0.0;\n", "    N Q0.0;\n    S Q0.2;\n")
    assert cpu.send("download", source=with_s).applied
    gone = WITHOUT_S2
    preview = cpu.send("download", source=gone, preview=True)
    assert preview.applied
    assert any("Q0.2" in line and "S2" in line and "stay set" in line for line in preview.lines)


def test_s7graph_upload_brings_back_the_chart_the_cpu_runs_after_a_download(
    cpu: Cpu, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """STEP 7's "Upload from device": the ``.s7g`` text the CPU compiled — after a download,
    the downloaded one — to stdout, or into a folder under the chart's file name, never over
    a file there without ``--force``."""
    bus = ["--cpu", "cpu1", *cpu.rig.bus]
    assert main(["upload", *bus]) == 0
    assert capsys.readouterr().out == CHART
    edited = CHART.replace(":= full;", ":= full OR empty;")
    assert cpu.send("download", source=edited, base=1).applied
    folder = tmp_path / "uploaded"
    assert main(["upload", *bus, "--fb", "Seq_fill", "--to", str(folder)]) == 0
    said = capsys.readouterr().out
    assert said == f"s7graph: Seq_fill version 2 of cpu1 → {folder / 'fill.s7g'} (22 lines)\n"
    assert [p.name for p in folder.iterdir()] == ["fill.s7g"]  # no symbol table: none given
    assert (folder / "fill.s7g").read_text(encoding="utf-8") == edited
    (folder / "fill.s7g").write_text("mine", encoding="utf-8")
    assert main(["upload", *bus, "--to", str(folder)]) == 2
    assert "fill.s7g exists (--force writes over it)" in capsys.readouterr().err
    assert (folder / "fill.s7g").read_text(encoding="utf-8") == "mine"
    assert main(["upload", *bus, "--to", str(folder), "--force"]) == 0
    assert (folder / "fill.s7g").read_text(encoding="utf-8") == edited
    assert main(["upload", *bus, "--fb", "Nope"]) == 2
    assert capsys.readouterr().err.endswith("runs no FB 'Nope'; it runs Seq_fill\n")
    assert main(["upload", *bus, "--to", str(folder / "fill.s7g")]) == 2
    assert capsys.readouterr().err == f"s7graph: error: --to {folder / 'fill.s7g'}: not a folder\n"


def test_a_preview_refuses_what_the_swap_would_refuse_with_the_same_reason(
    cpu: Cpu, tmp_path: Path
) -> None:
    """An operand beyond the CPU's memory and a call of a block the CPU has not loaded are
    refused by the swap at the scan boundary; the preview says so first, with the very
    reason the download's reply then gives — never a question whose answer is a refusal."""
    cc = cpu.session.graph.cc
    beyond = CHART.replace("N Q0.1;", "N Q9999.7;")
    calls = CHART.replace("N Q0.1;", "N Q0.1;\n    CALL FC 9;")
    for edited, why in (
        (beyond, "Q9999.7 is outside the Q area (128 bytes): reached, the new chart would stop"),
        (calls, "CALL FC 9: FC9 is not in this CPU; reached, the call would stop it"),
    ):
        asked = cpu.send("download", source=edited, preview=True)
        assert not asked.applied and why in asked.reason, asked.reason
        new_cc, _ = compile_text(edited, "the edited chart")
        with pytest.raises(SwapRefused) as swapped:  # the boundary's own refusal
            swap(cpu.session.graph, new_cc, cpu.session.cpu)
        assert asked.reason == f"download refused: {swapped.value}; the CPU keeps the old chart"
        done = cpu.send("download", source=edited)
        assert not done.applied and done.reason == asked.reason
    assert cpu.session.graph.cc is cc and cpu.path.read_text(encoding="utf-8") == CHART
    assert not list(tmp_path.glob("fill.s7g.~*~"))


def test_a_variable_whose_type_changes_restarts_at_its_initial_value_as_the_preview_says(
    cpu: Cpu,
) -> None:
    cpu.set("go", True)
    assert wait_until(lambda: cpu.active() == [2] and cpu.session.get("pieces") == 1)
    edited = CHART.replace("pieces : INT := 0;", "pieces : REAL := 2.5;").replace(
        "pieces := pieces + 1;", "pieces := pieces + 1.0;"
    )
    said = "variable pieces: INT → REAL, restarts at its initial value 2.5"
    preview = cpu.send("download", source=edited, preview=True)
    assert preview.applied and said in preview.lines, preview.lines
    reply = cpu.send("download", source=edited)
    assert reply.applied, reply.reason
    assert reply.lines.count(said) == 1, reply.lines
    assert cpu.session.get("pieces") == 2.5 and cpu.active() == [2]


SECOND = """SEQUENCE 2 "Count"
  INITIAL_STEP S20 "Ready":
    S1 N starts := starts + 1;
  END_STEP
  STEP S21 "Counted":
  END_STEP
  TRANSITION T20 FROM S20 TO S21 := go;
  TRANSITION T21 FROM S21 TO S20 := FALSE;
END_SEQUENCE
"""
WITH_SECOND = CHART.replace("END_SEQUENCE\n", "END_SEQUENCE\n" + SECOND).replace(
    "  pieces : INT := 0;\n", "  pieces : INT := 0;\n  starts : INT := 0;\n"
)


def test_a_new_sequencer_starts_in_its_initial_step_at_the_swap_as_the_preview_says(
    cpu: Cpu,
) -> None:
    """A sequencer the running chart did not have: its initial step active at the swap, its
    S1 rows run once in the next call (held there, as the first call after a start holds
    it), then it switches on — while the other sequencer goes on where it was."""
    cpu.set("go", True)
    assert wait_until(lambda: cpu.active() == [2])
    said = "new sequencer 2: its initial step S20 becomes active"
    preview = cpu.send("download", source=WITH_SECOND, preview=True)
    assert preview.applied and said in preview.lines, preview.lines
    reply = cpu.send("download", source=WITH_SECOND)
    assert reply.applied, reply.reason
    assert reply.lines.count(said) == 1, reply.lines
    assert wait_until(lambda: cpu.active() == [2, 21])  # S2 went on; S20 → S21 on go
    assert cpu.session.get("starts") == 1  # S20's S1 row, once


def test_a_restart_with_a_new_sequencer_starts_it_as_a_download_does(tmp_path: Path) -> None:
    """``carry_over`` for a download and for ``s7graph run`` with the changed file: the new
    sequencer's initial step active in both, the old sequencer's step with its time."""
    path = tmp_path / "fill.s7g"
    path.write_text(CHART, encoding="utf-8")
    online = ChartSession(*load_chart(path), VirtualClock())
    online.start()
    online.set("go", True)
    for _ in range(30):
        online.clock.advance(10)  # type: ignore[attr-defined]
        online.scan()
    store = StateStore(tmp_path / "state.sqlite")
    store.save(online.cpu)
    store.close()
    new_cc, _ = compile_text(WITH_SECOND, str(path))
    swap(online.graph, new_cc, online.cpu)
    path.write_text(WITH_SECOND, encoding="utf-8")
    restarted = ChartSession(*load_chart(path), VirtualClock())
    opened = open_state(tmp_path / "state.sqlite", restarted.cpu)
    try:
        a, b = online.graph.state, restarted.graph.state
        assert sorted(a.active) == sorted(b.active) == sorted(new_cc.step_index[n] for n in (2, 20))
        assert a.t_ns == b.t_ns and a.x == b.x
        assert opened.report is not None
        said = "new sequencer 2: its initial step S20 becomes active"
        assert any(said in note for note in opened.report.notes), opened.report.notes
    finally:
        opened.store.close()


def test_compile_errors_of_a_download_name_the_engineers_file(cpu: Cpu, tmp_path: Path) -> None:
    """Not the CPU's own chart file: the file the engineer downloads (``file``, as
    ``s7graph download`` gives its argument), or the edited chart of the page."""
    bad = CHART.replace("N Q0.1;", "N Q99999.0;")
    named = cpu.send("download", source=bad, file="my.s7g", preview=True)
    assert not named.applied and "my.s7g:16:7: error[E041]" in named.reason, named.reason
    assert all(line.startswith("my.s7g:") for line in named.lines), named.lines
    page = cpu.send("download", source=bad)
    assert not page.applied and page.lines[0].startswith("the edited chart:16:7:"), page.lines
    mine = tmp_path / "mine.s7g"
    mine.write_text(bad, encoding="utf-8")
    shell = _shell(cpu.rig.bus, "download", str(mine), "--user", "eng")
    assert shell.returncode == 1 and f"{mine}:16:7: error[E041]" in shell.stderr, shell.stderr
    assert "fill.s7g" not in shell.stderr + named.reason + page.reason + "".join(page.lines)
