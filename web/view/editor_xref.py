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
import html
import re
from collections.abc import Callable
from pathlib import PurePath
from typing import TYPE_CHECKING, Any, Final

import viser

from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.text.elements import Ref, RowRef, StepRef, TransitionRef
from s7graph.sequencer.text.model import Chart
from s7graph.sequencer.xref import CrossReferences, Use, cross_references
from s7graph.steps.scl import SclError
from s7graph.steps.scl import model as scl
from s7graph.steps.scl.parse import parse_source
from s7graph.web.bus.protocol import BlockSources
from s7graph.web.view import texts
from s7graph.web.view.block_links import BlockButtons
from s7graph.web.view.editor_cpu import Located
from s7graph.web.view.engineering import EditorPage

__all__ = [
    "MAX_OPERANDS",
    "MAX_USES",
    "NO_OPERAND",
    "CrossReferencing",
    "block_key",
    "key_ref",
    "parsed_blocks",
    "use_label",
]

NO_OPERAND: Final = "(choose an operand)"
MAX_OPERANDS: Final = 400  # operands the dropdown offers (a chart's own are far fewer)
MAX_USES: Final = 24  # uses shown as buttons; the rest are counted


_NUMBERED = re.compile(r"([A-Z]+) (\d+)")
_NAMED = re.compile(r'[A-Z]+ "(.+)"')


def use_label(use: Use) -> str:
    """A use as its button says it: ``S2 "Clamp" row 1 (S1 S) · set · line 24``; in a
    block, its file: ``OB 35 · write · oven.scl:32``."""
    if use.ref is None:
        return f"{use.element} · {use.access} · {PurePath(use.loc.file).name}:{use.loc.line}"
    return f"{use.element} · {use.access} · line {use.loc.line}"


def block_key(element: str) -> str | None:
    """The key the CPU's sources find a block by (``web.view.block_links.find_block``) for
    a use's element: ``OB 35`` → ``OB35``, ``FC "Scale"`` → ``"Scale"``; None for an element
    of the chart."""
    numbered = _NUMBERED.fullmatch(element)
    if numbered is not None:
        return f"{numbered[1]}{numbered[2]}"
    named = _NAMED.fullmatch(element)
    return f'"{named[1]}"' if named is not None else None


def parsed_blocks(sources: BlockSources | None) -> list[scl.Source]:
    """The CPU's S7-SCL blocks, each parsed where it stands in its file (its lines counted
    from its first); a block that does not parse is left out."""
    out: list[scl.Source] = []
    for block in sources.blocks if sources is not None else []:
        try:
            out.append(parse_source("\n" * max(block.line - 1, 0) + block.text, block.file))
        except (SclError, RecursionError):
            continue
    return out


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

        def _click(self, action: Callable[[], object]) -> Callable[[Any], None]: ...

        def _guarded(self, action: Callable[[], object]) -> None: ...

        def _place_at(
            self, at: Ref | tuple[float, float] | None, *, unfold: bool = True
        ) -> None: ...

        def select(self, ref: Ref | None) -> None: ...

    def _xref_build(self, side: Any) -> None:
        gui = self.client.gui
        self._xref: CrossReferences | None = None
        self._xref_buttons: list[Any] = []
        self._xref_shown: tuple[Use, ...] = ()
        self._xref_blocks: list[scl.Source] | None = None  # read at the first listing
        with side.add_tab("Cross-references"):
            self.xref_choice = gui.add_dropdown(
                "Uses of",
                (NO_OPERAND,),
                hint="An operand of the chart or of its S7-SCL blocks: where is it used?",
            )
            self.xref_html = gui.add_html(texts.small("Choose an operand to list its uses."))
            self.xref_folder = gui.add_folder("Uses")
        read = self.panel.wiring.blocks
        notify = functools.partial(self._notify, ok=False)
        self._xref_sources = BlockButtons(self.client, self.xref_folder, read, notify)
        self.xref_choice.on_update(lambda _: self._guarded(self._xref_uses))

    def _xref_show(self, chart: Chart) -> None:
        """The operands of ``chart`` (as the source view writes it) and of the CPU's S7-SCL
        blocks to choose from."""
        if self._xref_blocks is None:
            self._xref_blocks = parsed_blocks(self._xref_sources.read())
        blocks = self._xref_blocks
        self._xref = cross_references(self.located.chart or chart, self.symbols, blocks)
        options = (NO_OPERAND, *list(self._xref.operands())[:MAX_OPERANDS])
        if tuple(self.xref_choice.options) != options:
            if str(self.xref_choice.value) not in options:
                self.xref_choice.value = NO_OPERAND  # type: ignore[misc]
            self.xref_choice.options = options
        self._xref_uses()

    def _xref_uses(self) -> None:
        """The uses of the operand chosen, a button each."""
        chosen, refs = str(self.xref_choice.value), self._xref
        uses = tuple(u for u in refs.uses if u.operand == chosen) if refs is not None else ()
        if uses == self._xref_shown and self._xref_buttons:
            return
        self._xref_shown = uses
        for button in self._xref_buttons:
            button.remove()
        self._xref_buttons = []
        if not uses:
            text = "Choose an operand to list its uses."
            if refs is not None and refs.unused:
                text += " Symbols never used: " + ", ".join(f'"{n}"' for n in refs.unused)
            self.xref_html.content = texts.small(html.escape(text))
            return
        more = len(uses) - MAX_USES
        said = f"{len(uses)} use{'s' if len(uses) != 1 else ''}" + (
            f"; the first {MAX_USES} below" if more > 0 else ""
        )
        self.xref_html.content = texts.small(f"<b>{html.escape(chosen)}</b>: {said}")
        with self.xref_folder:
            for use in uses[:MAX_USES]:
                place = f"line {use.loc.line}, column {use.loc.col}"
                hint = f"select it: {place}" if use.ref else f"open the block's source: {place}"
                button = self.client.gui.add_button(use_label(use), hint=hint)
                button.on_click(self._click(functools.partial(self._xref_go, use)))
                self._xref_buttons.append(button)

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
