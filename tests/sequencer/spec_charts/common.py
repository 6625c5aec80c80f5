"""Shared chart builders of the SPEC conformance tests (``tests/sequencer/test_spec_*.py``).

A chart is written as source text and driven through the real cycle with the scenario
harness (``scenarios/harness.py``): 10 ms per call on a virtual clock.
"""

from __future__ import annotations

from tests.sequencer.scenarios.harness import Run


def source(sequences: str, *, header: str = "", params: str = "MAXIMUM") -> str:
    return (
        f'FUNCTION_BLOCK "Spec"\n  PARAMETERS := {params};\n{header}\n{sequences}\n'
        "END_FUNCTION_BLOCK\n"
    )


def seq(body: str, number: int = 1) -> str:
    return f'SEQUENCE {number} "s{number}"\n{body}\nEND_SEQUENCE\n'


def chart(sequences: str, *, header: str = "", params: str = "MAXIMUM") -> Run:
    return Run(source(sequences, header=header, params=params), file="spec.s7g")


def two_steps(
    rows: str, *, header: str = "", interlock: str = "", params: str = "MAXIMUM"
) -> Run:
    """S1 (initial) -T1 I0.0-> S2 (``rows``) -T2 I0.1-> S3 -T3 I0.2-> S1."""
    il = f"INTERLOCK := {interlock};" if interlock else ""
    return chart(
        seq(f"""
      INITIAL_STEP S1 "a": END_STEP
      STEP S2 "b": {il} {rows} END_STEP
      STEP S3 "c": END_STEP
      TRANSITION T1 FROM S1 TO S2 := I0.0;
      TRANSITION T2 FROM S2 TO S3 := I0.1;
      TRANSITION T3 FROM S3 TO S1 := I0.2;
    """),
        header=header,
        params=params,
    )


def enter(run: Run) -> None:
    """First call (S1), then a call that switches T1 into S2; I0.0 is released again."""
    run.call()
    run.set(I0_0=True).call()
    run.set(I0_0=False)
    assert run.active == [2]


def leave(run: Run) -> None:
    """One call that switches T2 out of S2 into S3."""
    run.set(I0_1=True).call()
    run.set(I0_1=False)
    assert run.active == [3]
