"""Names in the project directory (``web.harness.project``)."""

from __future__ import annotations

from s7graph.web.harness.project import chart_file


def test_an_opened_file_becomes_a_chart_of_its_stem_or_of_its_stem_and_the_chart_chosen() -> None:
    assert chart_file("line1.xml", None, ".s7g") == "line1.s7g"
    assert chart_file("line1.xml", None, ".scl") == "line1.scl"
    assert chart_file("crane.xml", "Crane.Hoist", ".s7g") == "crane_Crane.Hoist.s7g"
    assert chart_file("two.st", "a b/c", ".scl") == "two_a_b_c.scl"
    assert chart_file("noext", None, ".s7g") == "noext.s7g"
