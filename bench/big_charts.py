"""Charts that took a long time to compile, for the compiler-process tests and the
``downloads`` scenario of ``bench/jitter.py``: a chart of about 1 MB (1,000 steps of
many action rows, the editor's limits) and a chain of 5,000 ANDed contacts, both as the
drill's block (``FUNCTION_BLOCK "Seq_drill" FB 1 DB 1``) so that the drill takes them, and
within the CPU's 256 bytes of markers so that it runs them."""

from __future__ import annotations

from s7graph.sequencer.change.base import MAX_SOURCE, MAX_STEPS


def _head(name: str) -> list[str]:
    return [f'FUNCTION_BLOCK "{name}" FB 1 DB 1', "  PARAMETERS := STANDARD;"]


def huge_chart(chars: int = MAX_SOURCE - 10_000, name: str = "Seq_drill") -> str:
    """About ``chars`` characters: one loop of the editor's 1,000 steps, each with rows
    setting markers, each transition 8 ANDed contacts."""
    steps = MAX_STEPS
    rows = max(1, (chars // steps - 170) // 26)
    out = [*_head(name), 'SEQUENCE 1 "Big"']
    for k in range(1, steps + 1):
        out.append(f'  {"INITIAL_STEP" if k == 1 else "STEP"} S{k} "s{k}":')
        for r in range(rows):
            bit = (k * 7 + r) % 4000
            out.append(f"    N M{16 + bit // 8 % 200}.{bit % 8};  // row {r:03d}")
        out.append("  END_STEP")
    for k in range(1, steps + 1):
        cond = " AND ".join(f"M{(k + i) % 90}.{i % 8}" for i in range(8))
        out.append(f"  TRANSITION T{k} FROM S{k} TO S{k % steps + 1} := {cond};")
    return "\n".join([*out, "END_SEQUENCE", "END_FUNCTION_BLOCK"]) + "\n"


def contact_chain(contacts: int = 5_000, name: str = "Seq_drill") -> str:
    """Two steps, the first left by one transition of ``contacts`` ANDed contacts."""
    cond = " AND ".join(f"M{i // 8 % 250}.{i % 8}" for i in range(contacts))
    return (
        "\n".join(
            [
                *_head(name),
                'SEQUENCE 1 "Chain"',
                '  INITIAL_STEP S1 "Ready":',
                "  END_STEP",
                '  STEP S2 "Go":',
                "  END_STEP",
                f"  TRANSITION T1 FROM S1 TO S2 := {cond};",
                "  TRANSITION T2 FROM S2 TO S1 := M0.0;",
                "END_SEQUENCE",
                "END_FUNCTION_BLOCK",
            ]
        )
        + "\n"
    )
