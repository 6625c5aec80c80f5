"""A broken file is one clear line naming the place — the file and the line, element or
attribute — with the importer's diagnostic code and the documented exit status; never a
Python exception's name nor a traceback (docs/import-export.md)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from s7graph.sequencer.exchange import import_chart
from s7graph.sequencer.exchange.st import MAX_TREE_DEPTH
from s7graph.sequencer.exchange.xmltree import MAX_DEPTH, MAX_WIRE_DEPTH
from s7graph.sequencer.text.format import format_expr
from s7graph.web.cli import main
from tests.sequencer.exchange.helpers import corpus

_CLASS_NAME = re.compile(r"\b[A-Z]\w*(?:Error|Exception|Iteration)\b|Traceback|internal error")

_TRUE = (
    '<FlgNet><Parts><Part Name="TrCoil" UId="21"/></Parts><Wires><Wire UId="22"><Powerrail/>'
    '<NameCon UId="21" Name="in"/></Wire></Wires></FlgNet>'
)
_COIL = (
    '<PermanentOperation><FlgNet><Parts><Access Scope="GlobalVariable" UId="{uid}"><Symbol>'
    '<Component Name="Lamp"/></Symbol></Access><Part Name="Coil" UId="22"/></Parts><Wires>'
    '<Wire UId="23"><Powerrail/><NameCon UId="22" Name="in"/></Wire>'
    '<Wire UId="24"><IdentCon UId="21"/><NameCon UId="22" Name="operand"/></Wire>'
    "</Wires></FlgNet></PermanentOperation>"
)
_ACTION = (
    '<Action Qualifier="N"><Access Scope="GlobalVariable" UId="21"><Symbol>'
    '<Component Name="Pump"/><Address Area="Output" Type="{type}" BitOffset="0" '
    'Informative="true"/></Symbol></Access></Action>'
)


def _link(a: str, b: str, kind: str = "Direct") -> str:
    return (
        f"<Connection><NodeFrom>{a}</NodeFrom><NodeTo>{b}</NodeTo>"
        f"<LinkType>{kind}</LinkType></Connection>"
    )


def simaticml(
    *,
    number: str = "1",
    ref: str = "1",
    action: str = "",
    post: str = "",
    encoding: str = "utf-8",
) -> str:
    """A GRAPH FB of two steps and two transitions as TIA exports it (line 8: step 1,
    line 14: the connection from step 1, line 19: the permanent operations)."""
    return f"""<?xml version="1.0" encoding="{encoding}"?>
<Document><SW.Blocks.FB ID="0"><AttributeList><Name>Seq</Name><Number>1</Number>
<ProgrammingLanguage>GRAPH</ProgrammingLanguage></AttributeList><ObjectList>
<SW.Blocks.CompileUnit ID="1"><AttributeList><NetworkSource>
<Graph xmlns="http://www.siemens.com/automation/Openness/SW/NetworkSource/Graph/v5">
<PreOperations/>
<Sequence><Steps>
<Step Number="{number}" Init="true" Name="Idle"><Actions>{action}</Actions></Step>
<Step Number="2" Init="false" Name="Run"/>
</Steps><Transitions>
<Transition Name="Go" Number="1">{_TRUE}</Transition>
<Transition Name="Back" Number="2">{_TRUE}</Transition>
</Transitions><Branches/><Connections>
{_link(f'<StepRef Number="{ref}"/>', '<TransitionRef Number="1"/>')}
{_link('<TransitionRef Number="1"/>', '<StepRef Number="2"/>')}
{_link('<StepRef Number="2"/>', '<TransitionRef Number="2"/>')}
{_link('<TransitionRef Number="2"/>', '<StepRef Number="1"/>', "Jump")}
</Connections></Sequence>
<PostOperations>{post}</PostOperations>
</Graph></NetworkSource></AttributeList></SW.Blocks.CompileUnit></ObjectList></SW.Blocks.FB>
</Document>
"""


def run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], name: str, text: str, *extra: str
) -> tuple[int, list[str]]:
    """``s7graph import`` of ``text`` written to ``name``: (exit status, stderr lines); no
    Python exception's name in what it prints."""
    source = tmp_path / name
    source.write_text(text, encoding="utf-8")
    rc = main(["import", str(source), "-o", str(tmp_path / "out.s7g"), *extra])
    out, err = capsys.readouterr()
    assert not _CLASS_NAME.search(out + err), err
    return rc, err.splitlines()


def test_the_minimal_simaticml_of_these_tests_imports(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rc, err = run(tmp_path, capsys, "ok.xml", simaticml(post=_COIL.format(uid=21)))
    assert rc == 1 and [line.split(": ")[1] for line in err[:-1]] == ["warning[I032]"]
    assert '"Lamp" := TRUE;' in (tmp_path / "out.s7g").read_text()


def test_an_initial_step_without_a_pou_header_is_a_located_parse_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rc, err = run(tmp_path, capsys, "a.st", "INITIAL_STEP A: END_STEP\nEND_PROGRAM\n")
    assert rc == 2
    assert err[0].startswith(f"{tmp_path / 'a.st'}:1:1: error[I001]: the IEC text does not parse")
    assert err[1] == f"{tmp_path / 'a.st'}: not imported"


def test_an_encoding_the_xml_reader_cannot_decode_is_named_where_it_is_declared(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    for encoding in ("utf-88", "shift_jis", "rot13"):
        rc, err = run(tmp_path, capsys, "enc.xml", simaticml(encoding=encoding))
        assert rc == 2
        assert err[0] == (
            f"{tmp_path / 'enc.xml'}:1:31: error[I001]: the XML declaration names the "
            f"encoding '{encoding}', which this import cannot decode: save the file as UTF-8"
        )


def test_a_step_number_that_is_not_a_number_names_the_step(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rc, err = run(tmp_path, capsys, "num.xml", simaticml(number="1$"))
    assert rc == 2
    assert err == [
        f'{tmp_path / "num.xml"}:8:1: error[I013]: step "Idle": Number="1$" is not a number '
        "(GRAPH numbers steps 1, 2, …)",
        f"{tmp_path / 'num.xml'}: not imported",
    ]


@pytest.mark.parametrize(
    ("number", "said"),
    [
        ("-5", "Number -5 is outside 1..32767"),
        ("99999999999", "Number 99999999999 is outside 1..32767"),
        ("2", 'Number 2 is step "Idle"\'s too'),
    ],
)
def test_a_step_number_out_of_range_or_taken_twice_names_the_step(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], number: str, said: str
) -> None:
    text = simaticml(number=number, ref=number)
    rc, err = run(tmp_path, capsys, "num.xml", text)
    assert rc == 2
    step = "Run" if number == "2" else "Idle"
    assert f'error[I013]: step "{step}": {said} (GRAPH numbers steps 1, 2, …)' in err[0]


def test_a_transition_number_taken_twice_is_refused_not_dropped(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    text = simaticml().replace('Name="Back" Number="2"', 'Name="Back" Number="1"')
    rc, err = run(tmp_path, capsys, "dup.xml", text)
    assert rc == 2
    assert 'error[I013]: transition "Back": Number 1 is transition "Go"\'s too' in err[0]


def test_a_connection_naming_a_step_by_a_symbol_names_the_reference(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rc, err = run(tmp_path, capsys, "ref.xml", simaticml(ref="Symbol"))
    assert rc == 2
    assert err[0] == (
        f'{tmp_path / "ref.xml"}:14:23: error[I010]: a connection\'s StepRef Number="Symbol" '
        "is not a number (a connection names its ends by number)"
    )
    assert len(err) == 2  # that line and "not imported": no consequential errors


def test_a_permanent_coil_wired_to_no_access_is_left_out_at_its_wire(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rc, err = run(tmp_path, capsys, "coil.xml", simaticml(post=_COIL.format(uid=99)))
    assert rc == 1
    assert err[0].startswith(f"{tmp_path / 'coil.xml'}:19:")
    assert err[0].endswith(
        'warning[I022]: permanent operation not imported: the coil\'s operand is UId "21", '
        "which no Access has"
    )
    assert "PERMANENT" not in (tmp_path / "out.s7g").read_text().split("*)", 1)[1]


def test_an_address_type_the_import_does_not_read_leaves_the_row_out_at_its_access(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rc, err = run(tmp_path, capsys, "addr.xml", simaticml(action=_ACTION.format(type="Bool#")))
    assert rc == 1
    assert err[0] == (
        f'{tmp_path / "addr.xml"}:8:73: warning[I023]: step 1: action row with "Pump" not '
        "imported: an absolute address the importer does not read "
        '(Area="Output" Type="Bool#" BitOffset="0")'
    )
    rc, _ = run(
        tmp_path, capsys, "addr.xml", simaticml(action=_ACTION.format(type="Bool#")), "--strict"
    )
    assert rc == 2
    rc, _ = run(tmp_path, capsys, "addr.xml", simaticml(action=_ACTION.format(type="Bool")))
    assert rc == 0


def test_a_plcopen_transition_position_that_is_not_a_number_names_the_position(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    text = corpus("plcopen/beremiz_first_steps.xml").read_text(encoding="utf-8")
    m = re.search(r'<transition localId="\d+"[^>]*>\s*<position x="(\d+)"', text)
    assert m is not None
    broken = text[: m.start(1)] + "X$" + text[m.end(1) :]
    rc, err = run(tmp_path, capsys, "pos.xml", broken)
    assert rc == 2
    line = text.count("\n", 0, m.start(1)) + 1
    [error] = [e for e in err if "error[" in e]
    assert error.startswith(f"{tmp_path / 'pos.xml'}:{line}:")
    assert error.endswith(
        'error[I013]: a transition\'s position x="X$" is not a number (it orders the paths '
        "of an alternative branch, leftmost first)"
    )


def test_a_folder_given_as_a_file_says_so(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = tmp_path / "dir.s7g"
    folder.mkdir()
    source = tmp_path / "ok.xml"
    source.write_text(simaticml(), encoding="utf-8")
    for args, doing in (
        (["import", "--symbols", str(folder), str(source)], "read symbols"),
        (["import", str(source), "-o", str(folder)], "write"),
        (
            ["import", str(source), "-o", str(tmp_path / "c.s7g"), "--symbols-out", str(folder)],
            "write",
        ),
        (["export", str(tmp_path / "c.s7g"), "--to", "plcopen", "-o", str(folder)], "write"),
    ):
        if args[0] == "export":
            assert main(["import", str(source), "-o", str(tmp_path / "c.s7g")]) == 0
            capsys.readouterr()
        assert main(args) == 2
        err = capsys.readouterr().err
        assert err == f"s7graph: error: cannot {doing} {folder}: is a folder, not a file\n"


def test_an_unexpected_failure_of_an_importer_is_one_line_naming_the_file_and_format(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    def broken(*_: object, **__: object) -> None:
        raise ValueError("zip() argument 2 is longer than argument 1")

    monkeypatch.setattr("s7graph.web.cli.exchange.import_file", broken)
    rc, err = run(tmp_path, capsys, "any.xml", simaticml())
    assert rc == 2
    assert err == [
        f"s7graph: error: {tmp_path / 'any.xml'}: not imported: it cannot be read as "
        "TIA Portal SimaticML (S7-GRAPH)"
    ]
    assert not (tmp_path / "out.s7g").exists()


def _at(text: str, line: int, col: int) -> str:
    """The text of ``text`` from line ``line``, column ``col`` (both from 1) on."""
    return text.splitlines()[line - 1][col - 1 :]


@pytest.mark.parametrize(("levels", "refused"), [(MAX_DEPTH - 8, False), (3000, True)])
def test_elements_nested_too_deeply_are_refused_at_the_first_element_past_the_limit(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], levels: int, refused: bool
) -> None:
    """``PostOperations`` is 8 elements deep: ``levels`` elements inside it reach the limit
    and import; deeper, the first element past the limit is named by line and column."""
    text = simaticml(post="<X>" * levels + "</X>" * levels)
    rc, err = run(tmp_path, capsys, "deep.xml", text)
    if not refused:
        assert rc == 0, err
        return
    assert rc == 2
    m = re.fullmatch(r".*deep\.xml:(\d+):(\d+): error\[I001\]: (.*)", err[0])
    assert m is not None, err
    assert m[3] == (
        f"elements nest deeper than {MAX_DEPTH} levels here (an import reads at most "
        f"{MAX_DEPTH}; TIA and PLCopen files nest fewer than 20)"
    )
    line, col = int(m[1]), int(m[2])  # the first <X> past the limit, and those in it
    assert line == 19
    assert _at(text, line, col) == "<X>" * (levels - (MAX_DEPTH - 8)) + "</X>" * levels + (
        "</PostOperations>"
    )


def test_an_st_text_nested_too_deeply_is_refused_where_it_passes_the_limit(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """300 NOTs inside each other go past ``MAX_TREE_DEPTH``: the error is at one of them,
    on the condition's line, not a file that "nests too deeply" somewhere."""
    condition = "NOT " * 300 + "a"
    text = (
        "FUNCTION_BLOCK F\nVAR a : BOOL; END_VAR\nINITIAL_STEP S1: END_STEP\nSTEP S2: END_STEP\n"
        f"TRANSITION FROM S1 TO S2 := {condition};\nEND_TRANSITION\n"
        "TRANSITION FROM S2 TO S1 := a;\nEND_TRANSITION\nEND_FUNCTION_BLOCK\n"
    )
    rc, err = run(tmp_path, capsys, "deep.st", text)
    assert rc == 2
    m = re.fullmatch(r".*deep\.st:(\d+):(\d+): error\[I001\]: (.*)", err[0])
    assert m is not None, err
    assert m[3] == (
        f"the IEC text nests deeper than {MAX_TREE_DEPTH} levels here (an import reads at "
        f"most {MAX_TREE_DEPTH})"
    )
    assert int(m[1]) == 5 and _at(text, 5, int(m[2])).startswith("NOT NOT")


def _iec(condition: str) -> str:
    """An IEC textual SFC of two steps; ``condition`` is T1's, on line 5 at column 29."""
    return (
        "FUNCTION_BLOCK F\nVAR a : BOOL; n : INT; END_VAR\nINITIAL_STEP S1: END_STEP\n"
        f"STEP S2: END_STEP\nTRANSITION FROM S1 TO S2 := {condition};\nEND_TRANSITION\n"
        "TRANSITION FROM S2 TO S1 := a;\nEND_TRANSITION\nEND_FUNCTION_BLOCK\n"
    )


def test_a_flat_chain_past_the_limit_is_refused_as_an_expression_of_so_many_terms(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """20,000 ANDs in a row nest nothing: the refusal counts the terms, where they start."""
    rc, err = run(tmp_path, capsys, "flat.st", _iec(" AND ".join(["a"] * 20_000)))
    assert rc == 2
    assert err[0].endswith(
        "flat.st:5:29: error[I001]: the IEC text has an expression of 20,000 terms joined by "
        f"AND here: each is a level, and an import reads at most {MAX_TREE_DEPTH} (split the "
        "expression)"
    )


def test_a_syntax_error_quotes_at_most_forty_characters_of_the_text(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rc, err = run(tmp_path, capsys, "bad.st", _iec("a AND AND " + " AND ".join(["a"] * 2_000)))
    assert rc == 2
    said = err[0].split("does not parse: unexpected ", 1)[1]
    assert said == repr("a AND a AND a AND a AND a AND a AND a...")


@pytest.mark.parametrize("digits", ["١٢", "１２"])
def test_a_number_of_non_ascii_digits_is_a_parse_error_not_twelve(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], digits: str
) -> None:
    """IEC 61131-3 numbers have the digits 0-9 (section 2.2.1): another script's digits are
    not read as 12 but refused where they stand."""
    rc, err = run(tmp_path, capsys, "digits.st", _iec(f"n = {digits}"))
    assert rc == 2
    assert (
        f"digits.st:5:33: error[I001]: the IEC text does not parse: unexpected '{digits}"
        in (err[0])
    )


def _lad(nots: int, contacts: int = 1) -> str:
    """A transition's LAD network: ``contacts`` contacts in series on the power rail, then
    ``nots`` NOT boxes one after another, each part on a line of its own."""
    parts = ['<Part Name="TrCoil" UId="21"/>']
    wires, prev, uid = [], "", 100
    for k in range(contacts):
        parts.append(
            f'<Access Scope="GlobalVariable" UId="{uid}"><Symbol><Component Name="t{k}"/>'
            f'</Symbol></Access><Part Name="Contact" UId="{uid + 1}"/>'
        )
        src = f'<NameCon UId="{prev}" Name="out"/>' if prev else "<Powerrail/>"
        wires += [
            f'<Wire UId="{uid + 2}"><IdentCon UId="{uid}"/>'
            f'<NameCon UId="{uid + 1}" Name="operand"/></Wire>',
            f'<Wire UId="{uid + 3}">{src}<NameCon UId="{uid + 1}" Name="in"/></Wire>',
        ]
        prev, uid = str(uid + 1), uid + 4
    for _ in range(nots):
        parts.append(f'<Part Name="Not" UId="{uid}"/>')
        wires.append(
            f'<Wire UId="{uid + 1}"><NameCon UId="{prev}" Name="out"/>'
            f'<NameCon UId="{uid}" Name="in"/></Wire>'
        )
        prev, uid = str(uid), uid + 2
    wires.append(
        f'<Wire UId="{uid}"><NameCon UId="{prev}" Name="out"/><NameCon UId="21" Name="in"/></Wire>'
    )
    return (
        "<FlgNet><Parts>\n"
        + "\n".join(parts)
        + "\n</Parts><Wires>"
        + "".join(wires)
        + "</Wires></FlgNet>"
    )


@pytest.mark.parametrize(("nots", "refused"), [(MAX_WIRE_DEPTH - 1, False), (500, True)])
def test_a_condition_wired_through_too_many_elements_is_refused_at_the_one_past_the_limit(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], nots: int, refused: bool
) -> None:
    """A value flowing through NOT after NOT: up to ``MAX_WIRE_DEPTH`` elements it is read,
    beyond, the element past the limit is named by its line."""
    text = simaticml().replace(_TRUE, _lad(nots), 1)
    rc, err = run(tmp_path, capsys, "wired.xml", text)
    if not refused:
        assert rc == 1 and "error" not in " ".join(err), err
        return
    assert rc == 2
    m = re.fullmatch(r".*wired\.xml:(\d+):(\d+): error\[I012\]: (.*)", err[0])
    assert m is not None, err
    assert m[3] == (
        f"transition 1: a value that flows through more than {MAX_WIRE_DEPTH} elements one "
        f"after another (an import reads at most {MAX_WIRE_DEPTH})"
    )
    assert _at(text, int(m[1]), int(m[2])).startswith('<Part Name="Not"')


def test_a_rung_of_hundreds_of_contacts_in_series_imports() -> None:
    """Contacts in series are one chain, read without recursion and built as the parser
    builds a written chain: 500 of them are a condition of 500 operands."""
    text = simaticml().replace(_TRUE, _lad(0, contacts=500), 1)
    chart = import_chart(text.encode(), "long.xml").chart
    condition = chart.all_transitions()[0].condition
    assert condition is not None
    assert format_expr(condition, chains=True) == " AND ".join(f'"t{k}"' for k in range(500))
