"""Where a chart calls blocks: every ``CALL`` of its action rows and permanent instructions,
with the element it is in (docs/chart-format.md).

Pure: it reads the model only, so the text's names (``sequencer.text.names``: the instance
DBs a chart's calls name) and the runtime's calls (``sequencer.calls``: the instance DBs
it creates) walk a chart's calls the one way.
"""

from __future__ import annotations

from dataclasses import dataclass

from s7graph.sequencer.text.model import BlockCall, Chart

__all__ = ["CallSite", "call_sites"]


@dataclass(frozen=True, slots=True)
class CallSite:
    """One call of the chart and the element it is in (``step S2 row 1``)."""

    call: BlockCall
    element: str

    def line(self, severity: str, problem: str) -> str:
        """One diagnostic line: ``file:line:col: error: CALL SFB 4, DB 10: …(step S2 row 1)``."""
        c = self.call
        block = f"{c.kind} {c.block}" if c.kind else f'"{c.block}"'
        if c.instance is not None:
            block += f", DB {c.instance}" if isinstance(c.instance, int) else f', "{c.instance}"'
        return f"{c.loc}: {severity}: CALL {block}: {problem} ({self.element})"


def call_sites(chart: Chart) -> list[CallSite]:
    """Every block call of ``chart``, in written order: permanent instructions before, the
    steps' rows, permanent instructions after."""
    out = [CallSite(p, "permanent before") for p in chart.before if isinstance(p, BlockCall)]
    for seq in chart.sequences:
        for step in seq.steps:
            for k, row in enumerate(step.actions, 1):
                if isinstance(row.operand, BlockCall):
                    out.append(CallSite(row.operand, f"step S{step.number} row {k}"))
    out += [CallSite(p, "permanent after") for p in chart.after if isinstance(p, BlockCall)]
    return out
