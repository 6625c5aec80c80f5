"""``s7graph import`` and ``s7graph export`` on the command line: exit status, where the
chart and its symbols go, what is printed (docs/import-export.md); ``importable_files`` for the
editor's Open."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from s7graph.sequencer.exchange import importable_files
from s7graph.web.cli import main
from tests.paths import ROOT
from tests.sequencer.exchange.helpers import corpus, import_to, synthetic


def test_import_writes_the_chart_to_stdout_with_what_it_reports_on_top(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["import", str(corpus("plcopen/matiec_SFC_TEST.xml"))]) == 1
    out, err = capsys.readouterr()
    assert out.startswith("(* Imported from matiec_SFC_TEST.xml (PLCopen TC6 XML (SFC))")
    assert "matiec_SFC_TEST.xml:40:13: warning[I023]" in out.splitlines()[2]
    assert 'FUNCTION_BLOCK "MAIN_TEST"' in out
    assert err.splitlines()[-1].endswith("imported (PLCopen TC6 XML (SFC)), 3 warnings")


def test_import_without_problems_exits_0(tmp_path: Path) -> None:
    rc, out = import_to(tmp_path, corpus("simaticml/GraphEnd.xml"))
    assert rc == 0 and out.read_text().startswith("(* Imported from GraphEnd.xml")


def test_symbols_out_moves_the_symbols_to_a_table_check_reads(tmp_path: Path) -> None:
    table = tmp_path / "symbols.txt"
    rc, out = import_to(tmp_path, corpus("iec-text/matiec_sfc.txt"), "--symbols-out", str(table))
    assert rc == 1
    assert "SYMBOLS" not in out.read_text()
    assert table.read_text().splitlines() == [
        '"QX2" ; Q0.2 ; BOOL ; IEC %QX2',
        '"QX3" ; Q0.3 ; BOOL ; IEC %QX3',
        '"IX2" ; I0.2 ; BOOL ; IEC %IX2',
        '"IX3" ; I0.3 ; BOOL ; IEC %IX3',
    ]
    assert main(["check", str(out)]) == 2  # the symbols are not in the chart any more
    assert main(["check", str(out), "--symbols", str(table)]) == 0


def test_symbols_out_holds_the_tags_symbols_gave_too(tmp_path: Path) -> None:
    """A SimaticML block names tags of the PLC's tag table (``--symbols``): the table
    ``--symbols-out`` writes holds them beside the chart's own, so ``check`` needs only it."""
    given = tmp_path / "tags.txt"
    given.write_text(
        '"StepData.Values.CycleAbort" ; M5.0 ; BOOL ; x\n'
        '"StepData.Values.CurrentStep" ; MW100 ; INT ; y\n',
        encoding="utf-8",
    )
    table = tmp_path / "symbols.txt"
    source = corpus("simaticml/StepSequence.xml")
    rc, out = import_to(tmp_path, source, "--symbols", str(given), "--symbols-out", str(table))
    assert rc in (0, 1)
    assert table.read_text().splitlines()[:2] == [
        '"StepData.Values.CycleAbort" ; M5.0 ; BOOL ; x',
        '"StepData.Values.CurrentStep" ; MW100 ; INT ; y',
    ]
    assert main(["check", str(out), "--symbols", str(table)]) == 0


def test_strict_refuses_a_chart_with_constructs_left_out(tmp_path: Path) -> None:
    rc, out = import_to(tmp_path, corpus("iec-text/matiec_annexF_gravel.txt"), "--strict")
    assert rc == 2 and not out.exists()
    rc, out = import_to(tmp_path, corpus("simaticml/GraphEnd.xml"), "--strict")
    assert rc == 0 and out.exists()


def test_pou_chooses_a_chart_and_an_unknown_one_is_an_error(tmp_path: Path) -> None:
    source = corpus("plcopen/beremiz_first_steps.xml")
    assert import_to(tmp_path, source, "--pou", "CounterSFC")[0] == 1
    assert import_to(tmp_path, source, "--pou", "Nothing")[0] == 2


def test_export_refuses_an_unknown_format_and_a_chart_that_does_not_compile(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    drill = ROOT / "examples" / "drill" / "drill.s7g"
    assert main(["export", str(drill), "--to", "json", "-o", str(tmp_path / "x")]) == 2
    assert "--to must be plcopen or simaticml" in capsys.readouterr().err
    broken = tmp_path / "broken.s7g"
    broken.write_text(
        'FUNCTION_BLOCK "B"\nSEQUENCE 1\nINITIAL_STEP S1: END_STEP\n'
        "TRANSITION T1 FROM S1 TO S9 := TRUE;\nEND_SEQUENCE\nEND_FUNCTION_BLOCK\n"
    )
    assert main(["export", str(broken), "--to", "plcopen", "-o", str(tmp_path / "x")]) == 2
    assert "error[E010]" in capsys.readouterr().err


def test_importable_files_lists_what_import_reads_with_its_format(tmp_path: Path) -> None:
    for relative in (
        "plcopen/matiec_SFC_TEST.xml",
        "simaticml/GraphEnd.xml",
        "iec-text/matiec_sfc.txt",
    ):
        (tmp_path / Path(relative).name).write_bytes(corpus(relative).read_bytes())
    (tmp_path / "chart.s7g").write_text((ROOT / "examples/drill/drill.s7g").read_text())
    (tmp_path / "notes.txt").write_text("nothing to see\n")
    (tmp_path / "page.xml").write_text("<html/>")
    assert [(p.name, f) for p, f in importable_files(tmp_path)] == [
        ("GraphEnd.xml", "simaticml"),
        ("chart.s7g", "s7g"),
        ("matiec_SFC_TEST.xml", "plcopen"),
        ("matiec_sfc.txt", "iec-text"),
    ]


@pytest.mark.parametrize(
    ("name", "initial", "line"),
    [
        ("tia_unnamed_transitions.xml", 'Init="true"', 100),  # at the <Sequence>
        ("beremiz_chart_blocks.xml", 'initialStep="true"', 32),  # at its first step
    ],
)
def test_import_warns_at_once_of_a_chart_without_an_initial_step(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], name: str, initial: str, line: int
) -> None:
    """A chart whose steps are none initial never starts by itself: the import says so as
    ``check`` does — the same code and words (W103) — at the sequence in the file."""
    text = synthetic(name).read_text(encoding="utf-8")
    assert text.count(initial) == 1
    source = tmp_path / name
    source.write_text(text.replace(initial, initial.replace("true", "false")), encoding="utf-8")
    rc, out = import_to(tmp_path, source)
    assert rc == 1
    said = (
        "warning[W103]: sequence 1 has no initial step; it starts only by ON or MAN mode "
        "(sequence 1)"
    )
    err = capsys.readouterr().err
    assert re.search(rf"^{re.escape(str(source))}:{line}:\d+: {re.escape(said)}$", err, re.M), err
    main(["check", str(out)])
    checked = capsys.readouterr()
    assert said in checked.out + checked.err
