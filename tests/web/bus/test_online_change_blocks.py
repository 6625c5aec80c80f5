"""A download that brings changed S7-SCL blocks, over a real zenoh bus (docs/online-change.md,
"S7-SCL blocks"): compiled in the CPU's compiler process, the chart's calls checked against
the new interfaces, swapped in with the chart at one scan boundary, the instance DB keeping
its values by name — which its preview says first; refusals give a reason (a preview's
too) and leave the old blocks running; the block file is rewritten with a numbered backup;
an undo puts the old blocks back. Then through
``s7graph run --blocks`` and ``s7graph download --blocks`` as real processes, the change
surviving a restart."""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from s7graph.web.access.audit import read_audit
from s7graph.web.bus.client import BusClient
from s7graph.web.bus.protocol import CommandReply
from s7graph.web.cli import main
from s7graph.web.commands import Download, DownloadArgs, checked, make_command
from tests.paths import ROOT
from tests.web.helpers import CALLS_FB17, OnlineClient, cpu_process, online_client, wait_until

if TYPE_CHECKING:
    from tests.conftest import BusCerts

pytestmark = pytest.mark.timeout(120)

CHART = CALLS_FB17
BLOCKS = """FUNCTION_BLOCK FB17
VAR_INPUT go : BOOL; END_VAR
VAR n : INT; old : INT; END_VAR
  IF go THEN n := n + 1; END_IF;
END_FUNCTION_BLOCK
"""
# n by 1000 now, ``old`` dropped, ``fresh`` new (from 5), ``n`` an INT → DINT carried
CHANGED = """FUNCTION_BLOCK FB17
VAR_INPUT go : BOOL; END_VAR
VAR n : DINT; fresh : INT := 5; END_VAR
  IF go THEN n := n + 1000; fresh := fresh + 1; END_IF;
END_FUNCTION_BLOCK
"""


class Cpu(OnlineClient):
    TIMEOUT = 30.0

    def n(self) -> int:
        return int(self.session.get("DB10.n"))

    def grows_by(self, step: int) -> bool:
        """``n`` goes on growing by ``step`` a scan."""
        first = self.n()
        return wait_until(lambda: self.n() >= first + 3 * step and (self.n() - first) % step == 0)


@pytest.fixture
def cpu(tmp_path: Path, bus_certs: BusCerts) -> Iterator[Cpu]:
    blocks = {"fb17.scl": BLOCKS}
    with online_client(tmp_path, CHART, certs=bus_certs, name="seq.s7g", blocks=blocks) as on:
        yield Cpu(on.rig, on.client, on.token, on.user)


def test_a_download_swaps_changed_blocks_in_keeping_the_instance_values_by_name(
    cpu: Cpu,
) -> None:
    assert wait_until(lambda: cpu.n() > 5)
    preview = cpu.send("download", source=CHART, blocks={"fb17.scl": CHANGED}, preview=True)
    assert preview.applied, preview.reason
    assert "S7-SCL blocks changed: fb17.scl" in preview.lines
    said = [line for line in preview.lines if line.startswith("DB10 ")]
    assert "DB10 FB17 'FB17': dropped (no longer declared): old" in said
    assert "DB10 FB17 'FB17': new, at their initial values: fresh" in said
    assert cpu.session.cpu.block("FB17").interface[1].type == "INT"  # a preview: no change
    reply = cpu.send("download", source=CHART, blocks={"fb17.scl": CHANGED})
    assert reply.applied, reply.reason
    assert reply.version == 2
    assert [line for line in reply.lines if line.startswith("DB10 ")] == said
    assert cpu.grows_by(1000)  # the new code, on the value n had: carried as a DINT
    assert cpu.n() % 1000 != 0 and int(cpu.session.get("DB10.fresh")) > 5
    block_file = cpu.path.parent / "fb17.scl"
    assert block_file.read_text(encoding="utf-8") == CHANGED
    assert (cpu.path.parent / "fb17.scl.~1~").read_text(encoding="utf-8") == BLOCKS
    rows = [r for r in read_audit(cpu.rig.state) if r.op == "download" and r.outcome == "applied"]
    assert rows and "fb17.scl" in rows[-1].args and "sha256" in rows[-1].args

    asked = cpu.send("undo_download", preview=True)  # n would narrow: its preview says so
    assert not asked.applied and "DB10 (FB17): n: DINT → INT" in asked.reason, asked.reason
    back = cpu.send("undo_download")  # n would narrow from DINT to INT: refused
    assert not back.applied and back.reason == asked.reason, back.reason
    assert cpu.grows_by(1000) and block_file.read_text(encoding="utf-8") == CHANGED

    by_7 = CHANGED.replace("n + 1000", "n + 7")
    assert cpu.send("download", source=CHART, blocks={"fb17.scl": by_7}).applied
    assert cpu.grows_by(7)
    asked = cpu.send("undo_download", preview=True)
    assert asked.applied and "S7-SCL blocks changed: fb17.scl" in asked.lines, asked.reason
    back = cpu.send("undo_download")  # the blocks before, the values carried back
    assert back.applied, back.reason
    assert "S7-SCL blocks changed: fb17.scl" in back.lines
    assert not any(line.startswith("DB10 ") for line in asked.lines)  # the code only
    assert cpu.grows_by(1000) and block_file.read_text(encoding="utf-8") == CHANGED


def test_upload_brings_back_the_chart_with_the_scl_sources_the_cpu_runs(
    cpu: Cpu, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """STEP 7's "Upload from device" with blocks: the chart and each S7-SCL source the CPU
    runs — after a download, those it brought — under its file name in the folder; without
    ``--to``, stderr names the sources."""
    bus = ["--cpu", "cpu1", *cpu.rig.bus]
    folder = tmp_path / "uploaded"
    assert main(["upload", *bus, "--to", str(folder)]) == 0
    assert (folder / "fb17.scl").read_text(encoding="utf-8") == BLOCKS
    said = capsys.readouterr().out.splitlines()
    assert said[1] == f"s7graph: an S7-SCL source it runs → {folder / 'fb17.scl'} (5 lines)"
    assert cpu.send("download", source=CHART, blocks={"fb17.scl": CHANGED}).applied
    assert main(["upload", *bus, "--to", str(folder), "--force"]) == 0
    assert (folder / "seq.s7g").read_text(encoding="utf-8") == CHART
    assert (folder / "fb17.scl").read_text(encoding="utf-8") == CHANGED
    assert main(["upload", *bus]) == 0
    out = capsys.readouterr()
    assert out.out.endswith(CHART)
    assert out.err == (
        "s7graph: the CPU runs S7-SCL sources beside it (fb17.scl): --to DIR writes them\n"
    )


def test_refusals_give_a_reason_and_the_old_blocks_run_on(cpu: Cpu) -> None:
    assert wait_until(lambda: cpu.n() > 2)
    cases = {
        "n : BOOL; old : INT; END_VAR\n  IF go THEN n := NOT n;": (
            "DB10 (FB17): n: INT → BOOL: the value cannot be carried over"
        ),
        "n : INT; old : INT; END_VAR\n  IF go THEN n := n + TRUE;": (
            "the S7-SCL blocks do not compile"
        ),
    }
    for change, reason in cases.items():
        text = BLOCKS.replace("n : INT; old : INT; END_VAR\n  IF go THEN n := n + 1;", change)
        assert text != BLOCKS
        asked = cpu.send("download", source=CHART, blocks={"fb17.scl": text}, preview=True)
        assert not asked.applied and reason in asked.reason, asked.reason  # said before
        reply = cpu.send("download", source=CHART, blocks={"fb17.scl": text})
        assert not reply.applied and reason in reply.reason, reply.reason
        assert "keeps the old" in reply.reason or "do not compile" in reply.reason
    no_input = BLOCKS.replace("VAR_INPUT go : BOOL; END_VAR\n", "").replace("IF go", "IF TRUE")
    reply = cpu.send("download", source=CHART, blocks={"fb17.scl": no_input})
    assert not reply.applied and "the chart's calls do not fit the new blocks" in reply.reason
    assert any("E047" in line for line in reply.lines), reply.lines
    reply = cpu.send("download", source=CHART, blocks={"other.scl": BLOCKS})
    assert not reply.applied and "runs no S7-SCL source other.scl" in reply.reason
    reply = cpu.send("download", source=CHART, blocks={"fb17.scl": BLOCKS})
    assert not reply.applied and "nothing changes" in reply.reason
    assert reply.kind == "state"  # an engineering op's refusal names its kind too
    # the blocks swap, then the chart's is refused at the same boundary: both go back
    s3 = CHART.replace("INITIAL_STEP S1", "INITIAL_STEP S3").replace("FROM S1", "FROM S3")
    reply = cpu.send("download", source=s3, blocks={"fb17.scl": CHANGED})
    assert not reply.applied and "active steps S1 are not in the new chart" in reply.reason
    assert cpu.session.cpu.block("FB17").interface[1].type == "INT"  # the old FB17
    assert cpu.grows_by(1)  # the old FB runs on
    assert (cpu.path.parent / "fb17.scl").read_text(encoding="utf-8") == BLOCKS
    assert not (cpu.path.parent / "fb17.scl.~1~").exists()
    assert cpu.path.read_text(encoding="utf-8") == CHART


def test_a_download_without_blocks_leaves_them_as_they_are(cpu: Cpu) -> None:
    edited = CHART.replace('"never"', '"never ever"')
    reply = cpu.send("download", source=edited)
    assert reply.applied, reply.reason
    assert not any("S7-SCL" in line for line in reply.lines)
    assert cpu.grows_by(1)


def _cli(tmp_path: Path, *args: str) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "S7GRAPH_PASSWORD": "unused"}
    endpoint = f"unixsock-stream/{tmp_path}/bus.sock"
    return subprocess.run(
        [sys.executable, "-m", "s7graph", *args, "--connect", endpoint, "--user", "eng"],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=60,
    )


def _value(client: BusClient, name: str) -> int:
    got = client.watch([name], timeout=10)
    assert not got.error, got.error
    return int(got.values[0].value)  # type: ignore[arg-type]


def test_s7graph_download_blocks_into_s7graph_run_and_the_change_survives_a_restart(
    tmp_path: Path,
) -> None:
    chart, blocks, state = tmp_path / "seq.s7g", tmp_path / "fb17.scl", tmp_path / "s.sqlite"
    chart.write_text(CHART, encoding="utf-8")
    blocks.write_text(BLOCKS, encoding="utf-8")
    changed = tmp_path / "edit" / "fb17.scl"
    changed.parent.mkdir()
    changed.write_text(CHANGED, encoding="utf-8")
    args = [str(chart), "--blocks", str(blocks), "--state", str(state), "--duration-s", "100"]
    with cpu_process(tmp_path, args, fb="Seq", terminate=True) as (_, client, _):
        assert wait_until(lambda: _value(client, "DB10.n") > 3)
        done = _cli(tmp_path, "download", str(chart), "--blocks", str(changed), "--yes")
        assert done.returncode == 0, done.stdout + done.stderr
        assert "S7-SCL blocks changed: fb17.scl" in done.stdout
        fresh = "DB10 FB17 'FB17': new, at their initial values: fresh"
        assert f"\n  {fresh}\n" in done.stdout  # the preview's line, before the question
        assert f"\ns7graph: {fresh}\n" in done.stdout  # the download's
        assert "download applied" in done.stdout
        assert wait_until(lambda: _value(client, "DB10.n") > 3000)
        carried = _value(client, "DB10.n") % 1000  # n when downloaded: below 1000
        assert carried != 0
        missing = _cli(tmp_path, "download", str(chart), "--blocks", str(tmp_path / "x.scl"))
        assert missing.returncode == 2 and "cannot read" in missing.stderr
    assert blocks.read_text(encoding="utf-8") == CHANGED
    with cpu_process(tmp_path, args, fb="Seq", terminate=True) as (_, client, _):
        first = _value(client, "DB10.n")
        assert first > 3000 and first % 1000 == carried  # carried, then kept on disk
        assert wait_until(lambda: _value(client, "DB10.n") >= first + 3000)  # the new code
        assert _value(client, "DB10.fresh") > 5


def test_the_command_carries_at_most_8_sources_and_old_senders_need_none() -> None:
    many = {f"s{i}.scl": "" for i in range(9)}
    with pytest.raises(ValueError, match="blocks"):
        checked(Download(fb="Seq", args=DownloadArgs(source=CHART, blocks=many)))
    eight = dict(list(many.items())[:8])
    assert checked(Download(fb="Seq", args=DownloadArgs(source=CHART, blocks=eight)))
    old = make_command(op="download", fb="Seq", args={"source": CHART})
    assert isinstance(old, Download) and "blocks" not in old.args


def test_a_source_over_the_limit_is_refused_before_the_bus_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A download carries at most 1,000,000 characters a file: ``s7graph download`` says so,
    naming the file, before it joins the bus."""
    monkeypatch.setenv("S7GRAPH_PASSWORD", "unused")
    chart, big = tmp_path / "seq.s7g", tmp_path / "fb17.scl"
    chart.write_text(CHART, encoding="utf-8")
    big.write_text(BLOCKS + "// " + "x" * 1_000_000 + "\n", encoding="utf-8")
    endpoint = f"unixsock-stream/{tmp_path}/none.sock"
    args = ["download", str(chart), "--blocks", str(big), "--connect", endpoint, "--user", "eng"]
    assert main(args) == 2
    assert capsys.readouterr().err == (
        f"s7graph: error: {big}: 1,000,137 characters; a download carries at most 1,000,000 a "
        "file (split a source of blocks into several)\n"
    )


def test_a_refusal_the_cpu_words_itself_is_printed_once(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The compiler's time limit says ``download refused: …`` itself: printed as it is, not
    as ``download refused: download refused: …``."""
    from s7graph.web.cli.remote import _refused

    why = "download refused: not compiled within 20 s (the time limit)"
    assert _refused("download", CommandReply(applied=False, reason=why)) == 1
    assert capsys.readouterr().err == f"s7graph: {why}\n"
    assert _refused("download", CommandReply(applied=False, reason="no chart")) == 1
    assert capsys.readouterr().err == "s7graph: download refused: no chart\n"


def test_a_download_of_blocks_alone_leaves_the_chart_and_its_file_as_its_preview_says(
    cpu: Cpu,
) -> None:
    """The chart's text unchanged, the S7-SCL blocks changed: the preview says the chart
    does not change, and so does the reply — the chart that runs, its state and its file
    (no backup) stay as they are; an undo of it too."""
    graph = cpu.session.graph
    cc, state = graph.cc, graph.state
    by_7 = BLOCKS.replace("n + 1", "n + 7")
    preview = cpu.send("download", source=CHART, blocks={"fb17.scl": by_7}, preview=True)
    assert preview.applied and preview.lines[0] == "the chart does not change", preview.lines
    reply = cpu.send("download", source=CHART, blocks={"fb17.scl": by_7})
    assert reply.applied, reply.reason
    assert reply.lines[:3] == [
        "version 2 runs (was 1)",
        "the chart does not change",
        "S7-SCL blocks changed: fb17.scl",
    ], reply.lines
    assert not any("chart changed" in line for line in reply.lines)
    assert cpu.grows_by(7)
    assert graph.cc is cc and graph.state is state  # not swapped, not carried over
    assert cpu.path.read_text(encoding="utf-8") == CHART
    assert (cpu.path.parent / "fb17.scl.~1~").read_text(encoding="utf-8") == BLOCKS
    back = cpu.send("undo_download")
    assert back.applied and "the chart does not change" in back.lines, back.lines
    assert cpu.grows_by(1) and graph.cc is cc
    assert not list(cpu.path.parent.glob("seq.s7g.~*~"))  # the chart file never written


def test_a_preview_checks_a_new_call_against_the_blocks_the_download_brings(cpu: Cpu) -> None:
    """A chart calling an FB that only the new S7-SCL sources have: its preview does not
    refuse what the swap, after those blocks, takes — and refuses an FB neither has."""
    with_fb18 = CHANGED + BLOCKS.replace("FB17", "FB18").replace("n + 1", "n + 2")
    calls = CHART.replace(
        "    CALL FB 17, DB 10 (go := TRUE);\n",
        "    CALL FB 17, DB 10 (go := TRUE);\n    CALL FB 18, DB 11 (go := TRUE);\n",
    )
    asked = cpu.send("download", source=calls, blocks={"fb17.scl": with_fb18}, preview=True)
    assert asked.applied, asked.reason
    done = cpu.send("download", source=calls, blocks={"fb17.scl": with_fb18})
    assert done.applied, done.reason
    assert wait_until(lambda: int(cpu.session.get("DB11.n")) > 4)
    lacking = calls.replace("CALL FB 18, DB 11", "CALL FB 19, DB 12")
    asked = cpu.send("download", source=lacking, preview=True)
    assert not asked.applied and "FB19 is not in this CPU" in asked.reason, asked.reason


def _reading(condition: str) -> str:
    """The chart with T1 reading ``condition`` and the DB symbol ``Count_DB`` of DB10."""
    chart = CHART.replace(
        "TRANSITION T1 FROM S1 TO S2 := FALSE;", f"TRANSITION T1 FROM S1 TO S2 := {condition};"
    )
    return chart.replace(
        'SEQUENCE 1 "S"', 'SYMBOLS "Count_DB" : DB10 : FB17; END_SYMBOLS\nSEQUENCE 1 "S"'
    )


def test_a_chart_only_download_reads_a_variable_of_the_fb_the_cpu_holds_by_name(
    cpu: Cpu,
) -> None:
    """No sources in the download: the chart is compiled with the interfaces of the CPU's
    S7-SCL blocks, so ``"Count_DB".n`` compiles (its preview says so first) and switches
    the step once the FB's static variable gets there."""
    assert wait_until(lambda: cpu.n() > 2)
    target = cpu.n() + 20
    reads = _reading(f'"Count_DB".n >= {target}')
    asked = cpu.send("download", source=reads, preview=True)
    assert asked.applied, asked.reason
    reply = cpu.send("download", source=reads)
    assert reply.applied and reply.version == 2, reply.reason
    graph = cpu.session.graph
    assert wait_until(lambda: graph.state.active == [graph.cc.step_index[2]])
    assert cpu.n() >= target


def test_a_read_of_a_variable_the_downloaded_fb_no_longer_has_is_e048_naming_it(
    cpu: Cpu,
) -> None:
    """The chart reads ``DB10.old``; new sources whose FB17 has no ``old`` are refused with
    E048 naming it — its preview says the very same — and the old chart and blocks run on.
    Blocks whose FB has it, and then a chart alone reading a variable only the new blocks
    have, are taken: a chart-only download reads the blocks the CPU holds now."""
    reads_old = _reading("DB10.old > 30000")
    assert cpu.send("download", source=reads_old).applied
    asked = cpu.send("download", source=reads_old, blocks={"fb17.scl": CHANGED}, preview=True)
    reply = cpu.send("download", source=reads_old, blocks={"fb17.scl": CHANGED})
    assert not asked.applied and asked.reason == reply.reason, (asked.reason, reply.reason)
    assert not reply.applied and "E048" in reply.reason, reply.reason
    assert "old is not a variable of FB17 (its outputs and static variables: n, fresh)" in (
        reply.reason
    )
    assert cpu.session.cpu.block("FB17").interface[1].type == "INT"  # the old FB17
    assert cpu.grows_by(1) and cpu.path.read_text(encoding="utf-8") == reads_old
    assert (cpu.path.parent / "fb17.scl").read_text(encoding="utf-8") == BLOCKS

    reads_fresh = _reading("DB10.fresh < 0")
    assert cpu.send("download", source=reads_fresh, blocks={"fb17.scl": CHANGED}).applied
    assert cpu.grows_by(1000)
    alone = cpu.send("download", source=_reading("DB10.fresh < -1"), preview=True)
    assert alone.applied, alone.reason
    refused = cpu.send("download", source=reads_old)
    assert not refused.applied and "old is not a variable of FB17" in refused.reason


def test_the_held_interfaces_are_built_once_and_again_only_after_a_block_download(
    cpu: Cpu,
) -> None:
    """Chart-only downloads and previews read the interfaces of the CPU's blocks as kept
    (one build); a download of blocks, and its undo, make the next chart-only download read
    the blocks the CPU holds then: ``fresh`` after the one, ``old`` again after the other."""
    held = cpu.rig.online.held_interfaces
    assert cpu.send("download", source=_reading("DB10.old > 30000"), preview=True).applied
    assert cpu.send("download", source=_reading("DB10.old > 30001")).applied
    assert cpu.send("download", source=_reading("DB10.old > 30002"), preview=True).applied
    assert held.builds == 1
    wide = CHANGED.replace("n : DINT", "n : INT")  # no narrowing back: the undo is taken
    assert cpu.send("download", source=_reading("DB10.fresh < 0"), blocks={"fb17.scl": wide})
    lacks = cpu.send("download", source=_reading("DB10.old > 30000"), preview=True)
    assert not lacks.applied and "old is not a variable of FB17" in lacks.reason
    assert cpu.send("download", source=_reading("DB10.fresh < -1")).applied
    assert held.builds == 2
    assert cpu.send("undo_download").applied  # the chart reading fresh, the same blocks
    back = cpu.send("undo_download")  # the chart reading old, and the blocks before
    assert back.applied and "S7-SCL blocks changed: fb17.scl" in back.lines, back.reason
    assert cpu.send("download", source=_reading("DB10.old > 30003"), preview=True).applied
    lacks = cpu.send("download", source=_reading("DB10.fresh < -2"), preview=True)
    assert not lacks.applied and "fresh is not a variable of FB17" in lacks.reason
    assert held.builds == 3
