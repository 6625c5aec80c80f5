"""What a construct of each format becomes in GRAPH, and what a chart becomes in each
format: the tables the importer reads (qualifiers, types, functions) and the one table of
every other construct, import and export, that docs/import-export.md shows
(``markdown_tables``; a test checks the page against it).

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

# Every other construct of every format, for docs/import-export.md: (format, construct, what it
# becomes, note or why it is refused). "IEC" is PLCopen TC6 XML and textual SFC alike.
IEC, PLCOPEN, TEXT, TIA = "IEC", "PLCopen", "IEC text", "SimaticML"
TO_PLCOPEN, TO_TIA = "export → PLCopen", "export → SimaticML"
CONSTRUCTS: Final[tuple[tuple[str, str, str, str], ...]] = (
    (
        IEC,
        "step, initial step",
        "STEP / INITIAL_STEP, numbered in the order written",
        "the IEC name is the step's name; s7graph's own export keeps numbers",
    ),
    (
        IEC,
        "transition with an ST condition",
        "TRANSITION … := condition",
        "`x = TRUE` → `x`, `x = FALSE` → `NOT x`, `OR(a, b, c)` → `a OR b OR c`; 1 and 0 "
        "where a BOOL is expected are TRUE and FALSE (`:= 1` holds)",
    ),
    (IEC, "`SEL(G, IN0, IN1)` on BOOLs", "`NOT G AND IN0 OR G AND IN1`", "on other types refused"),
    (
        IEC,
        "condition wired from contacts, AND, OR, NOT, SEL (LD/FBD)",
        "the same condition",
        "an edge contact is refused (no GRAPH condition form)",
    ),
    (IEC, "named transition (ST, LD, FBD body)", "its condition", ""),
    (
        PLCOPEN,
        "transition body of ST statements (CODESYS, TwinCAT)",
        "`name := expr;` alone: its condition; other statements: an SCL FC called in "
        "PERMANENT BEFORE (`Name => Name`)",
        "the condition reads the FB variable the FC computes in the same call",
    ),
    (
        IEC,
        "several transitions from one step",
        "an alternative branch; priority: PRIORITY, then left to right (x), then as written",
        "IEC without priority may switch several paths; GRAPH switches exactly one",
    ),
    (IEC, "`TO (a, b)`, `FROM (a, b)`", "simultaneous divergence, join", ""),
    (IEC, "jump step", "a jump (TO the target step)", "into another chart of the POU too"),
    (IEC, "several charts in one POU", "one SEQUENCE each", "in the order of their first step"),
    (
        PLCOPEN,
        "SFC body of an action (TwinCAT, CODESYS)",
        "a chart of its own, `POU.action`, with the POU's variables",
        "`--pou` names it in full, by the action or by the POU; GRAPH does not nest charts, "
        "so a step associating it is reported",
    ),
    (
        IEC,
        "variable (VAR, VAR_INPUT, VAR_OUTPUT, VAR_EXTERNAL)",
        "FB variable (VAR)",
        "a GRAPH FB has no further pins; an external takes its global's value",
    ),
    (
        IEC,
        "located variable (`AT %IX0.1`)",
        'symbol `"name" : I0.1`',
        "unless it has an "
        "initial value or is an input the chart writes: then an FB variable (S7 re-reads "
        "inputs each cycle and starts outputs at 0)",
    ),
    (IEC, "`x := TRUE` / `x := FALSE` in an action", "`S x` / `R x` (the qualifier's event)", ""),
    (IEC, "`n := expr` (not a bit) in an action", "`N n := expr`", ""),
    (
        IEC,
        "`x := bit expression` in an action",
        "PERMANENT AFTER `x := gate AND (…) OR NOT gate AND x`",
        "gate: `Sn.X` (N), a one-call pulse of the step (P); GRAPH writes bits "
        "from conditions only in permanent instructions",
    ),
    (IEC, "set / reset coil of an action network", "PERMANENT AFTER `S x := gate AND …`", ""),
    (
        IEC,
        "an action body with IF, CASE, FOR, WHILE, REPEAT, EXIT, RETURN",
        "an SCL FC of the chart's `.scl` source (`Imported.blocks_scl`), called from the "
        "step's row: `CALL FC n (x := x, y_IN := y, y => y)`, a warning (I033)",
        "GRAPH rows are single instructions; S7 runs such a body as an SCL FC called from "
        "the step's row. Read variables are inputs; written ones outputs fed their value "
        "(`y_IN`), as an IN_OUT would be. A body the SCL compiler refuses is kept whole: "
        "`Imported.pending`, a `(* PENDING SCL` comment on the step, a warning (I021) at "
        "the SCL error",
    ),
    (
        IEC,
        "`END_IF` (END_CASE …) without `;` (CODESYS)",
        "read as with it",
        "",
    ),
    (
        IEC,
        "an S action on an initial step that nothing resets",
        "PERMANENT AFTER",
        "stored from the first call on, for good: it runs every call, after the rows",
    ),
    (
        IEC,
        "statements of a textual POU body beside its SFC",
        "PERMANENT BEFORE",
        "run every call, before the chart (an SCL FC called there when they hold an IF …)",
    ),
    (
        IEC,
        "call of a TON, TOF, TP, CTU, CTD or CTUD instance",
        "`CALL SFB n, DB m (…)` (a row of the action's step; permanent from the POU body or "
        "the chart's network)",
        "each instance an instance DB of its own: the `n` of a name `…_DB<n>` (as "
        "s7graph's PLCopen export writes them), else the next free from DB 100; IEC's `LD` "
        "is S7's `LOAD`; every output not given with `=>` written to an FB variable: "
        "`TON3.Q` reads `TON3_Q`",
    ),
    (
        IEC,
        "call of an R_TRIG, F_TRIG, SR or RS instance",
        "the bit assignments of its IEC body on FB variables (`E1_Q := E1_CLK AND NOT "
        "E1_M` …), gated by the step in an action",
        "the CPU has no system block for them; state starts FALSE as in matiec; CODESYS's "
        "`SET1`/`RESET`, `SET`/`RESET1` read too",
    ),
    (
        PLCOPEN,
        "function blocks drawn in a chart's network (Beremiz)",
        "called every call in PERMANENT AFTER, in the order the conditions need them",
        "as Beremiz computes them (the S action `COMPUTE_FUNCTION_BLOCKS` of the first "
        "initial step); a block no condition reads is reported, as Beremiz does not call it",
    ),
    (
        IEC,
        "other FB instances, arrays",
        "not imported",
        "GRAPH calls the CPU's system blocks; a read of an output of an instance never "
        "called is reported; an array element `A[1]` is the FB variable `A_1`",
    ),
    (
        IEC,
        "`x(L, dt)`, `x(D, dt)` with a TIME variable",
        "`L x, dt` / `D x, dt`",
        "the name after a timed qualifier is the action time; further names are indicators "
        "(reported: GRAPH rows have none)",
    ),
    (IEC, "IL action bodies", "not imported", ""),
    (IEC, "IL transition conditions, macro steps", "no chart (an error)", "a path needs them"),
    (
        TEXT,
        "a POU the grammar cannot read (IL, TYPE …) beside a chart",
        "left out, reported",
        "the file is read POU by POU when it does not parse as a whole",
    ),
    (
        PLCOPEN,
        "CODESYS entry / active / exit step actions",
        "S1 rows / rows / S0 rows",
        "CODESYS files import with `ORDER := CODESYS` (actions before transitions)",
    ),
    (
        IEC,
        "a step the chart can never leave",
        "a warning (I025) at the step",
        "what its transitions wait for that only the chart could write (an instance never "
        "called, a body the SCL compiler refused), and why nothing writes it",
    ),
    (TIA, "steps, transitions, branches, jumps, branch stops", "the same, numbers kept", ""),
    (TIA, "LAD/FBD conditions, interlocks, supervisions", "conditions", ""),
    (
        TIA,
        "a step's `T`/`U` compared with an untyped tag, an integer or a DInt tag",
        "a TIME comparison",
        "TIA compiles them as milliseconds; a DInt tag is declared TIME (reported)",
    ),
    (
        TIA,
        '`Scope="LocalConstant"`',
        "its value (the block's Constant section)",
        "",
    ),
    (
        TIA,
        '`Scope="GlobalConstant"`',
        "an FB variable of its name (reported)",
        "its value lives in the PLC's constants table, which a block export does not carry",
    ),
    (
        TIA,
        'a DB member `"T_S2".Q` of a DB symbol (kept in the block comment, or `--symbols`)',
        'the instance DB\'s variable read by name, `"T_S2".Q`',
        "the DB symbols s7graph's export kept are declared in `SYMBOLS` (those `--symbols` "
        'names stay there); of any other DB it is a tag `"T_S2.Q"`; a user FB\'s variable '
        "is checked by `check --blocks`",
    ),
    (
        TIA,
        "global tag without an address",
        "a symbol at a marker address inside the CPU's M area (reported)",
        "bits from M100.0, wider tags from MB150, then from MB16, never a used byte; M full: "
        "no chart (I014)",
    ),
    (TIA, "action rows", "the same rows (an `Access` with an address keeps it)", ""),
    (
        TIA,
        "permanent operations: coils, `Move` and `Call` boxes fed by the power rail",
        "bit instructions, assignments, CALLs (`FC2` → `FC 2`, `DB10` → `DB 10`)",
        "another box, or a box whose EN is a condition, is left out and reported (I022)",
    ),
    (
        TO_PLCOPEN,
        "steps, transitions, branches, jumps",
        "an SFC other IEC tools read",
        "each step's localId is its number (a transition's 100000 + its number); a step only "
        "an upward link reaches is drawn hanging on it",
    ),
    (
        TO_PLCOPEN,
        "permanent instructions",
        "the body of an inline action stored (S) on the first initial step",
        "other tools run it every call; BEFORE's results reach the conditions a call "
        "later there (reported)",
    ),
    (
        TO_PLCOPEN,
        "interlocks, supervisions, rows without an IEC qualifier, TO STOP, block options",
        "s7graph's data only (`addData`), each reported",
        "IEC has no form for them",
    ),
    (
        TO_PLCOPEN,
        "`CALL SFB n, DB m` of an IEC timer or counter",
        "the call of instance `TON_DBm`",
        "",
    ),
    (
        TO_PLCOPEN,
        'an instance DB\'s variable read by name (`"T_S2".Q`, `DB10.Q`)',
        "IEC's access to an FB instance's output: `TON_DB10.Q` of the instance the IEC "
        "timer's or counter's call uses; of another block's DB a global instance of its "
        "type (`Motor_DB : FB17`, reported: nothing calls it)",
        "a DB symbol is no IEC variable: one no read goes through is left out (reported); "
        "read by another tool, `TON_DB10.Q` is the FB variable `TON_DB10_Q` the call's "
        "`Q =>` writes",
    ),
    (
        TO_PLCOPEN,
        "a call passing a DB to a BLOCK_DB input",
        "an ST comment in its S7 spelling, as any call of a user block",
        "IEC 61131-3 has neither BLOCK_DB nor a DB as a value, and an IEC tool calls no "
        "S7-SCL block: no WORD literal is written for the DB; the warning (`X010`) names it, "
        "and a DB symbol it passes is reported as such",
    ),
    (
        TO_PLCOPEN,
        "transition names; the places of branches, jumps and actions",
        "names in s7graph's data only; each branch, jump and action placed (`position`, "
        "`relPosition`), each output named (`formalParameter`)",
        "as the TC6 v2.01 schema asks, which other tools check a file against",
    ),
    (
        TO_PLCOPEN,
        "names of the POU, steps and variables",
        "IEC identifiers (IEC 61131-3 ed.3, 6.1.2): ASCII letters, digits and single "
        "underscores, none at the end (`Lamp (x)` → `Lamp_x`), each once in the POU; "
        "Cyrillic in Latin letters by GOST 7.79-2000 system B, without its marks "
        "(`Подача` → `Podacha`, `Цех` → `Cex`), a letter with marks as its Latin base "
        "(`Füll` → `Full`)",
        "the chart kept in s7graph's data keeps its own names; IEC compares names without "
        "case: a step whose name another step or a variable has (`Dwell`, `dwell`), or "
        "that keeps no letter or digit (`注水`), is `S<n>`, a global `_2`, `_3` … (X013)",
    ),
    (
        TO_PLCOPEN,
        "S7 literals in ST (`L#70000`, `W#16#0F0F`, `DW#2#1010`)",
        "the IEC forms `DINT#70000`, `WORD#16#0F0F`, `DWORD#2#1010`",
        "other tools know no `L#`; read back, a DINT literal is a plain number",
    ),
    (TO_TIA, "the chart", "a GRAPH FB (`Graph/v5`)", "numbers, names, options kept"),
    (
        TO_TIA,
        "names of steps and transitions",
        "the same names, in any script (`Подача`); an unnamed one TIA's default (`Step3`, "
        "`Trans3`)",
        "TIA's names are texts, not identifiers; a transition named with that default "
        "comes back unnamed; a name taken before gets `_2` … (X013)",
    ),
    (
        TO_TIA,
        "action rows",
        "`Action` tokens; a symbol an `Access` with its informative address",
        "",
    ),
    (
        TO_TIA,
        "CALL rows",
        '`Qualifier="CALL"`, the call in s7graph\'s spelling',
        "reported: TIA names blocks and instance DBs by symbol",
    ),
    (
        TO_TIA,
        'an instance DB\'s variable read by name (`"T_S2".Q`, `DB10.Q`)',
        "a global access to a DB member, the DB by its name, as TIA writes one "
        "(`Component` `T_S2`, `Component` `Q`); the chart's DB symbols in the block comment",
        '`DB10.Q` goes by the DB symbol naming DB 10 (X013, read back as `"T_S2".Q`) and '
        "is refused, naming its place, when no symbol names it",
    ),
    (
        TO_TIA,
        "permanent CALLs",
        "a LAD `Call` box fed by the power rail (`CallInfo` `FC2`, instance `DB10`)",
        "reported as for CALL rows; read back as the same CALL",
    ),
    (
        TO_TIA,
        'a DB a call passes to a BLOCK_DB input (`src := DB5`, `src := "Recipe"`)',
        'a DB as a whole, as TIA writes `OPN %DB12` (Openness system manual, "Major '
        'changes", the `Address` node of `SW.PlcBlocks.Access.xsd`): `<Address Area="DB" '
        'Type="Block_DB" BlockNumber="5" />`, without bit offset; under the DB\'s symbol '
        '(`<Component Name="Recipe" />`) that address informative; a call box\'s parameter '
        '`Type="Block_DB"`',
        "read back as the same DB; a DB symbol of `--symbols` a call passes is kept in the "
        "block comment; a file TIA wrote declares the symbol from its informative address "
        '(`"Recipe" : DB5 : DB5`)',
    ),
    (
        TO_TIA,
        "permanent assignment of an operand or a constant to a non-bit",
        "a LAD `Move` box",
        "read back as the same assignment",
    ),
    (
        TO_TIA,
        "permanent assignment of an arithmetic expression",
        "refused (an error naming the place)",
        "TIA draws it with ADD/SUB/MUL/DIV or CALCULATE boxes, not written here: "
        "compute it in an FC the permanent instructions call",
    ),
)


def _row(cells: tuple[str, ...]) -> str:
    return "| " + " | ".join(cells) + " |"


def markdown_tables() -> str:
    """The tables of docs/import-export.md: qualifiers, then every other construct of every
    format (import and export)."""
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
    lines += ["", "| format | construct | becomes | note |", "|---|---|---|---|"]
    lines += [_row(c) for c in CONSTRUCTS]
    return "\n".join(lines)
