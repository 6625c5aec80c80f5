"""The example algorithms of the S7-SCL chapter (STEP7 comprehensive guide vol. 2, ch. 13,
"Examples of programming in SCL") as blocks in a real CPU on the virtual clock."""

from __future__ import annotations

import struct

from s7graph.engine import CpuMode
from tests.paths import EXAMPLES
from tests.steps.scl.helpers import run

GUIDE = EXAMPLES / "scl_guide"  # the listings, shared with bench/scl.py


def listing(name: str) -> str:
    return (GUIDE / f"{name}.scl").read_text(encoding="utf-8")


AVERAGE, BIT_COUNT, SORT = listing("average"), listing("bit_count"), listing("sort")
SORT_AS_PRINTED, INTEGRATOR = listing("sort_as_printed"), listing("integrator")
OB80, MESSAGES, SETPOINT = listing("ob80"), listing("messages"), listing("setpoint")


def test_average_of_n_reals_in_md0_and_up_goes_to_md100() -> None:
    def fill(cpu: object) -> None:
        for k in range(10):
            cpu.mem.markers[4 * k : 4 * k + 4] = struct.pack(">f", 1.5 * (k + 1))  # type: ignore[attr-defined]

    cpu = run(AVERAGE, before=fill)
    assert struct.unpack(">f", cpu.mem.markers[100:104])[0] == 8.25


def test_bit_counting_of_iw0_counts_the_closed_switches_into_mw0() -> None:
    def switches(cpu: object) -> None:
        cpu.mem.periph_in[0:2] = (0b0110_0001_1000_0101).to_bytes(2, "big")  # type: ignore[attr-defined]

    cpu = run(BIT_COUNT, before=switches)
    assert cpu.mem.get("MW0") == 6


DATA = [7, -3, 12, 0, 5, 5, -8, 30, 1, 2]


def words(cpu: object) -> list[int]:
    data = cpu.mem.dbs[1].data  # type: ignore[attr-defined]
    return [int.from_bytes(data[2 * k : 2 * k + 2], "big", signed=True) for k in range(10)]


def test_sorting_db1_with_goto_loops_leaves_ten_ints_in_order() -> None:
    """The guide's bubble sort of DB1 with two GOTO loops, its pass bounds reset for each
    pass (the listing as printed keeps ``low`` and ``i`` from the pass before)."""
    assert "low := 2" in SORT and "a001: ;" in SORT
    cpu = run(SORT)
    assert cpu.mode is CpuMode.RUN
    assert words(cpu) == sorted(DATA)


def test_the_sorting_listing_as_printed_does_what_a_reading_of_it_does() -> None:
    """Every GOTO goes where the listing says: the result is that of a line-by-line
    reading of it (which stops before the words are in order)."""
    v, n = list(DATA), 10
    i, low = 2 * n - 2, 0
    swap = 1
    while swap:
        swap = 0
        while True:
            low += 1
            if v[(i - 2) // 2] > v[i // 2]:
                v[(i - 2) // 2], v[i // 2] = v[i // 2], v[(i - 2) // 2]
                swap = 1
            else:
                i -= 2
            if i < low:
                break
    cpu = run(SORT_AS_PRINTED)
    assert words(cpu) == v != sorted(DATA)
    assert cpu.mem.get("MW0") == i


def test_the_integrator_sums_trapezoids_over_time_tck_and_resets() -> None:
    """IN = 2.0 for one second in 100 ms cycles integrates to 2.0; a rising input (the
    trapezoids of a ramp) to the area under it; RESET starts over."""
    src = INTEGRATOR

    def enable(cpu: object) -> None:
        cpu.mem.set("M0.0", True)  # type: ignore[attr-defined]
        cpu.mem.set("MW10", 4)  # type: ignore[attr-defined]

    cpu = run(src, 11, ms=100, before=enable)
    db = cpu.instance_db(1)
    assert abs(db["OUT"] - 2.0) < 1e-5
    cpu.mem.set("M0.1", True)
    cpu.scan()
    assert db["OUT"] == 0.0 and db["RESET_ACTIV"] is True


def test_the_integrator_of_a_ramp_is_the_area_of_the_triangle() -> None:
    """IN = t over 0..2 s: the trapezoids are exact, OUT = 2.0."""
    src = INTEGRATOR.replace("* 0.5", "/ 10.0")
    cpu = run(src, 0)
    cpu.mem.set("M0.0", True)
    for k in range(21):  # IN = k / 10 at t = k * 100 ms
        cpu.mem.set("MW10", k)
        cpu.scan()
        cpu.clock.advance(100)  # type: ignore[attr-defined]
    assert abs(cpu.instance_db(1)["OUT"] - 2.0) < 1e-5


def test_the_ob80_handler_sees_flt_id_1_when_the_cycle_time_is_exceeded() -> None:
    cpu = run(OB80, 2)
    assert cpu.mem.get("M0.0") is False
    cpu.clock.advance(200)  # type: ignore[attr-defined]
    cpu.scan()
    assert cpu.mode is CpuMode.RUN
    assert cpu.mem.get("M0.0") is True and cpu.mem.get("MB1") == 80


def test_the_message_generator_builds_motor_12_started_in_the_text_buffer() -> None:
    def press(cpu: object) -> None:
        mem = cpu.mem  # type: ignore[attr-defined]
        mem.set("MW0", 1)
        mem.set("MW2", 2)
        mem.periph_in[2:4] = (12).to_bytes(2, "big")
        mem.set("M10.0", True)

    cpu = run(MESSAGES, 2, before=press, names={"Messagetexts": "DB10", "Textgenerator": "FC10"})
    db = cpu.mem.dbs[10].data
    assert cpu.mem.get("DB10.DBW0") == 1  # the next free line
    text = db[4 : 4 + db[3]].decode("latin-1")
    assert text == "Motor12started"
    assert cpu.mem.get("M10.2") is True and cpu.mem.get("M10.1") is True


def test_the_setpoint_ramp_in_ob35_rises_holds_falls_and_stops_the_cpu() -> None:
    """The guide's heat-treatment ramp, OB35 every second (its listing reads the elapsed
    seconds from MW2 but never counts them: here ``b`` counts)."""

    def every_second(cpu: object) -> None:
        cpu.interrupts.configure(35, 1000)  # type: ignore[attr-defined]

    cpu = run(SETPOINT, 0)
    cpu.stop()
    every_second(cpu)
    cpu.start()
    for _ in range(51):
        cpu.scan()
        cpu.clock.advance(100)  # type: ignore[attr-defined]
    assert (cpu.mem.get("MW0"), cpu.mem.get("MW2")) == (405, 5)
    cpu.mem.set("MW2", 7200)
    for _ in range(10):
        cpu.scan()
        cpu.clock.advance(100)  # type: ignore[attr-defined]
    assert cpu.mem.get("MW0") == 403
    cpu.mem.set("MW2", 9000)
    for _ in range(10):
        cpu.scan()
        cpu.clock.advance(100)  # type: ignore[attr-defined]
    assert cpu.mode is CpuMode.STOP
