"""What an IEC 61131-3 SFC construct becomes in GRAPH: the tables the importer reads and
docs/import-export.md shows (``markdown_tables``).

Sources: IEC 61131-3 ed.3 §6.7.4 (action qualifiers); matiec's runtime
(``stage4/generate_c/generate_c_sfc.cc``: an action is active in the call its association says, its
body runs while it is active, a Boolean action variable is written from the action's state);
S7-GRAPH action rows (docs/semantics.md, "Actions": the event × qualifier table of
``steps.qualifiers``). A construct is mapped only where GRAPH has an exact equivalent; otherwise the
importer leaves it out and says so, with its place in the file.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Final

__all__ = ["CONSTRUCTS", "FUNCTIONS", "QUALIFIERS", "TYPES", "QualifierRule", "markdown_tables"]


@dataclass(frozen=True, slots=True)
class QualifierRule:
    """IEC qualifier ``iec``: ``variable`` is the GRAPH row of a Boolean action variable
    (``N`` ``S`` ``R`` ``D`` ``L``, or ``S1 N`` for a one-call pulse), None when there is no
    exact equivalent; ``body`` is the event under which the rows of an action body run
    ("" = every call while the step is active, ``S1`` once on activation, ``S0`` once on
    deactivation), None when there is none; ``gate`` is how a bit assignment of a body is
    gated in the permanent instructions (``X``: while the step is active, ``P``: in the
    activation call), "" when it cannot be."""

    iec: str
    meaning: str
    variable: str | None
    body: str | None
    gate: str
    timed: bool = False
    why: str = ""


QUALIFIERS: Final[dict[str, QualifierRule]] = {
    q.iec: q
    for q in (
        QualifierRule("N", "non-stored: while the step is active", "N", "", "X"),
        QualifierRule(
            "S",
            "set (stored) until an R",
            "S",
            None,
            "",
            why="a stored action body keeps running after its step; GRAPH rows "
            "act only while their step is active",
        ),
        QualifierRule(
            "R",
            "reset a stored action",
            "R",
            None,
            "",
            why="only stored bodies need a reset, and they have no equivalent",
        ),
        QualifierRule("P", "pulse: once, when the step becomes active", "S1 N", "S1", "P"),
        QualifierRule("P1", "pulse on activation (IEC ed.3)", "S1 N", "S1", "P"),
        QualifierRule(
            "P0",
            "pulse on deactivation (IEC ed.3)",
            None,
            "S0",
            "",
            why="a GRAPH S0 row on a bit sets it for good, it is not a pulse",
        ),
        QualifierRule(
            "D",
            "time delayed: active after the time, while the step is",
            "D",
            None,
            "",
            timed=True,
            why="GRAPH D and L act on bits only",
        ),
        QualifierRule(
            "L",
            "time limited: active for the time, at most while the step is",
            "L",
            None,
            "",
            timed=True,
            why="GRAPH D and L act on bits only",
        ),
        QualifierRule(
            "SD",
            "stored and time delayed",
            None,
            None,
            "",
            timed=True,
            why="no stored timed rows in GRAPH",
        ),
        QualifierRule(
            "DS",
            "delayed and stored",
            None,
            None,
            "",
            timed=True,
            why="no stored timed rows in GRAPH",
        ),
        QualifierRule(
            "SL",
            "stored and time limited",
            None,
            None,
            "",
            timed=True,
            why="no stored timed rows in GRAPH",
        ),
    )
}

# IEC elementary types → GRAPH types. ``exact`` False: the nearest wider GRAPH type, with a
# warning (S7 has no unsigned or 64-bit types).
TYPES: Final[dict[str, tuple[str, bool]]] = {
    "BOOL": ("BOOL", True),
    "BYTE": ("BYTE", True),
    "WORD": ("WORD", True),
    "DWORD": ("DWORD", True),
    "INT": ("INT", True),
    "DINT": ("DINT", True),
    "REAL": ("REAL", True),
    "TIME": ("TIME", True),
    "DATE": ("DATE", True),
    "TIME_OF_DAY": ("TIME_OF_DAY", True),
    "TOD": ("TIME_OF_DAY", True),
    "DATE_AND_TIME": ("DATE_AND_TIME", True),
    "DT": ("DATE_AND_TIME", True),
    "CHAR": ("CHAR", True),
    "STRING": ("STRING", True),
    "S5TIME": ("S5TIME", True),
    "SINT": ("INT", False),
    "USINT": ("INT", False),
    "UINT": ("DINT", False),
    "UDINT": ("DINT", False),
    "LINT": ("DINT", False),
    "ULINT": ("DINT", False),
    "LREAL": ("REAL", False),
    "LWORD": ("DWORD", False),
    "LTIME": ("TIME", False),
}

# IEC standard functions with an exact GRAPH function (IEC name → GRAPH name); AND OR XOR
# with several inputs and NOT are written as operators.
FUNCTIONS: Final[dict[str, str]] = {
    "ABS": "ABS",
    "SQRT": "SQRT",
    "LN": "LN",
    "EXP": "EXP",
    "SIN": "SIN",
    "COS": "COS",
    "TAN": "TAN",
    "ASIN": "ASIN",
    "ACOS": "ACOS",
    "ATAN": "ATAN",
    "INT_TO_DINT": "INT_TO_DINT",
    "DINT_TO_REAL": "DINT_TO_REAL",
}

# Everything else, for docs/import-export.md: (IEC construct, GRAPH, note).
CONSTRUCTS: Final[tuple[tuple[str, str, str], ...]] = (
    (
        "step, initial step",
        "STEP / INITIAL_STEP, numbered in the order written",
        "the IEC name is the step's name; s7graph's own export keeps numbers",
    ),
    (
        "transition with an ST condition",
        "TRANSITION … := condition",
        "`x = TRUE` → `x`, `x = FALSE` → `NOT x`, `OR(a, b, c)` → `a OR b OR c`",
    ),
    ("condition wired from contacts, AND, OR, NOT (LD/FBD)", "the same condition", ""),
    ("named transition (ST, LD, FBD body)", "its condition", ""),
    (
        "several transitions from one step",
        "an alternative branch; priority: PRIORITY, then left to right (x), then as written",
        "IEC without priority may switch several paths; GRAPH switches exactly one",
    ),
    ("`TO (a, b)`, `FROM (a, b)`", "simultaneous divergence, join", ""),
    ("jump step", "a jump (TO the target step)", "into another chart of the POU too"),
    ("several charts in one POU", "one SEQUENCE each", "in the order of their first step"),
    (
        "variable (VAR, VAR_INPUT, VAR_OUTPUT, VAR_EXTERNAL)",
        "FB variable (VAR)",
        "a GRAPH FB has no further pins; an external takes its global's value",
    ),
    (
        "located variable (`AT %IX0.1`)",
        'symbol `"name" : I0.1`',
        "unless it has an "
        "initial value or is an input the chart writes: then an FB variable (S7 re-reads "
        "inputs each cycle and starts outputs at 0)",
    ),
    ("`x := TRUE` / `x := FALSE` in an action", "`S x` / `R x` (with the qualifier's event)", ""),
    ("`n := expr` (not a bit) in an action", "`N n := expr`", ""),
    (
        "`x := bit expression` in an action",
        "PERMANENT AFTER `x := gate AND (…) OR NOT gate AND x`",
        "gate: `Sn.X` (N), a one-call pulse of the step (P); GRAPH writes bits "
        "from conditions only in permanent instructions",
    ),
    ("set / reset coil of an action network", "PERMANENT AFTER `S x := gate AND …`", ""),
    (
        "statements of a textual POU body beside its SFC",
        "PERMANENT BEFORE",
        "run every call, before the chart",
    ),
    (
        "call of a TON, TOF, TP, CTU, CTD or CTUD instance (ST, and FBD action bodies)",
        "`CALL SFB n, DB m (…)` (in the action's row, or PERMANENT BEFORE from the POU body)",
        "each instance an instance DB of its own: the `n` of a name `…_DB<n>` (as "
        "s7graph's PLCopen export writes them), else the next free from DB 100; IEC's `LD` "
        "is S7's `LOAD`; every output not given with `=>` written to an FB variable: "
        "`TON3.Q` reads `TON3_Q`",
    ),
    (
        "other FB instances (R_TRIG, SR …), and calls in FBD networks of the POU body",
        "not imported",
        "the CPU's system blocks are the IEC timers and counters; a read of an output of an "
        "instance never called is reported; an array element `A[1]` is the FB variable `A_1`",
    ),
    ("IF, CASE, FOR, WHILE, REPEAT", "not imported", "GRAPH rows are single instructions"),
    ("IL action bodies", "not imported", ""),
    ("IL transition conditions, macro steps", "no chart (an error)", "a path needs them"),
    (
        "CODESYS entry / active / exit step actions",
        "S1 rows / rows / S0 rows",
        "CODESYS files import with `ORDER := CODESYS` (actions before transitions)",
    ),
)


def _row(cells: tuple[str, ...]) -> str:
    return "| " + " | ".join(cells) + " |"


def markdown_tables() -> str:
    """The tables of docs/import-export.md: qualifiers, then the other constructs."""
    lines = [
        "| IEC qualifier | meaning | Boolean action variable | action body |",
        "|---|---|---|---|",
    ]
    for q in QUALIFIERS.values():
        var = f"`{q.variable}`" if q.variable else "not imported"
        if q.variable and q.timed:
            var = f"`{q.variable} x, t`"
        if q.body is None:
            body = "not imported"
        else:
            body = "rows every call" if q.body == "" else f"`{q.body}` rows"
        note = f" ({q.why})" if q.why else ""
        lines.append(_row((f"`{q.iec}`", q.meaning, var, body + note)))
    lines += ["", "| IEC construct | GRAPH | note |", "|---|---|---|"]
    lines += [_row(c) for c in CONSTRUCTS]
    return "\n".join(lines)
