"""*Cross-references* in edit mode: the chart's operands, and for the one chosen every use
— the element, the access, the line of the source view — a click on one selecting its
element on the chart, as TIA Portal's cross-reference list jumps to a use
(``sequencer.xref``; docs/online-change.md, "Editing in the browser and downloading").
The uses in the S7-SCL blocks the CPU runs beside the chart follow (its sources read once
per edit session, ``BusClient.blocks``); a click on one opens that block's source.
``CrossReferencing`` is a part of ``web.view.editor.Editor``, which owns the attributes it
declares.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import viser

from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.text.elements import Ref, RowRef, StepRef, TransitionRef
from s7graph.sequencer.text.model import Chart
from s7graph.sequencer.xref import CrossReferences, Use, cross_references
from s7graph.steps.scl import model as scl
from s7graph.web.view.block_links import BlockButtons
from s7graph.web.view.editor_cpu import Located
from s7graph.web.view.engineering import EditorPage
from s7graph.web.view.uses_list import UsesList, block_key, parsed_blocks

__all__ = ["CrossReferencing", "key_ref"]


def key_ref(ref: Ref | None) -> Ref | None:
    """The element the editor selects for ``ref``: a row's or a step part's step (its form
    shows the rows and conditions), else ``ref``."""
    if isinstance(ref, RowRef):
        return StepRef(ref.step)
    if isinstance(ref, StepRef) and ref.part:
        return StepRef(ref.number)
    return ref


class CrossReferencing:
    """The *Cross-references* tab of the editor's side panel."""

    client: viser.ClientHandle
    located: Located
    symbols: SymbolTable | None
    panel: EditorPage

    if TYPE_CHECKING:

        def _notify(self, title: str, body: str, *, ok: bool) -> None: ...

        def _guarded(self, action: Callable[[], object]) -> None: ...

        def _place_at(
            self, at: Ref | tuple[float, float] | None, *, unfold: bool = True
        ) -> None: ...

        def select(self, ref: Ref | None) -> None: ...

    def _xref_build(self, side: Any) -> None:
        self._xref: CrossReferences | None = None
        self._xref_blocks: list[scl.Source] | None = None  # read at the first listing
        with side.add_tab("Cross-references"):
            self.xref_list = UsesList(
                self.client,
                hint="An operand of the chart or of its S7-SCL blocks: where is it used?",
                go=self._xref_go,
                guard=self._guarded,
            )
        read = self.panel.wiring.blocks
        notify = functools.partial(self._notify, ok=False)
        self._xref_sources = BlockButtons(self.client, self.xref_list.folder, read, notify)

    def _xref_show(self, chart: Chart) -> None:
        """The operands of ``chart`` (as the source view writes it) and of the CPU's S7-SCL
        blocks to choose from."""
        if self._xref_blocks is None:
            self._xref_blocks = parsed_blocks(self._xref_sources.read())
        blocks = self._xref_blocks
        self._xref = cross_references(self.located.chart or chart, self.symbols, blocks)
        self.xref_list.show(self._xref)

    def _xref_go(self, use: Use) -> None:
        """Select the element of a use, its form beside it on the chart; open the source of
        the block a use in a block stands in."""
        key = block_key(use.element) if use.ref is None else None
        if key is not None:
            self._xref_sources.open(key, use.element)
            return
        target = key_ref(use.ref)
        if isinstance(target, StepRef | TransitionRef):
            self._place_at(target)
        self.select(target)
