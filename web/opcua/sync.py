"""Synchronization as an OPC UA method (docs/opcua.md, "Synchronize"): ``Synchronize`` on
each FB's object asks the CPU where the process stands in the chart (the bus's
``fb/<fb>/sync``; docs/semantics.md, "Synchronization") and answers the steps found — a
read, which any session may call, so that an HMI offers the operator the steps to resume at
before it sends ``SetSteps`` in MAN.
"""

from __future__ import annotations

from typing import Final

from asyncua import ua

from s7graph.web.bus.protocol import SyncReport
from s7graph.web.opcua.methods import refusal_status
from s7graph.web.opcua.typed import ObjectIds, StatusCodes, ua_id

__all__ = ["DESCRIPTION", "NAME", "TIMEOUT_S", "sync_output_arguments", "sync_result"]

NAME: Final = "Synchronize"
DESCRIPTION: Final = (
    "where the process stands in the chart (S7-GRAPH's synchronization): the steps whose "
    "interlock holds and whose next transition does not (Fits), those of them a transition "
    "into which holds too (Likely); a read, any session; resume at them with SetSteps in MAN"
)
TIMEOUT_S: Final = 5.0
"""How long a call waits for the CPU's next scan boundary."""


def _argument(name: str, oid: int, text: str, rank: int) -> ua.Argument:
    return ua.Argument(
        Name=name, DataType=ua_id(oid), ValueRank=rank, Description=ua.LocalizedText(text)
    )


def sync_output_arguments() -> list[ua.Argument]:
    """``Likely`` and ``Fits`` (step numbers, in chart order) and ``Cycle``."""
    one, scalar = ua.ValueRank.OneDimension, ua.ValueRank.Scalar
    return [
        _argument("Likely", ObjectIds.UInt16, "the steps that fit and were entered", one),
        _argument("Fits", ObjectIds.UInt16, "every step that fits, the likely ones too", one),
        _argument("Cycle", ObjectIds.UInt64, "the scan whose values were judged", scalar),
    ]


def sync_result(report: SyncReport) -> tuple[int, list[ua.Variant]]:
    """The status code and output variants of ``report``: ``Good`` with the steps, or the
    status code of why nothing was judged (no answer: ``BadCommunicationError``; the FB
    not called yet: ``BadInvalidState``; the queue full: ``BadResourceUnavailable``). A
    report names no kind: its words decide, the FB's name it begins with left out (an FB
    ``Seq_busy`` not called yet is no busy CPU)."""
    if report.error:
        said = report.error.removeprefix(f"{report.fb}: ") if report.fb else report.error
        return refusal_status(said), []
    likely = [s.number for s in report.steps if s.likely]  # StepNo: a UInt16 already
    fits = [s.number for s in report.steps if s.fits]
    return StatusCodes.Good, [
        ua.Variant(likely, ua.VariantType.UInt16),
        ua.Variant(fits, ua.VariantType.UInt16),
        ua.Variant(report.cycle, ua.VariantType.UInt64),
    ]
