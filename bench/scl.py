"""S7-SCL benchmark (run as ``python bench/scl.py``; see bench/README.md).

**Compile.** CPU time of ``compile_scl`` on a generated source of about 1,000 lines of
realistic blocks — FBs with IF, CASE, FOR and REAL arithmetic, FCs with string functions,
global DBs with initial values, an OB calling them — given per 1,000 lines, and the share
of it that is parsing (lark and the syntax tree); the first compile of the process (which
builds lark's parser) apart; min/median/max over ``--repeat`` rounds.

**Scan.** The example algorithms of the S7-SCL chapter of the STEP7 comprehensive guide
(vol. 2, ch. 13 — average of N REALs, bit counting, sorting with GOTO, the trapezoidal
integrator over TIME_TCK, the message generator with CONCAT/RIGHT/I_STRNG; the listings of
``examples/scl_guide/`` that ``tests/steps/scl/test_examples.py`` runs, their OB1 calling
the block in every scan), each against the same logic hand-written as Python blocks with the
engine's ``@fb``/``@fc``/``@ob`` decorators and ``ctx.mem``'s typed access, as
docs/runtime.md, "Programs of blocks in Python", writes them. Each runs in its own ``Cpu``
on a ``VirtualClock`` (10 ms a scan), beside a third with an empty OB1 (the CPU's own cost
of a scan); the CPU time of ``Cpu.scan()`` alone is measured, in chunks of 50 scans, the
three in turn, so load from other processes hits them alike, and a round of ``--scans``
scans keeps each one's quickest chunk. Reported: µs per scan of each, and the SCL ÷ Python
ratio of the scan and of the block (the empty scan taken off), min/median/max over the
rounds, with the load average. The run ends by checking that both left the same result in
memory (exit status 1 otherwise). ``--count``: Python opcodes and calls per scan instead,
deterministic.
Target: SCL within 1.5× of the hand-written Python.
"""

from __future__ import annotations

import argparse
import gc
import os
import statistics
import struct
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "bench"))

from figures import opcodes, spread  # noqa: E402 (bench/ on the path first)

from s7graph import sfb  # noqa: E402
from s7graph.engine import CallContext, Cpu, InstanceDB, VirtualClock, fb, fc, ob  # noqa: E402
from s7graph.engine.address import parse_address  # noqa: E402
from s7graph.engine.blocks import DB, FB, FC, OB  # noqa: E402
from s7graph.steps.scl import compile_scl  # noqa: E402
from s7graph.steps.scl.parse import parse_source  # noqa: E402

# ---------------------------------------------------------------- the algorithms in SCL

GUIDE = ROOT / "examples" / "scl_guide"  # the guide's listings, as the tests run them


def listing(name: str) -> str:
    return (GUIDE / f"{name}.scl").read_text(encoding="utf-8")


AVERAGE, BIT_COUNT, SORT = listing("average"), listing("bit_count"), listing("sort")
INTEGRATOR = listing("integrator")
# the generator's blocks, called in every scan (the listing's OB1 calls it on an edge)
MESSAGES = (
    listing("messages").split("Organization_block OB1")[0]
    + """
ORGANIZATION_BLOCK OB1
  M10.2 := Textgenerator(unit := WORD_TO_INT(MW0), no := WORD_TO_INT(IW2),
                         status := WORD_TO_INT(MW2), value := WORD_TO_INT(MW4));
END_ORGANIZATION_BLOCK
"""
)
MESSAGE_NAMES = {"Messagetexts": "DB10", "Textgenerator": "FC10"}

EMPTY = """
ORGANIZATION_BLOCK OB1
END_ORGANIZATION_BLOCK
"""

# ---------------------------------------------------------------- the same, in Python

MD100 = parse_address("MD100")
MW0 = parse_address("MW0")
IW0 = parse_address("IW0")
MW10 = parse_address("MW10")


@fc(1, "AVERAGE", IN={"n": "INT"})
def py_average(ctx: CallContext, p: dict[str, Any]) -> None:
    mem = ctx.mem
    n = p["n"]
    total = 0.0
    for i in range(0, 4 * n, 4):
        total += mem.read_as(parse_address(f"MD{i}"), "REAL")  # type: ignore[operator]
    mem.write_as(MD100, "REAL", total / n)


@ob(1)
def py_average_ob1(ctx: CallContext) -> None:
    ctx.call(py_average, n=10)


@ob(1)
def py_bit_count(ctx: CallContext) -> None:
    mem = ctx.mem
    a = mem.read_as(IW0, "INT")
    assert isinstance(a, int)
    s = 0
    for _ in range(16):
        b = int(a / 2)  # INT division: toward zero
        s += a - b * 2
        a = b
    mem.write_as(MW0, "INT", s)


@fc(1, "SORT", IN={"n": "INT"})
def py_sort(ctx: CallContext, p: dict[str, Any]) -> None:
    mem = ctx.mem
    swap = True
    while swap:
        swap = False
        i = 2 * p["n"] - 2
        while i >= 2:
            lo, hi = parse_address(f"DB1.DBW{i - 2}"), parse_address(f"DB1.DBW{i}")
            if mem.read_as(lo, "INT") > mem.read_as(hi, "INT"):  # type: ignore[operator]
                temp1 = mem.read_as(lo, "INT")  # read again, as the guide's listing does
                mem.write_as(lo, "INT", mem.read_as(hi, "INT"))
                mem.write_as(hi, "INT", temp1)
                swap = True
            i -= 2
        mem.write_as(MW0, "INT", i)


@ob(1)
def py_sort_ob1(ctx: CallContext) -> None:
    ctx.call(py_sort, n=10)


REALS = ("IN", "OUT", "OUT_LOW", "LAST_IN", "LAST_OUT", "LAST_TIME", "ACTUAL_TIME", "X")


@fb(
    1,
    "INTEGRAL",
    IN={"IN": "REAL", "RESET": "BOOL", "ENABLE": "BOOL"},
    OUT={"OUT": "REAL", "RESET_ACTIV": "BOOL"},
    STAT={name: ("REAL", 0.0) for name in REALS[2:]} | {"n": ("INT", 0)},
)
def py_integral(ctx: CallContext, db: InstanceDB) -> None:
    v = db.values
    v["RESET_ACTIV"] = v["RESET"]
    if v["RESET"]:
        v["OUT"] = v["OUT_LOW"] = v["LAST_OUT"] = v["X"] = 0.0
        v["LAST_TIME"] = v["ACTUAL_TIME"]
        v["ACTUAL_TIME"] = ctx.call("SFC64")["RET_VAL"] / 1000.0  # type: ignore[operator]
        v["n"] = 0
    elif not v["ENABLE"]:
        v["n"] = 0
    elif v["n"] == 0:
        v["ACTUAL_TIME"] = v["LAST_TIME"] = ctx.call("SFC64")["RET_VAL"] / 1000.0  # type: ignore[operator]
        v["LAST_IN"] = v["IN"]
        v["n"] = 1
    else:
        now: float = ctx.call("SFC64")["RET_VAL"] / 1000.0  # type: ignore[operator]
        last_time: float = v["LAST_TIME"]  # type: ignore[assignment]
        x_in: float = v["IN"]  # type: ignore[assignment]
        last_in: float = v["LAST_IN"]  # type: ignore[assignment]
        span = now - last_time + (2147483.647 if now < last_time else 0.0)
        x = span * (x_in + last_in) / 2
        out: float = v["OUT"]  # type: ignore[assignment]
        low: float = v["OUT_LOW"]  # type: ignore[assignment]
        last_out, out = out, out + x
        low = (out - last_out) - x + low
        if low != 0 and abs(out / low) < 10_000_000:
            last_out, out = out, out - low
            low = (out - last_out) + low
        v.update(ACTUAL_TIME=now, LAST_TIME=now, LAST_IN=x_in, X=x, OUT=out, OUT_LOW=low)
        v["LAST_OUT"] = last_out


@ob(1)
def py_integral_ob1(ctx: CallContext) -> None:
    mem = ctx.mem
    x_in = mem.read_as(MW10, "INT") * 0.5  # type: ignore[operator]
    ctx.call(py_integral, 1, IN=x_in, RESET=mem.get("M0.1"), ENABLE=mem.get("M0.0"))


HW_AT, STATUS_AT, BUFFER_AT = 722, 812, 2  # DB10's layout: STRING[16] 18 bytes, [12] 14, [34] 36


def _i_strng(v: int) -> str:
    return f"{v:+d}"


@fc(
    10,
    "Textgenerator",
    IN={"unit": "INT", "no": "INT", "status": "INT", "value": "INT"},
    RET="BOOL",
)
def py_text(ctx: CallContext, p: dict[str, Any]) -> bool:
    mem = ctx.mem
    unit, status, value = p["unit"], p["status"], p["value"]
    text, ok = "", True
    if 1 <= unit <= 5 and 1 <= status <= 5:
        hw = mem.read_as(parse_address(f"DB10.DBB{HW_AT + 18 * (unit - 1)}"), "STRING[16]")
        st = mem.read_as(parse_address(f"DB10.DBB{STATUS_AT + 14 * (status - 1)}"), "STRING[12]")
        text = f"{hw}{_i_strng(p['no'])[-2:]}"[:34]
        text = f"{text}{st}"[:34]
        if value != 0:
            text = f"{text}{_i_strng(value)}"[:34]
    else:
        ok = False
    i = mem.read_as(DB10_INDEX, "INT")
    assert isinstance(i, int)
    mem.write_as(parse_address(f"DB10.DBB{BUFFER_AT + 36 * i}"), "STRING[34]", text)
    mem.write_as(DB10_INDEX, "INT", (i + 1) % 20)
    return ok


DB10_INDEX = parse_address("DB10.DBW0")


@ob(1)
def py_text_ob1(ctx: CallContext) -> None:
    mem = ctx.mem
    out = ctx.call(
        py_text,
        unit=mem.read_as(MW0, "INT"),
        no=mem.read_as(parse_address("IW2"), "INT"),
        status=mem.read_as(parse_address("MW2"), "INT"),
        value=mem.read_as(parse_address("MW4"), "INT"),
    )
    mem.set("M10.2", out["RET_VAL"])


# ---------------------------------------------------------------- the workloads


def _fill_reals(cpu: Cpu) -> None:
    for k in range(10):
        cpu.mem.markers[4 * k : 4 * k + 4] = struct.pack(">f", 1.5 * (k + 1))


SORT_DATA = (7, -3, 12, 0, 5, 5, -8, 30, 1, 2)


def _unsort(cpu: Cpu) -> None:
    data = cpu.mem.dbs[1].data
    data[0:20] = b"".join(v.to_bytes(2, "big", signed=True) for v in SORT_DATA)


def _switches(cpu: Cpu) -> None:
    cpu.mem.periph_in[0:4] = (0b0110_0001_1000_0101).to_bytes(2, "big") + (12).to_bytes(2, "big")


def _enable(cpu: Cpu) -> None:
    cpu.mem.set("M0.0", True)
    cpu.mem.set("MW10", 4)


def _message(cpu: Cpu) -> None:
    for name, value in (("MW0", 1), ("MW2", 2), ("MW4", 7)):
        cpu.mem.set(name, value)
    cpu.mem.periph_in[2:4] = (12).to_bytes(2, "big")


@dataclass
class Workload:
    """One algorithm: its SCL source, its Python blocks, what a CPU gets before it starts
    (``prepare``) and between scans (``between``), and the memory both must leave."""

    name: str
    scl: str
    python: tuple[OB | FB | FC, ...]
    prepare: Callable[[Cpu], None] = lambda cpu: None
    between: Callable[[Cpu], None] | None = None
    result: Callable[[Cpu], object] = lambda cpu: None
    db_of_scl: tuple[int, ...] = ()  # global DBs the Python CPU takes from the SCL program
    names: dict[str, str] = field(default_factory=dict)


def _db_bytes(number: int, size: int) -> Callable[[Cpu], object]:
    return lambda cpu: bytes(cpu.mem.dbs[number].data[:size])


WORKLOADS = (
    Workload(
        "average",
        AVERAGE,
        (py_average, py_average_ob1),
        _fill_reals,
        result=lambda cpu: cpu.mem.get("MD100"),
    ),
    Workload(
        "bit count", BIT_COUNT, (py_bit_count,), _switches, result=lambda cpu: cpu.mem.get("MW0")
    ),
    Workload(
        "sort",
        SORT,
        (py_sort, py_sort_ob1),
        between=_unsort,
        result=lambda cpu: (bytes(cpu.mem.dbs[1].data[:20]), cpu.mem.get("MW0")),
        db_of_scl=(1,),
    ),
    Workload(
        "integrator",
        INTEGRATOR,
        (py_integral, py_integral_ob1),
        _enable,
        result=lambda cpu: round(float(cpu.instance_db(1)["OUT"]), 3),  # type: ignore[arg-type]
    ),
    Workload(
        "message",
        MESSAGES,
        (py_text, py_text_ob1),
        _message,
        result=_db_bytes(10, 722),
        db_of_scl=(10,),
        names=MESSAGE_NAMES,
    ),
)


def build(w: Workload, language: str) -> tuple[Cpu, VirtualClock]:
    """A started CPU running ``w`` in ``language`` (``scl``, ``python``, ``empty``)."""
    clock = VirtualClock()
    cpu = Cpu(clock)
    sfb.install(cpu)
    program = compile_scl(w.scl, f"{w.name}.scl", blocks=sfb.SYSTEM_BLOCKS, names=w.names)
    if language == "scl":
        program.load(cpu)
    elif language == "python":
        cpu.load(
            *w.python, *(b for b in program.blocks if isinstance(b, DB) and b.number in w.db_of_scl)
        )
        for blk in w.python:
            if isinstance(blk, FB):
                cpu.create_instance_db(blk.number, blk)
    else:
        compile_scl(EMPTY, "empty.scl").load(cpu)
    cpu.start()
    if language != "empty":
        w.prepare(cpu)
        if w.between is not None:
            w.between(cpu)
    return cpu, clock


def measure(
    cpu: Cpu, clock: VirtualClock, between: Callable[[Cpu], None] | None, scans: int
) -> float:
    """µs of CPU time per ``Cpu.scan()`` over ``scans`` scans (the clock and ``between``
    outside). CPU time: a scan's time away from the processor, to other processes of a
    loaded machine, is not counted."""
    total = 0
    counter = time.process_time_ns
    scan = cpu.scan
    for _ in range(scans):
        t0 = counter()
        scan()
        total += counter() - t0
        clock.advance(10)
        if between is not None:
            between(cpu)
    return total / scans / 1000.0


CHUNK = 50
"""Scans measured in one go, the three programs in turn; a round keeps each program's
quickest chunk (the one least disturbed by the machine's other work)."""


@dataclass
class Figures:
    scl: list[float] = field(default_factory=list)
    python: list[float] = field(default_factory=list)
    empty: list[float] = field(default_factory=list)
    scan_ratio: list[float] = field(default_factory=list)
    block_ratio: list[float] = field(default_factory=list)

    def add(self, got: dict[str, float]) -> None:
        self.scl.append(got["scl"])
        self.python.append(got["python"])
        self.empty.append(got["empty"])
        self.scan_ratio.append(got["scl"] / got["python"])
        block_py = got["python"] - got["empty"]
        if block_py > 0:
            self.block_ratio.append((got["scl"] - got["empty"]) / block_py)


def run_scans(scans: int, repeat: int, only: set[str] | None) -> tuple[dict[str, Figures], bool]:
    figures: dict[str, Figures] = {}
    same = True
    for w in WORKLOADS:
        if only and w.name not in only:
            continue
        cpus = {lang: build(w, lang) for lang in ("scl", "python", "empty")}
        between = {"scl": w.between, "python": w.between, "empty": None}
        for lang, (cpu, clock) in cpus.items():
            measure(cpu, clock, between[lang], 100)  # warm up
        f = figures[w.name] = Figures()
        for _ in range(repeat):
            gc.collect()
            best = dict.fromkeys(cpus, float("inf"))
            for _ in range(max(1, scans // CHUNK)):
                for lang, (cpu, clock) in cpus.items():
                    best[lang] = min(best[lang], measure(cpu, clock, between[lang], CHUNK))
            f.add(best)
        left = {lang: w.result(cpus[lang][0]) for lang in ("scl", "python")}
        if left["scl"] != left["python"]:
            print(f"{w.name}: SCL left {left['scl']!r}, Python {left['python']!r}")
            same = False
    return figures, same


def count_opcodes(
    cpu: Cpu, clock: VirtualClock, between: Callable[[Cpu], None] | None
) -> tuple[float, float]:
    """Python opcodes and Python-level calls per ``Cpu.scan()`` (``sys.settrace`` with
    opcode events, 20 scans after 50 unmeasured ones): deterministic, unlike the times."""
    measure(cpu, clock, between, 50)
    ops = calls = 0
    for _ in range(20):
        o, c = opcodes(cpu.scan)
        ops, calls = ops + o, calls + c
        clock.advance(10)
        if between is not None:
            between(cpu)
    return ops / 20, calls / 20


def run_counts(only: set[str] | None) -> None:
    print("Python opcodes (calls) per scan, deterministic; block = the empty OB1's taken off")
    print(
        f"{'algorithm':<11} {'empty OB1':>14} {'SCL':>16} {'Python':>16} {'SCL/Python block':>17}"
    )
    for w in WORKLOADS:
        if only and w.name not in only:
            continue
        got = {}
        for lang in ("scl", "python", "empty"):
            cpu, clock = build(w, lang)
            got[lang] = count_opcodes(cpu, clock, w.between if lang != "empty" else None)
        (eo, ec), (so, sc), (po, pc) = got["empty"], got["scl"], got["python"]
        print(
            f"{w.name:<11} {eo:>7.0f} ({ec:>4.0f}) {so:>8.0f} ({sc:>5.0f}) {po:>8.0f} ({pc:>5.0f}) "
            f"{(so - eo) / (po - eo):>16.2f}x"
        )


# ---------------------------------------------------------------- compile

BLOCK_TEMPLATE = """
// Block set {k}: a motor with its monitoring, a recipe step, its texts
TYPE UDT{k}
STRUCT
  speed : REAL;
  limit : REAL;
  ramp : TIME;
  name : STRING[16];
END_STRUCT
END_TYPE

DATA_BLOCK DB{db}
STRUCT
  settings : UDT{k};
  recipe : ARRAY[1..8] OF INT := 10, 20, 30, 40, 50, 60, 70, 80;
  total : DINT := 0;
  label : STRING[24] := 'line {k}';
END_STRUCT
BEGIN
  settings.speed := 1450.0;
  settings.limit := 1600.0;
  settings.ramp := T#2S500MS;
  settings.name := 'motor {k}';
END_DATA_BLOCK

FUNCTION_BLOCK FB{k}
VAR_INPUT
  start : BOOL;
  stop : BOOL;
  feedback : BOOL;
  setpoint : REAL := 1450.0;
  actual : INT;
END_VAR
VAR_OUTPUT
  running : BOOL;
  fault : BOOL;
  deviation : REAL;
  state : INT;
END_VAR
VAR
  started_at : TIME;
  count : DINT;
  history : ARRAY[0..15] OF REAL;
  slot : INT;
  filtered : REAL;
END_VAR
VAR_TEMP
  i : INT;
  sum : REAL;
  speed : REAL;
END_VAR
  speed := INT_TO_REAL(actual) * 0.1;
  IF stop OR fault THEN
    running := FALSE;
    state := 0;
  ELSIF start AND NOT running THEN
    running := TRUE;
    count := count + 1;
    state := 1;
  END_IF;
  CASE state OF
    0: deviation := 0.0;
    1: IF feedback THEN
         state := 2;
       END_IF;
    2, 3: deviation := setpoint - speed;
       IF ABS(deviation) > 0.1 * setpoint THEN
         state := 3;
       ELSE
         state := 2;
       END_IF;
  ELSE
    fault := TRUE;
  END_CASE;
  history[slot] := speed;
  slot := (slot + 1) MOD 16;
  sum := 0.0;
  FOR i := 0 TO 15 DO
    sum := sum + history[i];
  END_FOR;
  filtered := sum / 16.0;
  IF DB{db}.settings.limit < filtered THEN
    fault := TRUE;
  END_IF;
END_FUNCTION_BLOCK

FUNCTION FC{k} : INT
VAR_INPUT
  step : INT;
  quantity : REAL;
END_VAR
VAR_OUTPUT
  message : STRING[40];
  done : BOOL;
END_VAR
VAR_TEMP
  k : INT;
  amount : DINT;
END_VAR
  done := FALSE;
  IF step < 1 OR step > 8 THEN
    message := CONCAT(IN1 := 'bad step ', IN2 := I_STRNG(step));
    FC{k} := -1;
    RETURN;
  END_IF;
  amount := 0;
  FOR k := 1 TO step DO
    amount := amount + DB{db}.recipe[k];
  END_FOR;
  DB{db}.total := DB{db}.total + amount;
  message := CONCAT(IN1 := LEFT(IN := DB{db}.label, L := 12), IN2 := R_STRNG(quantity));
  done := amount >= REAL_TO_DINT(quantity);
  FC{k} := DINT_TO_INT(amount MOD 1000);
END_FUNCTION
"""

OB_TEMPLATE = """
ORGANIZATION_BLOCK OB1
VAR_TEMP
  r : INT;
  text : STRING[40];
  ok_step : BOOL;
END_VAR
{calls}END_ORGANIZATION_BLOCK
"""

CALL = """  FB{k}.DB{inst}(start := I{k}.0, stop := I{k}.1, feedback := I{k}.2,
                  actual := WORD_TO_INT(IW{iw}));
  Q{k}.0 := DB{inst}.running;
  r := FC{k}(step := 3, quantity := 12.5, message := text, done := ok_step);
"""


def compile_source(sets: int) -> str:
    """``sets`` block sets of ``BLOCK_TEMPLATE`` and an OB1 calling each."""
    blocks = "".join(BLOCK_TEMPLATE.format(k=k, db=100 + k) for k in range(1, sets + 1))
    calls = "".join(CALL.format(k=k, inst=200 + k, iw=64 + 2 * k) for k in range(1, sets + 1))
    return blocks + OB_TEMPLATE.format(calls=calls)


def source_sets(lines: int = 1000) -> int:
    """How many block sets make a source of at most ``lines`` lines."""
    sets = 1
    while len(compile_source(sets + 1).splitlines()) <= lines:
        sets += 1
    return sets


def run_compile(repeat: int) -> tuple[int, float, list[float], list[float]]:
    """Lines of the source, the first compile (s), then per 1,000 lines: compile and parse
    CPU seconds of each round."""
    sets = source_sets()
    text = compile_source(sets)
    lines = len(text.splitlines())
    t0 = time.process_time()
    compile_scl(text, "bench.scl", blocks=sfb.SYSTEM_BLOCKS)
    first = time.process_time() - t0
    total: list[float] = []
    parse: list[float] = []
    for _ in range(repeat):
        gc.collect()
        t0 = time.process_time()
        parse_source(text, "bench.scl")
        t1 = time.process_time()
        program = compile_scl(text, "bench.scl", blocks=sfb.SYSTEM_BLOCKS)
        t2 = time.process_time()
        assert len(program.blocks) == 3 * sets + 1
        parse.append((t1 - t0) * 1000 / lines)
        total.append((t2 - t1) * 1000 / lines)
    return lines, first, total, parse


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeat", type=int, default=5, help="rounds; min/median/max (5)")
    ap.add_argument("--scans", type=int, default=2000, help="scans a round (2000)")
    ap.add_argument("--only", default="", help="algorithms, comma-separated (all)")
    ap.add_argument("--no-compile", action="store_true", help="the scan figures only")
    ap.add_argument("--count", action="store_true", help="opcodes per scan, no timing")
    args = ap.parse_args(argv)
    only = {s.strip() for s in args.only.split(",") if s.strip()} or None
    if args.count:
        run_counts(only)
        return 0
    load = os.getloadavg()
    print(
        f"python {sys.version.split()[0]}, load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}"
    )
    if not args.no_compile:
        lines, first, total, parse = run_compile(args.repeat)
        print(f"compile: a source of {lines} lines, {args.repeat} rounds (CPU time)")
        print(f"  first compile of the process (builds lark's parser) {first:.2f} s")
        print(
            f"  per 1,000 lines: compile_scl {spread(total, '{:.3f}')} s, "
            f"of it parsing {spread(parse, '{:.3f}')} s"
        )
    figures, same = run_scans(args.scans, args.repeat, only)
    print(
        f"scan: {args.repeat} rounds of {args.scans} scans each, in chunks of {CHUNK} in turn; "
        "µs of CPU time per scan, a round's quickest chunk (min/median/max over the rounds)"
    )
    head = f"{'algorithm':<11} {'empty OB1':>17} {'SCL':>20} {'Python':>20} "
    head += f"{'SCL/Python scan':>18} {'block':>18}"
    print(head)
    for name, f in figures.items():
        print(
            f"{name:<11} {spread(f.empty, '{:.1f}'):>17} {spread(f.scl, '{:.1f}'):>20} "
            f"{spread(f.python, '{:.1f}'):>20} {spread(f.scan_ratio):>18} "
            f"{spread(f.block_ratio):>18}"
        )
    medians = {n: statistics.median(f.block_ratio) for n, f in figures.items() if f.block_ratio}
    if medians:
        worst = max(medians, key=medians.__getitem__)
        print(
            f"block ratio (median of the rounds): the largest {medians[worst]:.2f}x ({worst}), "
            f"the algorithms' median {statistics.median(medians.values()):.2f}x; target 1.5x"
        )
    load = os.getloadavg()
    print(f"load average at the end {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}")
    print("same results in SCL and Python" if same else "RESULTS DIFFER")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
