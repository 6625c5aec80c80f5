"""Bad input is one clear, located error, never a traceback; byte order marks, CRLF line
ends, namespaces and their prefixes, the old ``tc6.xsd`` schema read as the rest
(docs/import-export.md)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from s7graph.sequencer.exchange import ImportFailed, detect_format, import_chart
from s7graph.sequencer.text.walk import unlocated
from s7graph.web.cli import main
from tests.sequencer.exchange.helpers import codes, corpus


def failure(data: bytes, file: str = "bad.xml") -> list[tuple[str, int, int]]:
    with pytest.raises(ImportFailed) as info:
        import_chart(data, file)
    return [(d.code, d.loc.line, d.loc.col) for d in info.value.diagnostics]


def test_bom_and_crlf_change_nothing_in_textual_sfc() -> None:
    plain = corpus("iec-text/matiec_sfc.txt").read_bytes()
    dressed = b"\xef\xbb\xbf" + plain.replace(b"\n", b"\r\n")
    a, b = import_chart(plain, "f.txt"), import_chart(dressed, "f.txt")
    assert unlocated(a.chart) == unlocated(b.chart)
    assert codes(a.problems) == codes(b.problems)


def test_bom_and_crlf_change_nothing_in_xml_and_lines_stay_right() -> None:
    plain = corpus("plcopen/matiec_SFC_TEST.xml").read_bytes()
    dressed = b"\xef\xbb\xbf" + plain.replace(b"\n", b"\r\n")
    a, b = import_chart(plain, "f.xml"), import_chart(dressed, "f.xml")
    assert unlocated(a.chart) == unlocated(b.chart)
    assert codes(a.problems) == codes(b.problems) == [("I023", 40), ("I023", 53), ("I024", 783)]


@pytest.mark.parametrize(
    ("relative", "codec"),
    [
        ("iec-text/matiec_sfc.txt", "utf-16"),  # Notepad's "Unicode": a BOM, little endian
        ("plcopen/matiec_SFC_TEST.xml", "utf-16"),
        ("plcopen/matiec_SFC_TEST.xml", "utf-16-be"),  # no BOM: told by its "<?"
        ("simaticml/GraphBranch2.xml", "utf-32"),
    ],
)
def test_a_file_saved_in_utf16_or_utf32_reads_as_in_utf8(relative: str, codec: str) -> None:
    """A file saved as "Unicode" (XML names UTF-16 in its declaration) is the same chart,
    its problems on the same lines, and ``importable_files`` knows its format."""
    plain = corpus(relative).read_bytes()
    text = re.sub('encoding="utf-8"', f'encoding="{codec}"', plain.decode("utf-8-sig"), flags=re.I)
    wide = text.replace("\n", "\r\n").encode(codec)
    assert detect_format(wide) == detect_format(plain)
    a, b = import_chart(plain, "f.xml"), import_chart(wide, "f.xml")
    assert unlocated(a.chart) == unlocated(b.chart)
    assert codes(a.problems) == codes(b.problems)


@pytest.mark.parametrize(
    "namespace",
    ["http://www.plcopen.org/xml/tc6_0200", "http://www.plcopen.org/xml/tc6_0201"],
)
def test_every_plcopen_namespace_reads_the_same(namespace: str) -> None:
    old = corpus("plcopen/matiec_SFC_TEST.xml").read_bytes()  # the old tc6.xsd namespace
    new = old.replace(b"http://www.plcopen.org/xml/tc6.xsd", namespace.encode())
    assert unlocated(import_chart(new, "f.xml").chart) == unlocated(
        import_chart(old, "f.xml").chart
    )


def test_a_namespace_prefix_on_every_element_reads_the_same() -> None:
    text = corpus("plcopen/beremiz_first_steps.xml").read_text(encoding="utf-8")
    ns = "http://www.plcopen.org/xml/tc6_0201"
    prefixed = text.replace(f'xmlns="{ns}"', f'xmlns:p="{ns}"')
    prefixed = prefixed.replace("<", "<p:").replace("<p:/", "</p:").replace("<p:?", "<?")
    prefixed = prefixed.replace("<p:![CDATA[", "<![CDATA[").replace("<p:xhtml:", "<xhtml:")
    prefixed = prefixed.replace("</p:xhtml:", "</xhtml:")
    a = import_chart(text.encode(), "f.xml").chart
    b = import_chart(prefixed.encode(), "f.xml").chart
    assert unlocated(a) == unlocated(b)


def test_merge_conflict_markers_are_one_error_at_their_line() -> None:
    lines = corpus("plcopen/beremiz_first_steps.xml").read_bytes().split(b"\n")
    lines[100:100] = [b"<<<<<<< HEAD", b"x", b"=======", b"y", b">>>>>>> branch"]
    assert failure(b"\n".join(lines)) == [("I003", 101, 1)]


def test_malformed_xml_is_one_error_where_the_parser_stopped() -> None:
    data = corpus("plcopen/beremiz_first_steps.xml").read_bytes()[:5000]
    [(code, line, col)] = failure(data)
    assert code == "I001" and line > 100 and col >= 1


def test_entities_are_refused_not_expanded() -> None:
    bomb = (
        b'<?xml version="1.0"?>\n<!DOCTYPE project [<!ENTITY a "aaaaaaaaaa">'
        b'<!ENTITY b "&a;&a;&a;&a;&a;&a;&a;&a;">]>\n'
        b'<project xmlns="http://www.plcopen.org/xml/tc6_0201">&b;</project>'
    )
    assert [c for c, _, _ in failure(bomb)] == ["I002"]


def test_text_that_is_no_chart_says_so() -> None:
    assert [c for c, _, _ in failure(b"hello world\n", "notes.txt")] == ["I001"]
    assert [c for c, _, _ in failure(b"<html><body/></html>", "page.xml")] == ["I001"]


def test_textual_sfc_syntax_error_is_located() -> None:
    text = b"PROGRAM P\nVAR a : BOOL; END_VAR\nINITIAL_STEP S: END_STEP\nTRANSITION FROM S TO\n"
    with pytest.raises(ImportFailed) as info:
        import_chart(text, "p.st")
    [d] = info.value.diagnostics
    assert (d.code, d.loc.line) == ("I001", 4) and "ends too early" in d.message


def test_an_il_condition_or_an_unknown_step_means_no_chart() -> None:
    text = (
        b"PROGRAM P\nVAR a : BOOL; END_VAR\nINITIAL_STEP S: END_STEP\nSTEP T: END_STEP\n"
        b"TRANSITION FROM S TO T : LD a\nEND_TRANSITION\n"
        b"TRANSITION FROM T TO Nowhere := a; END_TRANSITION\nEND_PROGRAM\n"
    )
    assert [(c, line) for c, line, _ in failure(text, "p.st")] == [("I012", 5), ("I010", 7)]


def test_the_command_line_reports_failures_as_lines_not_tracebacks(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = tmp_path / "broken.xml"
    bad.write_bytes(b'<project xmlns="http://www.plcopen.org/xml/tc6_0201"><types>')
    assert main(["import", str(bad), "-o", str(tmp_path / "out.s7g")]) == 2
    err = capsys.readouterr().err
    assert f"{bad}:1:" in err and "error[I001]" in err and "Traceback" not in err
    assert not (tmp_path / "out.s7g").exists()
    assert main(["import", str(tmp_path / "missing.xml")]) == 2
    assert "cannot read" in capsys.readouterr().err


CORPUS_FILES = [
    "plcopen/matiec_SFC_TEST.xml",
    "plcopen/beremiz_traffic_light.xml",
    "simaticml/StepSequence.xml",
    "iec-text/matiec_annexF_gravel.txt",
]


@pytest.mark.parametrize("relative", CORPUS_FILES)
def test_damaged_files_give_a_chart_or_located_problems_never_an_exception(relative: str) -> None:
    """Cut, spliced or sprinkled with markup characters, a file still imports or fails with
    its problems listed — nothing else escapes."""
    import random

    data = corpus(relative).read_bytes()
    rng = random.Random(relative)
    for trial in range(12):
        d = bytearray(data)
        if trial % 3 == 0:
            d = d[: rng.randrange(len(d))]
        elif trial % 3 == 1:
            for _ in range(5):
                d[rng.randrange(len(d))] = rng.choice(b'<>"&;:=()ab01 \n')
        else:
            i = rng.randrange(len(d))
            del d[i : i + rng.randrange(200)]
        try:
            result = import_chart(bytes(d), "damaged")
        except ImportFailed as exc:
            assert exc.diagnostics and all(x.loc.line >= 1 for x in exc.diagnostics)
        else:
            assert result.chart.sequences
