"""A chart's comments stay with the element they annotate (``sequencer.text.comments``): read,
edited and written again — by the editor, a download, ``s7graph import`` of a `.s7g` —
the text keeps every comment, and a change summary does not call a comment a change."""

from __future__ import annotations

from s7graph.sequencer.change.content import ChangeRow, RenameStep, RenumberStep
from s7graph.sequencer.change.diff import summarize
from s7graph.sequencer.change.edit import apply_edit
from s7graph.sequencer.change.typed import RowFields
from s7graph.sequencer.text.comments import find_comments
from s7graph.sequencer.text.format import format_chart
from s7graph.sequencer.text.model import Chart
from s7graph.sequencer.text.parse import parse_chart, parse_file
from s7graph.sequencer.text.walk import uncommented, unlocated
from tests.paths import ROOT

EXAMPLES = sorted(ROOT.glob("examples/*/*.s7g"))

ANNOTATED = """(* Filling station.
   Two lines of block comment above the block. *)
FUNCTION_BLOCK "Fill"
  PARAMETERS := STANDARD;
VAR
  count : INT := 0;   // bottles since the last cold restart
END_VAR
// the one sequencer
SEQUENCE 1 "Main"
  INITIAL_STEP S1 "Wait // not a comment":
  END_STEP
  (* S2 opens the valve *)
  STEP S2 "Fill":
    N Q0.0;           // the valve
    S1 N count := count + 1;
  END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.0;  // a bottle is there
  // full
  TRANSITION T2 FROM S2 TO S1 := I0.1;
END_SEQUENCE
END_FUNCTION_BLOCK
// end of file
"""


def annotated() -> Chart:
    return parse_chart(ANNOTATED, "fill.s7g")


def texts(chart_text: str) -> list[str]:
    return [c.text for c in find_comments(chart_text)]


def test_every_comment_belongs_to_the_element_it_annotates() -> None:
    """Above an element: the element's ``comment``; at the end of its first line: its
    ``trailing``; after the last element: the chart's end. A ``//`` inside a quoted name is
    no comment."""
    c = annotated()
    seq = c.sequences[0]
    s1, s2 = seq.steps
    t1, t2 = seq.transitions
    assert c.comment.startswith("(* Filling station.") and c.comment.endswith("block. *)")
    assert c.vars[0].trailing == "// bottles since the last cold restart"
    assert c.vars[0].comment == ""
    assert seq.comment == "// the one sequencer"
    assert s1.name == "Wait // not a comment" and s1.comment == ""
    assert s2.comment == "(* S2 opens the valve *)"
    assert [(r.comment, r.trailing) for r in s2.actions] == [("", "// the valve"), ("", "")]
    assert (t1.trailing, t2.comment) == ("// a bottle is there", "// full")
    assert (t1.comment, t2.trailing) == ("", "")
    assert c.end_comment == "// end of file"


def test_a_chart_written_again_keeps_every_comment() -> None:
    """``format_chart`` writes each comment where it stood, above its element or at the end
    of its first line: the same comments, verbatim, and the text reads back to the same
    model."""
    c = annotated()
    written = format_chart(c)
    assert sorted(texts(written)) == sorted(texts(ANNOTATED))
    again = parse_chart(written, "fill.s7g")
    assert unlocated(again) == unlocated(c)
    assert format_chart(again) == written


def test_a_trailing_comment_comes_back_at_the_end_of_its_line() -> None:
    """An engineer's end-of-line remark is not moved above its line by an edit in the
    browser: every kind of element keeps it there, a block comment and a ``//`` after it
    on one line included."""
    text = (
        'FUNCTION_BLOCK "T" FB 3  // the block\n'
        "VAR\n  n : INT := 0;  (* pieces *)\nEND_VAR\n"
        'SEQUENCE 1 "Main"  // one\n'
        '  INITIAL_STEP S1 "Wait":  // waiting\n'
        "    N Q0.0;  (* lamp *) // green\n"
        "  END_STEP\n"
        "  STEP S2:\n  END_STEP\n"
        "  TRANSITION T1 FROM S1 TO S2 := I0.0;  // go\n"
        "  TRANSITION T2 FROM S2 TO S1;\n"
        "END_SEQUENCE\nEND_FUNCTION_BLOCK\n"
    )
    written = format_chart(parse_chart(text, "t.s7g"))
    lines = written.splitlines()
    for expected in (
        'FUNCTION_BLOCK "T" FB 3 // the block',
        "  n : INT := 0; (* pieces *)",
        'SEQUENCE 1 "Main" // one',
        '  INITIAL_STEP S1 "Wait": // waiting',
        "    N Q0.0; (* lamp *) // green",
        "  TRANSITION T1 FROM S1 TO S2 := I0.0; // go",
    ):
        assert expected in lines, (expected, written)
    assert not any(line.lstrip().startswith(("//", "(*")) for line in lines), written
    again = parse_chart(written, "t.s7g")
    assert unlocated(again) == unlocated(parse_chart(text, "t.s7g"))
    assert format_chart(again) == written


def test_the_examples_keep_their_comments_through_the_writer() -> None:
    for path in EXAMPLES:
        text = path.read_text(encoding="utf-8")
        written = format_chart(parse_file(path))
        assert sorted(texts(written)) == sorted(texts(text)), path.name
        assert unlocated(parse_chart(written, path.name)) == unlocated(parse_file(path))


def test_an_edit_keeps_the_comments_of_what_it_changes() -> None:
    """Renaming and renumbering a step, changing a row: their comments stay, in place."""
    c = annotated()
    for edit in (
        RenameStep(2, "Fill bottle"),
        RenumberStep(2, 7),
        ChangeRow(2, 0, RowFields(qualifier="N", operand="Q0.1")),
    ):
        out = apply_edit(c, edit)
        assert out.refusal is None, out.refusal
        written = format_chart(out.chart)
        assert sorted(texts(written)) == sorted(texts(ANNOTATED)), edit
        assert any(line.endswith("; // the valve") for line in written.splitlines()), edit


def test_a_change_summary_does_not_count_a_reworded_comment() -> None:
    """A download whose chart differs only in its comments changes nothing in the CPU."""
    c = annotated()
    reworded = parse_chart(ANNOTATED.replace("// full", "// the bottle is full"), "fill.s7g")
    assert reworded.sequences[0].transitions[1].comment == "// the bottle is full"
    assert summarize(c, reworded).unchanged
    assert uncommented(unlocated(reworded)) == uncommented(unlocated(c))
