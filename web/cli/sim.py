"""``s7graph sim``: run a chart on the virtual clock — the black-box contract of docs/cli.md,
"s7graph sim".

Each cycle (``k`` = 0, 1, …, at ``t_ms = k * cycle_ms``): apply the stimuli with
``at_ms <= t_ms`` (values stay until set again), read inputs, call the FB from OB1, write
outputs, run the plant (if any), write one JSON line, advance the clock by ``cycle_ms``::

    {"cycle": 7, "t_ms": 70, "active": ["S1", "S3"], "events": [["S1", "S3"]],
     "mode": "AUTO", "values": {"Q0.0": true, "S_NO": 3, "ERR_FLT": false}}

``active``: the active steps sorted by number. ``events``: the transitions switched in this
cycle, in switching order, as ``[from, to]`` step pairs — one pair per preceding × following
step (a divergence from S1 to S2, S3 gives ``["S1","S2"], ["S1","S3"]``; a branch stop gives
``[from, "STOP"]``). The CPU's startup (OB100 with INIT_SQ) happens before cycle 0; a
switch in it (with ``ORDER := CODESYS`` a step activated there may switch in that call)
opens cycle 0's ``events``.
``values``: every ``--watch`` name — S7 addresses, symbols, FB pins of the chart's parameter
set, FB variables, ``Sn.X``/``Sn.T``/``Sn.U``, ``Tn.TT``.

Stimulus names: addresses, symbols, FB *input* pins of the parameter set, FB variables.
An input address (I…) is written on the module side (PI), so the CPU reads it at the start
of the cycle. A chart that does not compile, an unknown name or a pin outside the parameter
set: diagnostics on stderr, exit status 2. ``--blocks`` S7-SCL sources bring the user FBs
and FCs the chart calls (and OBs that run beside it, ``web.harness.scl``); a call of a
block the CPU does not have is a warning on stderr.
When the CPU goes to STOP (a block error without OB121, as on S7), the trace ends with
that cycle's line, the reason goes to stderr and the exit status is 1.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any, TextIO

from s7graph.engine.clock import VirtualClock
from s7graph.engine.errors import S7Error
from s7graph.engine.record import ScanRecord
from s7graph.sequencer.compiled import CompiledChart
from s7graph.web.cli.report import fail
from s7graph.web.cli.trace import Stimulus, checked_inputs, ms, run_trace, trace_out
from s7graph.web.harness.plant import LoadedPlant, PlantError, load_plant
from s7graph.web.harness.session import ChartSession


def _events(cc: CompiledChart, fired: list[int]) -> list[list[str]]:
    pairs: list[list[str]] = []
    for j in fired:
        for s in cc.tr_src[j]:
            src = cc.step_label(s)
            if cc.tr_dst[j]:
                pairs.extend([src, cc.step_label(d)] for d in cc.tr_dst[j])
            else:
                pairs.append([src, "STOP"])
    return pairs


def sim_command(
    chart: Path,
    /,
    *,
    stimulus: Path | None = None,
    cycle_ms: float = 10.0,
    cycles: int = 100,
    watch: str = "",
    trace: Path | None = None,
    symbols: Path | None = None,
    plant: Path | None = None,
    blocks: Sequence[Path] = (),
) -> int:
    """Run ``chart`` for ``cycles`` cycles; return the exit status (docs/cli.md, "s7graph sim").
    ``blocks``: S7-SCL sources whose FBs and FCs the chart's calls reach, whose OBs run
    beside it."""
    try:
        session = ChartSession.load(chart, symbols, VirtualClock(), blocks=blocks)
        stim, names = checked_inputs(session, stimulus, watch)
        loaded: LoadedPlant | None = load_plant(plant) if plant is not None else None
    except S7Error as exc:  # ChartLoadError included
        return fail(exc)
    for line in session.warnings + session.missing:
        print(line, file=sys.stderr)
    try:
        with trace_out(trace) as out:
            return _run(session, stim, names, loaded, cycle_ms, cycles, out)
    except PlantError as exc:
        return fail(exc, 1)
    except S7Error as exc:
        return fail(exc)


def _run(
    session: ChartSession,
    stim: Stimulus,
    names: list[str],
    plant: LoadedPlant | None,
    cycle_ms: float,
    cycles: int,
    out: TextIO,
) -> int:
    cc = session.cc
    clock = session.clock
    assert isinstance(clock, VirtualClock)
    session.start()
    startup = list(session.graph.state.fired)  # the startup call's switches: in line 0

    def cycle(k: int, t_ms: float) -> tuple[ScanRecord, dict[str, Any]]:
        record = session.scan()
        st = session.graph.state
        if plant is not None:
            plant.cycle(session, ms(t_ms), ms(cycle_ms))
        return record, {
            "active": [
                cc.step_label(i) for i in sorted(st.active, key=cc.step_numbers.__getitem__)
            ],
            "events": _events(cc, startup + st.fired if k == 0 else st.fired),
            "mode": st.mode,
        }

    return run_trace(session, clock, cycle, stim, names, cycle_ms, cycles, out)
