"""The fast path is the general path, only faster: random charts (hypothesis) run on two
CPUs side by side — GraphFBs built with ``fast=True`` (the quiet call, the flat OB1 path,
the fused step functions, the cheap switch, the incremental display) and with
``fast=False`` (every call through ``GraphRuntime.execute``'s general path, every output
recomputed) — and every scan's trace must be equal: the step events of the scan record,
the FB output pins, the process image and markers, and the whole instance-DB content
(``GraphState.to_state``: active steps, step times, criteria, variables, display cursor).

The charts mix what the fast path takes (plain steps, one active step per sequencer) with
what makes it step aside (interlocks, supervisions, joins, simultaneous branches, ON/OFF
rows, jumps between sequencers, permanent instructions, skip steps, the CODESYS order);
the stimuli change inputs rarely enough that most calls are quiet, and sometimes pulse an
FB pin, switch the mode or queue an operator command.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as hs

from s7graph.engine.blocks import FC, OB
from s7graph.engine.clock import VirtualClock
from s7graph.engine.cpu import Cpu
from s7graph.sequencer.compile import compile_chart
from s7graph.sequencer.compiled import CompiledChart
from s7graph.sequencer.fb import GraphFB, StepEvent, install_all
from s7graph.sequencer.params import inputs_for
from s7graph.sequencer.text.parse import parse_chart

IN_BITS = tuple(f"I0.{b}" for b in range(8))
OUT_BITS = tuple(f"Q0.{b}" for b in range(8)) + tuple(f"M1.{b}" for b in range(8))


@dataclass(frozen=True)
class Program:
    """Chart texts (one per FB) and the stimulus of each scan."""

    charts: tuple[str, ...]
    scans: tuple[dict[str, Any], ...]


@hs.composite
def conditions(draw: Any, steps: list[int], transitions: list[int]) -> str:
    """A condition over inputs, step attributes, variables and transition results."""

    def atom() -> str:
        kind = draw(hs.integers(0, 9))
        if kind <= 3:
            return f"{draw(hs.sampled_from(['', 'NOT ']))}{draw(hs.sampled_from(IN_BITS))}"
        if kind == 4:
            return f"S{draw(hs.sampled_from(steps))}.T >= T#{draw(hs.sampled_from([10, 20, 40]))}MS"
        if kind == 5:
            return f"S{draw(hs.sampled_from(steps))}.X"
        if kind == 6:
            return f"v >= {draw(hs.integers(0, 4))}"
        if kind == 7:
            return f"T{draw(hs.sampled_from(transitions))}.TT"
        if kind == 8:
            return draw(hs.sampled_from(["TRUE", "FALSE", "M1.0", "NOT M1.1"]))
        return f"S{draw(hs.sampled_from(steps))}.U < T#30MS"

    parts = [atom() for _ in range(draw(hs.integers(1, 3)))]
    ops = [draw(hs.sampled_from([" AND ", " OR "])) for _ in parts[1:]]
    text = parts[0]
    for op, p in zip(ops, parts[1:], strict=True):
        text += op + p
    return text


@hs.composite
def rows(draw: Any, me: int, steps: list[int]) -> list[str]:
    """Action rows of step ``me``."""
    out = []
    for _ in range(draw(hs.integers(0, 3))):
        kind = draw(hs.integers(0, 13))
        bit = draw(hs.sampled_from(OUT_BITS))
        other = draw(hs.sampled_from(steps))
        t = draw(hs.sampled_from([10, 20, 30]))
        out.append(
            [
                f"N {bit};",
                f"NC {bit};",
                f"S {bit};",
                f"R {bit};",
                f"D {bit}, T#{t}MS;",
                f"L {bit}, T#{t}MS;",
                "N v := v + 1;",
                "S1 N v := 0;",
                "S0 N w := w + 1;",
                f"S1 N {bit};",
                f"S1 ON S{other};",
                f"S1 OFF S{other};" if other != me else "S0 N w := w - 1;",
                "V1 N w := w + 10;",
                "L1 OFF S_ALL;" if draw(hs.booleans()) else f"S0 S {bit};",
            ][kind]
        )
    return out


@hs.composite
def charts(draw: Any, fb: int) -> str:
    """One FB: 1–3 sequencers of 1–5 steps, transitions mostly along a loop, some
    alternatives and jumps; with ``wild`` > 0 also interlocks, supervisions, simultaneous
    branches, joins and branch stops (which send a sequencer down the general path)."""
    wild = draw(hs.integers(0, 2))

    def chance(*percent: int) -> bool:
        return draw(hs.integers(0, 99)) < percent[wild]

    n_seq = draw(hs.integers(1, 3))
    sizes = [draw(hs.integers(1, 5)) for _ in range(n_seq)]
    numbers = [[10 * s + k + 1 for k in range(n)] for s, n in enumerate(sizes)]
    every = [n for seq in numbers for n in seq]
    tr_numbers = list(range(1, sum(sizes) + 1))  # one leaving each step, at least
    params = draw(hs.sampled_from(["STANDARD", "STANDARD", "MAXIMUM", "USER", "MINIMUM"]))
    options = [f"  PARAMETERS := {params};"]
    for option, percent in (
        ("SKIP_STEPS", (0, 10, 20)),
        ("ORDER := CODESYS", (0, 10, 20)),
        ("ACK_REQUIRED := FALSE", (20, 30, 30)),
        ("ACK_FORCES_SWITCH", (0, 10, 20)),
    ):
        if chance(*percent):
            options.append(f"  {option if ':=' in option else option + ' := TRUE'};")
    text = [
        f'FUNCTION_BLOCK "R{fb}" FB {fb} DB {fb}',
        *options,
        "VAR v : INT := 0; w : INT := 0; END_VAR",
    ]
    if chance(10, 20, 20):
        text += [
            "PERMANENT BEFORE",
            f"  M1.0 := {draw(hs.sampled_from(IN_BITS))};",
            "END_PERMANENT",
        ]
    if chance(10, 20, 20):
        text += ["PERMANENT AFTER", "  S M1.2 := M1.1;", "END_PERMANENT"]
    tr = iter(range(1, 4 * len(every) + 1))
    for s, seq in enumerate(numbers):
        text.append(f'SEQUENCE {s + 1} "s{s + 1}"')
        for k, n in enumerate(seq):
            kw = "INITIAL_STEP" if k == 0 or chance(0, 10, 10) else "STEP"
            body = []
            if chance(0, 12, 25):
                body.append(f"INTERLOCK := {draw(conditions(every, tr_numbers))};")
            if chance(0, 10, 20):
                body.append(f"SUPERVISION := {draw(conditions(every, tr_numbers))};")
            body += draw(rows(n, every))
            text.append(f'  {kw} S{n} "s{n}": {" ".join(body)} END_STEP')
        for k, n in enumerate(seq):
            targets = [seq[(k + 1) % len(seq)]]
            sources = [n]
            dst = None
            if chance(15, 15, 20):  # a jump, maybe into another sequencer
                targets = [draw(hs.sampled_from(every))]
            elif len(seq) > 2 and chance(0, 8, 15):  # simultaneous branch
                targets = sorted({targets[0], draw(hs.sampled_from(seq))})
            elif len(seq) > 1 and chance(0, 8, 15):  # a join
                sources = sorted({n, draw(hs.sampled_from(seq))})
            elif chance(0, 4, 8):
                dst = "STOP"
            cond = draw(conditions(every, tr_numbers))
            dst = dst or _steps(targets)
            text.append(f"  TRANSITION T{next(tr)} FROM {_steps(sources)} TO {dst} := {cond};")
            if chance(25, 25, 25):  # an alternative path, lower priority
                alt = draw(hs.sampled_from(every if chance(30, 30, 30) else seq))
                cond = draw(conditions(every, tr_numbers))
                text.append(f"  TRANSITION T{next(tr)} FROM S{n} TO S{alt} := {cond};")
        text.append("END_SEQUENCE")
    text.append("END_FUNCTION_BLOCK")
    return "\n".join(text) + "\n"


def _steps(numbers: list[int]) -> str:
    return f"S{numbers[0]}" if len(numbers) == 1 else f"({', '.join(f'S{n}' for n in numbers)})"


@hs.composite
def programs(draw: Any) -> Program:
    texts = tuple(draw(charts(fb)) for fb in range(1, draw(hs.integers(1, 2)) + 1))
    pins = sorted({p.name for t in texts for p in inputs_for(_params(t))})
    scans = []
    for _ in range(draw(hs.integers(10, 80))):
        stim: dict[str, Any] = {}
        if draw(hs.integers(0, 2)) == 0:
            stim["I0"] = draw(hs.integers(0, 255))
        if pins and draw(hs.integers(0, 6)) == 0:
            pin = draw(hs.sampled_from(pins))
            sel = draw(hs.sampled_from([0, 7, 11, 12, 13, 21, 22, 31]))  # steps are 11.., 21..
            stim["pin"] = (pin, sel if pin == "S_SEL" else draw(hs.booleans()))
        if draw(hs.integers(0, 15)) == 0:
            stim["command"] = draw(
                hs.sampled_from(
                    ["ACK_EF", "INIT_SQ", "SW_MAN", "SW_AUTO", "S_ON", "T_PUSH", "OFF_SQ"]
                )
            )
            stim["step"] = draw(hs.sampled_from([None, 11, 12, 21]))
        if draw(hs.integers(0, 8)) == 0:
            stim["ms"] = draw(hs.sampled_from([0, 1, 25]))
        scans.append(stim)
    return Program(texts, tuple(scans))


def _params(text: str) -> str:
    return text.split("PARAMETERS := ", 1)[1].split(";", 1)[0]


def _compiled(program: Program) -> list[CompiledChart]:
    return [compile_chart(parse_chart(t, f"<R{k + 1}>")) for k, t in enumerate(program.charts)]


class Plant:
    """One CPU calling the program's FBs from OB1, on the fast or the general path."""

    def __init__(
        self,
        program: Program,
        *,
        fast: bool,
        blocks: tuple[Any, ...] = (),
        compiled: list[CompiledChart] | None = None,
    ) -> None:
        """``compiled``: the program's charts compiled already (a compiled chart is frozen:
        the two plants of one program share it, as a CPU and its twin do)."""
        self.clock = VirtualClock()
        self.cpu = Cpu(self.clock)
        self.cpu.load(*blocks)
        self.fbs = [GraphFB(cc, fast=fast) for cc in compiled or _compiled(program)]
        install_all(self.cpu, self.fbs)
        self.cpu.start("warm")

    def scan(self, stim: dict[str, Any]) -> dict[str, Any]:
        mem = self.cpu.mem
        if "I0" in stim:
            mem.periph_in[0] = stim["I0"]
        for g in self.fbs:
            assert g.idb is not None
            if "pin" in stim:
                name, value = stim["pin"]
                if name in g.idb.values:
                    g.idb.values[name] = value
            if "command" in stim:
                g.command(stim["command"], stim["step"])
        self.clock.advance(stim.get("ms", 10))
        rec = self.cpu.scan()
        return {
            "mode": str(rec.mode),
            "diagnostics": [str(d) for d in rec.diagnostics],
            "events": [tuple(e) for e in rec.events if isinstance(e, StepEvent)],
            "memory": (bytes(mem.inputs[:2]), bytes(mem.outputs[:2]), bytes(mem.markers[:4])),
            "fbs": [(g.outputs, g.state.to_state(), _call_lists(g)) for g in self.fbs],
        }


def _call_lists(g: GraphFB) -> tuple[list[int], ...]:
    """The per-call lists ``to_state`` leaves out (transitions fired, steps entered/left)."""
    st = g.state
    return st.fired, st.entered, st.left


def _fb(body: str) -> str:
    return (
        f'FUNCTION_BLOCK "R1" FB 1 DB 1\n  PARAMETERS := STANDARD;\n'
        f"VAR v : INT := 0; w : INT := 0; END_VAR\n{body}END_FUNCTION_BLOCK\n"
    )


# corners the random charts reach rarely
PINNED = _fb("""SEQUENCE 1 "s1"
  INITIAL_STEP S11 "a": END_STEP
  STEP S12 "b": END_STEP
  STEP S13 "c": END_STEP
  TRANSITION T1 FROM S11 TO S12 := I0.0;
  TRANSITION T2 FROM S12 TO S11 := NOT I0.0;
  TRANSITION T3 FROM S13 TO S11 := FALSE;
END_SEQUENCE
""")  # S_SEL shows an inactive step: S_MORE while the one active step switches
JUMPS = _fb("""SEQUENCE 1 "s1"
  INITIAL_STEP S11 "a": N Q0.0; END_STEP
  STEP S12 "b": N Q0.1; S1 N v := 5; END_STEP
  TRANSITION T1 FROM S11 TO S22 := I0.0 AND NOT I0.1;
  TRANSITION T2 FROM S12 TO S11 := FALSE;
END_SEQUENCE
SEQUENCE 2 "s2"
  INITIAL_STEP S21 "c": END_STEP
  STEP S22 "d": S1 ON S23; N Q0.2; END_STEP
  STEP S23 "e": N Q0.3; S1 N w := w + 1; END_STEP
  TRANSITION T3 FROM S21 TO STOP := TRUE;
  TRANSITION T4 FROM S22 TO S12 := I0.1;
  TRANSITION T5 FROM S23 TO S21 := FALSE;
END_SEQUENCE
""")  # into a later sequencer (its S1 ON row appends a step), then into an earlier one


@example(Program((PINNED,), ({}, {"pin": ("S_SEL", 13)}, {}, {"I0": 1}, {}, {"I0": 0}, {})))
@example(Program((JUMPS,), ({}, {}, {"I0": 1}, {}, {"I0": 3}, {}, {})))
@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(programs())
def test_fast_and_general_path_give_the_same_trace(program: Program) -> None:
    compiled = _compiled(program)  # once: the paths differ in the FB, not in the compile
    fast = Plant(program, fast=True, compiled=compiled)
    general = Plant(program, fast=False, compiled=compiled)
    for n, stim in enumerate(program.scans):
        a, b = fast.scan(stim), general.scan(stim)
        assert a == b, f"scan {n} ({stim}) differs:\n{program.charts[0]}"


def test_a_block_called_from_a_quiet_call_nests_and_faults_as_from_the_general_path() -> None:
    """The flat OB1 path runs a quiet call one nesting level below OB1, like the call layers
    it leaves out: a block a row calls sees the same depth, and an exception escaping the
    FB's body (here: a row calls a block that is not loaded) is reported with the FB, as on
    the general path. With OB121 loaded the CPU goes on, and so do both paths alike: a call
    an exception cut short (FC 9 raises while I0.2 is set) is not trusted by the next one
    (the S_SEL it latched is shown; the interlock it lost in S21 holds U there)."""
    text = _fb("""SEQUENCE 1 "s1"
  INITIAL_STEP S11 "a": CALL FC 9; END_STEP
  STEP S12 "b": CALL FC 8; END_STEP
  TRANSITION T1 FROM S11 TO S12 := I0.0;
  TRANSITION T2 FROM S12 TO S11 := FALSE;
END_SEQUENCE
""")
    guarded = (
        'SEQUENCE 1 "s0"\n  INITIAL_STEP S21 "c": INTERLOCK := I0.1; END_STEP\n'
        '  TRANSITION T3 FROM S21 TO S21 := FALSE;\nEND_SEQUENCE\nSEQUENCE 2 "s1"'
    )
    before = text.replace('SEQUENCE 1 "s1"', guarded)

    def probe(ctx: Any, _: Any, depths: list[int]) -> None:
        depths.append(ctx.depth)
        if ctx.cpu.mem.inputs[0] & 4:
            raise ValueError("probe")

    cut_short = [{}, {}, {"pin": ("S_SEL", 12), "I0": 4}, {"I0": 0}, {}]
    into_s12 = [{}, {}, {"I0": 1}, {}, {"I0": 0}, {}]
    interlock_lost = [{"I0": 2}, {}, {"I0": 4}, {"I0": 0}, {}]  # quiet calls in AUTO
    in_man = [{"pin": ("SW_MAN", True)}, {"I0": 2}, {"I0": 4}, {"I0": 0}, {}]  # general ones
    for chart, scans in (
        (text, cut_short),
        (text, into_s12),
        (before, interlock_lost),
        (before, in_man),
    ):
        for ob121 in ((), (OB(121, "OB121", lambda ctx: None),)):
            seen = {}
            for fast in (True, False):
                depths: list[int] = []
                fc9 = FC(9, "Probe", (), lambda ctx, p, d=depths: probe(ctx, p, d))
                plant = Plant(Program((chart,), ()), fast=fast, blocks=(fc9, *ob121))
                seen[fast] = (depths, [plant.scan(stim) for stim in scans])
            assert seen[True] == seen[False]
            depths, trace = seen[True]
            cut = next(n for n, t in enumerate(trace) if t["diagnostics"])
            assert depths[:3] == [2, 2, 2] and trace[cut]["mode"] == ("RUN" if ob121 else "STOP")
            fault = "FB1: block FC8" if scans is into_s12 else "FC9: ValueError: probe"
            assert fault in trace[cut]["diagnostics"][0]
            if ob121 and scans is cut_short:
                assert trace[-1]["fbs"][0][0]["S_NO"] == 12
