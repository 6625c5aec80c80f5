"""The chart's checking: the validator (``validate``) running the rules by topic
(``structure``, ``rows``, ``types``, sharing ``context``), and the diagnostics they report
(``diagnostics``: codes, places, the compiler-style line).

Import from the module named after what it holds (``s7graph.sequencer.checks.validate``).
"""
