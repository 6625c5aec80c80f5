"""A chart calls system blocks as a GRAPH step does on S7 (``sequencer/calls.py``): the
CPU has SFB0–5 and the SFCs, the instance DB a ``CALL SFB 4, DB 10`` names is created
with the chart (at load and at an online change), kept with the state, and kept when a
later chart no longer calls it; an SFC's outputs reach the FB variables they name. A call
of a block the CPU lacks is a warning at load and, reached, a STOP that ``sim`` reports
with its reason and exit status 1; a download may not add one."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from s7graph.engine.clock import VirtualClock
from s7graph.engine.modes import CpuMode
from s7graph.sequencer.change.online import SwapRefused, swap
from s7graph.web.cli import main
from s7graph.web.harness.persist import open_state
from s7graph.web.harness.session import ChartLoadError, ChartSession, compile_text

CHART = """FUNCTION_BLOCK "Timed" FB 3 DB 3
VAR done : BOOL; waited : TIME; END_VAR
SEQUENCE 1 "Main"
  INITIAL_STEP S1 "Wait":
    {call}
  END_STEP
  STEP S2 "Go":
  END_STEP
  TRANSITION T1 FROM S1 TO S2 := done;
  TRANSITION T2 FROM S2 TO S1 := NOT I0.0;
END_SEQUENCE
END_FUNCTION_BLOCK
"""
TON = "CALL SFB 4, DB 10 (IN := I0.0, PT := T#2S, Q => done, ET => waited);"


def chart(tmp_path: Path, call: str, name: str = "timed.s7g") -> Path:
    path = tmp_path / name
    path.write_text(CHART.format(call=call), encoding="utf-8")
    return path


def sim(
    path: Path, capsys: pytest.CaptureFixture[str], *args: str
) -> tuple[int, list[dict[str, object]], str]:
    stim = path.with_suffix(".jsonl")
    stim.write_text('{"at_ms": 0, "set": {"I0.0": true}}\n', encoding="utf-8")
    rc = main(["sim", str(path), "--stimulus", str(stim), *args])
    out, err = capsys.readouterr()
    return rc, [json.loads(line) for line in out.splitlines()], err


def test_a_ton_called_in_a_step_times_out_and_switches_the_sequence(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rc, trace, err = sim(chart(tmp_path, TON), capsys, "--cycles", "205", "--watch", "waited")
    assert rc == 0 and err == ""
    assert trace[150]["values"] == {"waited": 1500}
    first = next(line["cycle"] for line in trace if line["active"] == ["S2"])
    assert first == 201  # Q at 2000 ms, T1 in the next cycle


def test_a_call_of_a_block_the_cpu_lacks_is_a_warning_and_reached_a_reported_stop(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    text = CHART.format(call="").replace('STEP S2 "Go":', 'STEP S2 "Go":\n    CALL FC 9;')
    path = tmp_path / "fc.s7g"
    path.write_text(text.replace("done;", "I0.0;"), encoding="utf-8")
    rc, trace, err = sim(path, capsys, "--cycles", "20")
    assert rc == 1
    assert [line["active"] for line in trace] == [["S2"]]  # S2's call in cycle 0: the end
    warning, stop = err.splitlines()
    assert warning.startswith(f"{path}:8:5: warning: CALL FC 9: FC9 is not in this CPU")
    assert stop.startswith("s7graph: error: cycle 0: the CPU went to STOP: FB3: block FC9")
    assert "BlockError" not in err


def test_an_instance_db_that_is_something_else_refuses_the_chart(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = chart(tmp_path, TON.replace("DB 10", "DB 3"))
    rc, trace, err = sim(path, capsys, "--cycles", "2")
    assert rc == 2 and trace == []
    assert err == (  # said by the chart's check, before any CPU is made
        f"{path}:5:5: error[E046]: DB3 is the instance DB of FB3 (this chart) already "
        "(step S1 row 1)\n"
    )


def test_an_online_change_that_adds_a_timer_creates_its_instance_db(tmp_path: Path) -> None:
    clock = VirtualClock()
    session = ChartSession.load(chart(tmp_path, ""), None, clock)
    session.start()
    session.set("I0.0", True)
    session.scan()
    assert 10 not in session.cpu.instance_dbs
    new, _ = compile_text(CHART.format(call=TON), "timed.s7g")
    swap(session.graph, new, session.cpu)
    for _ in range(202):  # the timer starts in the first scan after the swap
        clock.advance(10)
        session.scan()
    assert session.cpu.mode is CpuMode.RUN
    assert session.get("S2.X") is True
    with pytest.raises(ChartLoadError, match="DB3 is the instance DB of FB3"):  # at compile
        compile_text(CHART.format(call=TON.replace("DB 10", "DB 3")), "timed.s7g")
    assert session.cpu.mode is CpuMode.RUN


def test_the_timer_instance_is_kept_with_the_state_and_outlives_its_call(tmp_path: Path) -> None:
    """Saved while the timer has run 1.5 s; restarted hot (another process, another clock)
    its DB holds the same and the time runs on from 1.5 s; a chart that no longer calls it
    still loads the file, the DB kept as S7 keeps DBs."""
    state = tmp_path / "timed.state.sqlite"
    session = ChartSession.load(chart(tmp_path, TON), None, VirtualClock())
    opened = open_state(state, session.cpu, hot=True)  # keeps the hot restart image
    session.cpu.start("warm")
    session.set("I0.0", True)
    for _ in range(151):
        session.scan()
        batch = opened.store.stage(session.cpu)
        if batch is not None:
            opened.store.write(batch)
        session.clock.advance(10)  # type: ignore[attr-defined]
    saved = dict(session.cpu.instance_db(10).values)
    assert saved["ET"] == 1500
    opened.store.close()

    clock = VirtualClock(10**12)  # another process's clock: far from the first one's
    again = ChartSession.load(chart(tmp_path, TON), None, clock)
    reopened = open_state(state, again.cpu, hot=True)
    assert reopened.report is not None
    assert dict(again.cpu.instance_db(10).values) == saved
    again.cpu.start("hot")
    again.set("I0.0", True)
    again.scan()
    assert again.cpu.instance_db(10).values["ET"] == 1500  # resumed as persisted
    for _ in range(50):
        clock.advance(10)
        again.scan()
    assert again.cpu.instance_db(10).values["ET"] == 2000 and again.get("done") is True
    reopened.store.close()

    without = ChartSession.load(chart(tmp_path, ""), None, VirtualClock())
    kept = open_state(state, without.cpu)
    assert dict(without.cpu.instance_db(10).values) == saved
    kept.store.close()


CLOCK = """FUNCTION_BLOCK "Clock" FB 3
VAR now : DATE_AND_TIME; ret : INT; ticks : TIME; END_VAR
SEQUENCE 1
  INITIAL_STEP S1:
    CALL SFC 1 (RET_VAL => ret, CDT => now);
  END_STEP
  TRANSITION T1 FROM S1 TO S1 := FALSE;
END_SEQUENCE
PERMANENT AFTER
  CALL SFC 64 (RET_VAL => ticks);
END_PERMANENT
END_FUNCTION_BLOCK
"""


def test_an_sfc_writes_its_outputs_to_fb_variables(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """READ_CLK's CDT (an OUT) and TIME_TCK's RET_VAL reach the FB variables they name,
    from a step's row and from a permanent instruction."""
    path = tmp_path / "clock.s7g"
    path.write_text(CLOCK, encoding="utf-8")
    rc, trace, err = sim(path, capsys, "--cycles", "3", "--watch", "now,ret,ticks")
    assert rc == 0 and err == ""
    assert trace[2]["values"] == {"now": "1990-01-01 00:00:00.020000", "ret": 0, "ticks": 20}


def test_an_sfc_call_without_all_its_parameters_is_refused_by_check(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "clock.s7g"
    path.write_text(CLOCK.replace("RET_VAL => ret, ", ""), encoding="utf-8")
    assert main(["check", str(path)]) == 2
    assert "E046]: SFC1 READ_CLK: an SFC takes every parameter; RET_VAL missing" in (
        capsys.readouterr().out
    )


def test_a_download_may_not_add_a_call_of_a_block_the_cpu_lacks(tmp_path: Path) -> None:
    """Reached, the call would stop a running plant: the swap is refused, the old chart runs
    on. A chart that already had the call may still be changed."""
    session = ChartSession.load(chart(tmp_path, ""), None, VirtualClock())
    session.start()
    session.scan()
    calling, _ = compile_text(CHART.format(call="CALL FC 9;"), "timed.s7g")
    with pytest.raises(SwapRefused, match=r"CALL FC 9: FC9 is not in this CPU"):
        swap(session.graph, calling, session.cpu)
    assert session.graph.cc is not calling
    had = ChartSession.load(chart(tmp_path, "CALL FC 9;", "had.s7g"), None, VirtualClock())
    had.start()
    changed, _ = compile_text(CHART.format(call="CALL FC 9;").replace('"Go"', '"Went"'), "t")
    swap(had.graph, changed, had.cpu)
    assert had.graph.cc is changed


@pytest.mark.parametrize("db", ["0", "65536"])
def test_an_instance_db_number_outside_1_to_65535_is_refused_by_check(
    db: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = chart(tmp_path, TON.replace("DB 10", f"DB {db}"))
    assert main(["check", str(path)]) == 2
    assert f"error[E046]: DB {db}: a DB number is 1 to 65535" in capsys.readouterr().out


def test_a_system_block_called_by_its_name_is_that_block(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``CALL "TON", DB 10 (…)`` is SFB 4, checked and given its instance DB the same way."""
    path = chart(tmp_path, TON.replace("SFB 4", '"TON"'))
    rc, trace, err = sim(path, capsys, "--cycles", "205")
    assert rc == 0 and err == ""
    assert next(line["cycle"] for line in trace if line["active"] == ["S2"]) == 201
    path.write_text(CHART.format(call='CALL "TON" (IN := I0.0);'), encoding="utf-8")
    assert main(["check", str(path)]) == 2
    assert "SFB4 TON is an SFB and needs an instance DB" in capsys.readouterr().out
