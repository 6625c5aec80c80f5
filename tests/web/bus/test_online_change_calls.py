"""A download whose chart calls the CPU's S7-SCL blocks in a way that does not fit them, over a
real zenoh bus (docs/online-change.md, "S7-SCL blocks"): a chart brought alone has its calls
of the blocks the CPU holds checked against them (E047, as ``s7graph check --blocks``), as
one that brings new sources has them checked against those — refused with the row and the
parameter, its preview alike, the old chart running on. Reached, each of these calls
stopped the CPU. A call of a block the CPU lacks keeps the swap's rule: refused when new,
taken when the running chart already has it."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from s7graph.engine.cpu import CpuMode
from s7graph.web.bus.protocol import CommandReply
from tests.web.helpers import CALLS_FB17, OnlineClient, online_client, wait_until

if TYPE_CHECKING:
    from tests.conftest import BusCerts

pytestmark = pytest.mark.timeout(180)

BLOCKS = """FUNCTION_BLOCK FB17
VAR_INPUT go : BOOL; k : INT; END_VAR
VAR_OUTPUT q : BOOL; END_VAR
VAR n : INT; END_VAR
  IF go THEN n := n + 1; END_IF;
  q := go;
END_FUNCTION_BLOCK
FUNCTION_BLOCK FB18
VAR_INPUT go : BOOL; END_VAR
VAR n : INT; END_VAR
  IF go THEN n := n + 1; END_IF;
END_FUNCTION_BLOCK
FUNCTION FC5 : VOID
VAR_INPUT a : INT; END_VAR
VAR_OUTPUT r : INT; END_VAR
  r := a + 1;
END_FUNCTION
DATA_BLOCK DB20
STRUCT x : INT; END_STRUCT
BEGIN
END_DATA_BLOCK
"""
ROW = "CALL FB 17, DB 10 (go := TRUE);"
# S1 counts in DB10 and DB11; S2, never reached, calls FC 9, which the CPU lacks
CHART = CALLS_FB17.replace(ROW, f"{ROW}\n    CALL FB 18, DB 11 (go := TRUE);").replace(
    'STEP S2 "never": END_STEP', 'STEP S2 "never":\n    CALL FC 9 (x := 1);\n  END_STEP'
)
UNFIT = {  # row 1 of S1 as the download brings it → what its refusal says
    "CALL FB 17, DB 10 (go := TRUE, nope := 1);": (
        "4:5: error[E047]: FB17 has no parameter nope (parameters: go, k, q) (step S1 row 1)"
    ),
    "CALL FB 17, DB 10 (go := TRUE, k := M0.0);": (
        "4:41: error[E047]: FB17: k is INT, BOOL does not fit it (step S1 row 1)"
    ),
    "CALL FB 17, DB 10 (go := 2.5);": (
        "4:30: error[E047]: FB17: go is BOOL, REAL does not fit it (step S1 row 1)"
    ),
    "CALL FB 17, DB 10 (go := TRUE, q := 5);": (
        "4:5: error[E047]: FB17: q is an output, use q => ... (step S1 row 1)"
    ),
    "CALL FB 17 (go := TRUE);": (
        "4:5: error[E047]: FB17 is an FB and needs an instance DB (CALL FB 17, DB n) "
        "(step S1 row 1)"
    ),
    "CALL FC 5, DB 12 (a := 1, r => MW20);": (
        "4:5: error[E047]: FC5 is an FC and takes no instance DB (step S1 row 1)"
    ),
}
ELSEWHERE = {  # instance DBs that are something else: the swap's own words, as before
    "CALL FB 17, DB 11 (go := TRUE);": (
        "4:5: error: CALL FB 17, DB 11: DB11 is the instance DB of FB18 'FB18' (step S1 row 1)"
    ),
    "CALL FB 17, DB 20 (go := TRUE);": (
        "4:5: error: CALL FB 17, DB 20: DB20 is a global DB (step S1 row 1)"
    ),
}


class Cpu(OnlineClient):
    def download(self, source: str, *, preview: bool = False, **args: object) -> CommandReply:
        return self.send("download", source=source, preview=preview, **args)

    def counts(self) -> tuple[int, int]:
        return int(self.session.get("DB10.n")), int(self.session.get("DB11.n"))

    def runs_on(self) -> bool:
        """RUN, and the old S1 calls FB17 and FB18 on."""
        first = self.counts()
        grows = wait_until(
            lambda: all(n > v + 2 for n, v in zip(self.counts(), first, strict=True))
        )
        return grows and self.session.cpu.mode is CpuMode.RUN


@pytest.fixture
def cpu(tmp_path: Path, bus_certs: BusCerts) -> Iterator[Cpu]:
    blocks = {"fb.scl": BLOCKS}
    with online_client(tmp_path, CHART, certs=bus_certs, name="seq.s7g", blocks=blocks) as on:
        yield Cpu(on.rig, on.client, on.token, on.user)


def test_a_chart_alone_whose_call_does_not_fit_a_block_the_cpu_holds_is_refused_naming_it(
    cpu: Cpu,
) -> None:
    """A parameter FB17 lacks, a BOOL to its INT input, a REAL to its BOOL, its output given
    with ``:=``, FB17 without its instance DB, FC5 with one: E047 naming the row and the
    parameter, the preview first; an instance DB that is something else keeps the swap's
    reason. The old chart runs on and its file stays."""
    cc = cpu.session.graph.cc
    for row, why in {**UNFIT, **ELSEWHERE}.items():
        source = CHART.replace(ROW, row)
        asked = cpu.download(source, preview=True)
        reply = cpu.download(source)
        assert not asked.applied and asked.reason == reply.reason, (row, asked.reason)
        assert not reply.applied and f"the edited chart:{why}" in reply.reason, reply.reason
        if row in UNFIT:
            assert reply.reason.startswith("the chart's calls do not fit the CPU's blocks: ")
            assert any(why in line for line in reply.lines), reply.lines
    assert cpu.runs_on()
    assert cpu.path.read_text(encoding="utf-8") == CHART
    assert cpu.session.graph.cc is cc  # never swapped


def test_a_download_with_new_blocks_refuses_the_same_calls_against_those(cpu: Cpu) -> None:
    """The sources changed too: the same calls are checked against the new blocks, the
    same E047 refusing them, the preview first; the old blocks and chart run on."""
    by_2 = BLOCKS.replace("n := n + 1;", "n := n + 2;", 1)
    for row, why in UNFIT.items():
        source = CHART.replace(ROW, row)
        asked = cpu.download(source, preview=True, blocks={"fb.scl": by_2})
        reply = cpu.download(source, blocks={"fb.scl": by_2})
        assert not asked.applied and asked.reason == reply.reason, (row, asked.reason)
        assert (
            reply.reason == f"the chart's calls do not fit the new blocks: the edited chart:{why}"
        )
    assert cpu.runs_on()
    assert (cpu.path.parent / "fb.scl").read_text(encoding="utf-8") == BLOCKS


def test_calls_that_fit_and_a_call_of_a_block_the_running_chart_already_lacks_are_taken(
    cpu: Cpu,
) -> None:
    """FC5 with every parameter runs; FC9, which the CPU lacks and S2 of the running chart
    already calls, is not checked (the swap's rule: it stops the CPU only if reached), even
    with a parameter nobody declares — while a new call of FB19 is refused."""
    fits = CHART.replace(ROW, f"{ROW}\n    CALL FC 5 (a := 41, r => MW20);").replace(
        "CALL FC 9 (x := 1);", "CALL FC 9 (x := 1, whatever := 2.5);"
    )
    asked = cpu.download(fits, preview=True)
    assert asked.applied, asked.reason
    reply = cpu.download(fits)
    assert reply.applied and reply.version == 2, reply.reason
    assert wait_until(lambda: int(cpu.session.get("MW20")) == 42)
    assert cpu.runs_on()
    lacking = fits.replace("CALL FC 5 (a := 41, r => MW20);", "CALL FB 19, DB 19 (go := TRUE);")
    refused = cpu.download(lacking, preview=True)
    assert not refused.applied and "FB19 is not in this CPU" in refused.reason, refused.reason
    assert cpu.runs_on() and cpu.path.read_text(encoding="utf-8") == fits
