"""Compile diagnostics of a chart: what is wrong, where, and which element (docs/chart-format.md).

Every diagnostic carries ``file:line:col`` and the step / transition / row it concerns;
``format_diagnostic`` prints it the way compilers do::

    drill.s7g:14:5: error[E020]: S0 NC: the interlock mark C is allowed only ... (step S2 row 3)

Codes: ``E0xx`` errors (the chart does not compile), ``W1xx`` warnings. The list of codes
lives in ``CODES`` so tests and ``s7graph check`` can name them; ``Diagnostic`` is shared
with S7-SCL (``steps/diagnostics.py``).
"""

from __future__ import annotations

from typing import Final

from s7graph.steps.diagnostics import Diagnostic, error, format_diagnostic, sort_key, warning

__all__ = ["CODES", "Diagnostic", "error", "format_diagnostic", "sort_key", "warning"]

CODES: Final[dict[str, str]] = {
    # parser (sequencer/text/parse.py)
    "E001": "syntax error: unexpected token or character",
    "E002": "unexpected end of file",
    "E003": "literal that does not parse or does not fit its type",
    "E004": "unknown header option or option value",
    "E005": "action row whose operand does not fit its qualifier",
    "E006": "expression nested too deeply (more than 32 levels of operators)",
    # structure (sequencer/checks/validate.py, rules in sequencer/checks/)
    "E010": "unknown step in FROM / TO",
    "E011": "duplicate step number",
    "E012": "duplicate transition number",
    "E013": "duplicate declaration (FB variable or symbol)",
    "E014": "FB variable of a type a chart cannot hold",
    "E015": "simultaneous branch or join across sequences (only a jump reaches another)",
    # action rows
    "E020": "event / qualifier / C combination that S7-GRAPH does not allow",
    "E021": "missing value (D L CS TL TD TF need one)",
    "E022": "D / L time is not a TIME",
    "E023": "value given to a qualifier that takes none, or of the wrong type",
    "E024": "operand of the wrong kind for the qualifier (bit, timer, counter)",
    "E025": "OFF S_ALL misuse",
    "E026": "ON / OFF of an unknown step",
    # types (docs/semantics.md, "Actions" and "Conditions"; STEP7 comprehensive guide vol. 2, ch.
    # 14)
    "E030": "comparison of different or non-comparable types",
    "E031": "assignment of a value of another type",
    "E032": "operator not allowed for the operand type",
    "E033": "unknown function or wrong argument",
    "E034": "condition that is not a boolean of contacts and comparisons",
    "E035": "a coil (bit assignment) outside the permanent instructions",
    # operands
    "E040": "unknown symbol",
    "E041": "absolute address that does not parse or is out of range",
    "E042": "unknown FB variable or name",
    "E043": "Sn.X / Sn.T / Sn.U of an unknown step",
    "E044": "Tn.TT of an unknown transition",
    "E045": "write to a read-only operand (FB output, PI, step or transition attribute)",
    # calls
    "E046": "CALL of a system block s7graph lacks, or with a wrong instance or parameter",
    "E047": "CALL of a user FB or FC that does not fit the program's blocks (--blocks): "
    "unknown block or parameter, wrong direction, type or instance DB",
    "E048": 'instance DB variable read by name (DB10.Q, "T_S2".Q) of a DB that is no instance '
    "DB of the chart's calls, or not an output or in-out of its block (or a static variable "
    "of a user FB of --blocks)",
    # warnings
    "W101": "step without a way in",
    "W102": "step without a way out",
    "W103": "sequencer without an initial step",
    "W110": "more steps, transitions, paths, sequencers or condition elements than S7-GRAPH allows",
    "W120": "empty transition condition (always holds)",
    "W122": "rows marked C on a step without an interlock",
    "W130": "simultaneous branch that can never join",
    "W140": "operand beyond the memory of a default CPU (s7graph check, which knows no CPU: "
    "sequencer/checks/default_cpu.py)",
}
