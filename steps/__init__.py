"""Step content → generated Python: conditions (transitions, interlocks, supervisions),
expressions, operands and action rows with the qualifier table (docs/semantics.md).

The syntax tree of this language is ``steps.syntax``; the chart model holds it. Import from
the module named after what it holds.
"""
