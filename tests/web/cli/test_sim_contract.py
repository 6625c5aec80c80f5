"""``s7graph sim`` exactly per docs/cli.md, "s7graph sim" (the public black-box contract)."""

from __future__ import annotations

from pathlib import Path

from hypothesis import given, settings
from hypothesis import strategies as hs

from s7graph.web.cli.sim import sim_command
from tests.sequencer.helpers import read_trace, write_sim_inputs

CHART = """FUNCTION_BLOCK "Drill"
  PARAMETERS := STANDARD;
SYMBOLS "Start" : I0.7 : BOOL; "Motor" : Q0.0 : BOOL; END_SYMBOLS
SEQUENCE 1 "Main"
  INITIAL_STEP S1 "Ready": END_STEP
  STEP S2 "Run": N "Motor"; END_STEP
  STEP S3 "A": END_STEP
  TRANSITION T1 FROM S1 TO (S2, S3) := "Start";
  TRANSITION T2 FROM (S2, S3) TO S1 := I0.1;
END_SEQUENCE
END_FUNCTION_BLOCK
"""


def run(
    tmp_path: Path,
    stim: list[dict],
    cycles: int = 6,
    watch: str = "Q0.0,S_NO,ERR_FLT",
    chart: str = CHART,
) -> tuple[int, list[dict]]:
    c, s, out = write_sim_inputs(tmp_path, chart, stim)
    rc = sim_command(c, stimulus=s, cycle_ms=10, cycles=cycles, watch=watch, trace=out)
    return rc, read_trace(out)


def test_sim_writes_one_line_per_cycle_with_the_contract_fields(tmp_path: Path) -> None:
    rc, lines = run(tmp_path, [{"at_ms": 20, "set": {"Start": True}}])
    assert rc == 0 and len(lines) == 6
    assert lines[0] == {
        "cycle": 0,
        "t_ms": 0,
        "active": ["S1"],
        "events": [],
        "mode": "AUTO",
        "values": {"Q0.0": False, "S_NO": 1, "ERR_FLT": False},
    }
    assert lines[2]["events"] == [["S1", "S2"], ["S1", "S3"]]
    assert lines[2]["active"] == ["S2", "S3"] and lines[2]["values"]["Q0.0"] is True
    assert lines[3]["events"] == []


def test_sim_stimulus_pins_switch_the_mode(tmp_path: Path) -> None:
    rc, lines = run(
        tmp_path, [{"at_ms": 0, "set": {"SW_MAN": True}}, {"at_ms": 10, "set": {"Start": True}}]
    )
    assert rc == 0 and lines[-1]["mode"] == "MAN" and lines[-1]["active"] == ["S1"]


def test_sim_rejects_a_pin_outside_the_parameter_set(tmp_path: Path, capsys) -> None:
    rc, _ = run(tmp_path, [{"at_ms": 0, "set": {"HALT_SQ": True}}])
    assert rc == 2 and "HALT_SQ" in capsys.readouterr().err


def test_sim_exits_2_with_diagnostics_for_a_chart_that_does_not_compile(
    tmp_path: Path, capsys
) -> None:
    rc, _ = run(tmp_path, [], chart=CHART.replace('N "Motor"', 'N "Nope"'))
    err = capsys.readouterr().err
    assert rc == 2 and "c.s7g:" in err and "Nope" in err


def test_sim_says_the_charts_warnings_on_stderr_and_runs_it(tmp_path: Path, capsys) -> None:
    """A chart with warnings runs (exit 0), its warnings on stderr as ``check`` says them:
    an empty transition condition holds (W120)."""
    rc, trace = run(tmp_path, [], chart=CHART.replace(":= I0.1;", ":= ;"))
    err = capsys.readouterr().err.splitlines()
    assert rc == 0 and len(err) == 1 and "c.s7g:9:3: warning[W120]: transition T2" in err[0]
    assert trace[0]["active"] == ["S1"]  # T1 waits for Start; T2 would switch at once


@settings(max_examples=25, deadline=None)
@given(
    hs.lists(
        hs.tuples(hs.integers(0, 150), hs.sampled_from(["Start", "I0.1"]), hs.booleans()),
        max_size=12,
    )
)
def test_the_same_inputs_always_give_the_same_trace(tmp_path_factory, stim) -> None:
    rows = [{"at_ms": t, "set": {n: v}} for t, n, v in stim]
    a = run(tmp_path_factory.mktemp("a"), rows, cycles=20)
    b = run(tmp_path_factory.mktemp("b"), rows, cycles=20)
    assert a == b and a[0] == 0


def test_a_switch_in_the_startup_call_is_in_the_first_lines_events(tmp_path: Path) -> None:
    """With ``ORDER := CODESYS`` the initial step runs its rows and may switch inside the
    startup call (docs/semantics.md, "One FB call"): that switch opens cycle 0's ``events``,
    so every switch is in some line (docs/cli.md, "s7graph sim"), as GRAPH's, made in
    cycle 0's call, is."""
    chart = CHART.replace("PARAMETERS := STANDARD;", "PARAMETERS := STANDARD; ORDER := CODESYS;")
    chart = chart.replace('TO (S2, S3) := "Start";', "TO (S2, S3) := TRUE;")
    (tmp_path / "graph").mkdir()
    rc_graph, graph = run(tmp_path / "graph", [], cycles=2, chart=chart.replace("CODESYS", "GRAPH"))
    rc, lines = run(tmp_path, [], cycles=2, chart=chart)
    assert rc == rc_graph == 0
    assert lines[0]["events"] == [["S1", "S2"], ["S1", "S3"]] and lines[1]["events"] == []
    assert lines[0]["active"] == ["S2", "S3"]
    assert graph[0]["events"] == lines[0]["events"]  # GRAPH switches in cycle 0's own call


VARS = CHART.replace(
    "  PARAMETERS := STANDARD;\n", "  PARAMETERS := STANDARD;\nVAR n : INT; END_VAR\n"
)


def test_a_stimulus_value_that_does_not_fit_names_its_line_and_exits_2(
    tmp_path: Path, capsys
) -> None:
    """A value set on a variable, pin or address that its type cannot hold is the
    stimulus's fault, not the chart's: ``FILE:LINE: name: why``, exit 2 — never a STOP of
    the CPU blaming the FB, never a value wrapped or kept as text."""
    for values, why in [
        ({"n": "abc"}, "n: bad literal 'abc': not a literal (to set the INT n)"),
        ({"n": 40000}, "n: 40000 is out of range for INT (to set the INT n)"),
        ({"S_SEL": "x"}, "S_SEL: bad literal 'x'"),
        ({"S_SEL": None}, "S_SEL: "),
        ({"Start": "yes"}, "Start: 'yes' is out of range for BOOL"),
    ]:
        rc, _ = run(
            tmp_path, [{"at_ms": 0, "set": {"S_SEL": 1}}, {"at_ms": 10, "set": values}], chart=VARS
        )
        err = capsys.readouterr().err
        assert rc == 2 and err.startswith(f"s7graph: error: {tmp_path / 's.jsonl'}:2: {why}"), err
    rc, lines = run(
        tmp_path, [{"at_ms": 0, "set": {"n": 7.0, "S_SEL": 2}}], chart=VARS, watch="n,S_SEL"
    )
    assert rc == 0 and lines[0]["values"] == {"n": 7, "S_SEL": 2}  # 7.0: a whole number


def test_a_stimulus_file_that_cannot_be_read_is_one_line_naming_it(tmp_path: Path, capsys) -> None:
    c, s, out = write_sim_inputs(tmp_path, CHART, [])
    for content, why in [
        (b"\xff\n", "1:1: not UTF-8"),
        (b"[" * 100_000 + b"\n", "1: bad stimulus line: nested too deep"),
        (b'{"at_ms": -5, "set": {}}\n', "1: bad stimulus line: at_ms must be a time in ms from 0"),
        (b'{"at_ms": {"a": 1}, "set": {}}\n', "1: bad stimulus line: at_ms must be a time in ms"),
        (b"[1, 2]\n", '1: bad stimulus line: a line is an object {"at_ms": 0, "set": {...}}'),
        (b"null\n", "1: bad stimulus line: a line is an object"),
        (b'{"at_ms": 0}\n', '1: bad stimulus line: "set" must be an object of names and values'),
        (b'{"at_ms": 1' + b"0" * 5000 + b', "set": {}}\n', "1: bad stimulus line: a number too"),
        (b'{"at_ms": 0, "set": \n', "1: bad stimulus line: not JSON"),
    ]:
        s.write_bytes(content)
        assert sim_command(c, stimulus=s, cycles=1, trace=out) == 2
        assert capsys.readouterr().err.startswith(f"s7graph: error: {s}:{why}")
    assert sim_command(c, stimulus=tmp_path, cycles=1, trace=out) == 2
    assert capsys.readouterr().err == f"s7graph: error: cannot read {tmp_path}: Is a directory\n"
    assert sim_command(c, cycles=1, trace=tmp_path) == 2
    assert capsys.readouterr().err == (
        f"s7graph: error: cannot write the trace {tmp_path}: Is a directory\n"
    )


def test_a_charts_variable_is_watched_and_set_through_its_instance_db_too(
    tmp_path: Path,
) -> None:
    """S7-GRAPH keeps an FB's static variables in its instance DB: ``DB1.n`` and
    ``"Drill".n`` are the chart's ``n``, read and set as ``n`` is."""
    rc, lines = run(
        tmp_path,
        [{"at_ms": 0, "set": {"DB1.n": 7}}, {"at_ms": 10, "set": {'"Drill".n': 9}}],
        chart=VARS,
        watch='n,DB1.n,"Drill".n',
        cycles=2,
    )
    assert rc == 0
    assert [line["values"] for line in lines] == [
        {"n": 7, "DB1.n": 7, '"Drill".n': 7},
        {"n": 9, "DB1.n": 9, '"Drill".n': 9},
    ]


def test_a_charts_variable_is_named_in_any_case_as_s7_names_are(tmp_path: Path) -> None:
    """S7 names are not case-sensitive: ``N``, ``db1.N`` set and watch the chart's ``n``;
    the trace keeps each name as the watch list wrote it."""
    rc, lines = run(
        tmp_path,
        [{"at_ms": 0, "set": {"N": 7}}, {"at_ms": 10, "set": {"db1.N": 9}}],
        chart=VARS,
        watch="N,n,DB1.N",
        cycles=2,
    )
    assert rc == 0
    assert [line["values"] for line in lines] == [
        {"N": 7, "n": 7, "DB1.N": 7},
        {"N": 9, "n": 9, "DB1.N": 9},
    ]


def test_a_symbol_named_like_a_pin_outside_the_set_is_pointed_to_its_quotes(
    tmp_path: Path, capsys
) -> None:
    """``HALT_SQ`` unquoted is the pin, which STANDARD lacks; the refusal says that the chart's
    symbol of that name takes its quotes, and with them it is set and watched."""
    chart = CHART.replace(
        '"Motor" : Q0.0 : BOOL;', '"Motor" : Q0.0 : BOOL; "HALT_SQ" : I0.3 : BOOL;'
    )
    rc, _ = run(tmp_path, [{"at_ms": 0, "set": {"HALT_SQ": True}}], chart=chart)
    err = capsys.readouterr().err
    assert rc == 2 and err.endswith('; the symbol "HALT_SQ" is written with its quotes\n'), err
    rc, lines = run(
        tmp_path, [{"at_ms": 0, "set": {'"HALT_SQ"': True}}], chart=chart, watch='"HALT_SQ"'
    )
    assert rc == 0 and lines[0]["values"] == {'"HALT_SQ"': True}


def test_a_watched_cell_beyond_the_cpus_cells_is_refused_by_name(tmp_path: Path, capsys) -> None:
    for name in ("T256", "C300"):
        rc, _ = run(tmp_path, [], watch=name)
        assert rc == 2
        assert capsys.readouterr().err.endswith(
            f"s7graph: error: {name}: only 256 {name[0]} cells exist\n"
        )
