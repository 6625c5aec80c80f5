"""Blink Q0.0 from the cyclic interrupt OB35 and count the blinks in a retentive MW.

OB35 runs every 500 ms (set in ``setup``) and toggles Q0.0. OB1 feeds Q0.0 into an IEC
up-counter (SFB0 CTU semantics, ``sfb.iec_counters.CTU``) kept in instance DB 10; the count
is copied to MW0, which lies in the default retentive range MB0..MB15, so it survives a
restart. ``s7graph run examples/blink.py`` — stop with Ctrl-C.
"""

from __future__ import annotations

from s7graph.engine import CallContext, Cpu, InstanceDB, fb, ob
from s7graph.sfb.iec_counters import CTU


@fb(10, "BlinkCounter", IN={"pulse": "BOOL"}, OUT={"count": "INT"}, STAT={"ctu": ("OBJECT", CTU)})
def blink_counter(ctx: CallContext, db: InstanceDB) -> None:
    counter = db.ctu
    assert isinstance(counter, CTU)
    db.count = counter(CU=bool(db.pulse), R=False, PV=32767).cv


@ob(35, "Blink")
def blink(ctx: CallContext) -> None:
    ctx.mem.set("Q0.0", not ctx.mem.get("Q0.0"))


@ob(1, "Main")
def main(ctx: CallContext) -> None:
    out = ctx.call(blink_counter, 10, pulse=bool(ctx.mem.get("Q0.0")))
    ctx.mem.set("MW0", out["count"])


def setup(cpu: Cpu) -> None:
    cpu.interrupts.configure(35, 500)
    cpu.create_instance_db(10, blink_counter)
