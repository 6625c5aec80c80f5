"""One diagnostic for charts and S7-SCL sources: the same text, two orders."""

from __future__ import annotations

from s7graph.engine.errors import SourceLocation
from s7graph.sequencer.checks import diagnostics as chart
from s7graph.steps.diagnostics import errors_first, format_diagnostic, sort_key
from s7graph.steps.scl import diagnostics as scl


def test_a_chart_and_an_scl_source_report_the_same_diagnostic_type() -> None:
    assert chart.Diagnostic is scl.Diagnostic


def test_a_diagnostic_prints_file_line_column_severity_code_and_element() -> None:
    loc = SourceLocation("mix.scl", 14, 5)
    assert format_diagnostic(scl.error("E220", "cannot assign", loc, "FB17")) == (
        "mix.scl:14:5: error[E220]: cannot assign (FB17)"
    )
    assert format_diagnostic(chart.warning("W101", "no way in", loc)) == (
        "mix.scl:14:5: warning[W101]: no way in"
    )


def test_a_chart_lists_in_source_order_and_scl_lists_errors_first() -> None:
    late_error = scl.error("E201", "bad", SourceLocation("a.scl", 9, 1))
    early_warning = scl.warning("W301", "unused", SourceLocation("a.scl", 2, 1))
    both = [late_error, early_warning]
    assert sorted(both, key=sort_key) == [early_warning, late_error]
    assert sorted(both, key=errors_first) == [late_error, early_warning]
    assert chart.sort_key is sort_key and scl.sort_key is errors_first
