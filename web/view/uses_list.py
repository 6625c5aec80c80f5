"""A cross-reference list on a page (``sequencer.xref``), as TIA Portal's: *Uses of* offers
the operands, and each use of the one chosen is a button — the element, the access, the
place — that goes to it. The editor's *Cross-references* tab (``web.view.editor_xref``)
and a program's page (``web.view.program_view``) show one each, with the uses in the
S7-SCL blocks the CPU runs (:func:`parsed_blocks`; a use there opens its block's source:
:func:`block_key`).
"""

from __future__ import annotations

import functools
import html
import re
from collections.abc import Callable
from pathlib import PurePath
from typing import Any, Final

import viser

from s7graph.sequencer.xref import CrossReferences, Use
from s7graph.steps.scl import SclError
from s7graph.steps.scl import model as scl
from s7graph.steps.scl.parse import parse_source
from s7graph.web.bus.protocol import BlockSources
from s7graph.web.view import texts

__all__ = [
    "MAX_OPERANDS",
    "MAX_USES",
    "NO_OPERAND",
    "UsesList",
    "block_key",
    "parsed_blocks",
    "use_label",
]

NO_OPERAND: Final = "(choose an operand)"
MAX_OPERANDS: Final = 400  # operands the dropdown offers (a chart's own are far fewer)
MAX_USES: Final = 24  # uses shown as buttons; the rest are counted
_CHOOSE: Final = "Choose an operand to list its uses."

_NUMBERED = re.compile(r"([A-Z]+) (\d+)")
_NAMED = re.compile(r'[A-Z]+ "(.+)"')


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


def use_label(use: Use) -> str:
    """A use as its button says it: ``S2 "Clamp" row 1 (S1 S) · set · line 24``; in a
    block, its file: ``OB 35 · write · oven.scl:32``."""
    if use.ref is None:
        return f"{use.element} · {use.access} · {PurePath(use.loc.file).name}:{use.loc.line}"
    return f"{use.element} · {use.access} · line {use.loc.line}"


class UsesList:
    """*Uses of*, a line saying how many, and the folder of buttons, built where the GUI
    is now; ``go(use)`` runs when a use's button is clicked, through ``guard`` (which keeps
    an error from killing a viser callback)."""

    def __init__(
        self,
        client: viser.ClientHandle,
        *,
        hint: str,
        go: Callable[[Use], None],
        guard: Callable[[Callable[[], object]], None],
    ) -> None:
        gui = client.gui
        self.client, self._go, self._guard = client, go, guard
        self.refs: CrossReferences | None = None
        self._buttons: list[Any] = []
        self._shown: tuple[Use, ...] = ()
        self.choice = gui.add_dropdown("Uses of", (NO_OPERAND,), hint=hint)
        self.line = gui.add_html(texts.small(_CHOOSE))
        self.folder = gui.add_folder("Uses")
        self.choice.on_update(lambda _: self._guard(self._uses))

    def show(self, refs: CrossReferences) -> None:
        """Offer the operands of ``refs``; the one chosen stays chosen while it is there."""
        self.refs = refs
        options = (NO_OPERAND, *list(refs.operands())[:MAX_OPERANDS])
        if tuple(self.choice.options) != options:
            if str(self.choice.value) not in options:
                self.choice.value = NO_OPERAND  # type: ignore[misc]
            self.choice.options = options
        self._uses()

    def _uses(self) -> None:
        """The uses of the operand chosen, a button each."""
        chosen, refs = str(self.choice.value), self.refs
        uses = tuple(u for u in refs.uses if u.operand == chosen) if refs is not None else ()
        if uses == self._shown and self._buttons:
            return
        self._shown = uses
        for button in self._buttons:
            button.remove()
        self._buttons = []
        if not uses:
            text = _CHOOSE
            if refs is not None and refs.unused:
                text += " Symbols never used: " + ", ".join(f'"{n}"' for n in refs.unused)
            self.line.content = texts.small(html.escape(text))
            return
        more = len(uses) - MAX_USES
        said = f"{len(uses)} use{'s' if len(uses) != 1 else ''}" + (
            f"; the first {MAX_USES} below" if more > 0 else ""
        )
        self.line.content = texts.small(f"<b>{html.escape(chosen)}</b>: {said}")
        with self.folder:
            for use in uses[:MAX_USES]:
                place = f"line {use.loc.line}, column {use.loc.col}"
                hint = f"select it: {place}" if use.ref else f"open the block's source: {place}"
                button = self.client.gui.add_button(use_label(use), hint=hint)
                button.on_click(self._clicked(use))
                self._buttons.append(button)

    def _clicked(self, use: Use) -> Callable[[Any], None]:
        return lambda _: self._guard(functools.partial(self._go, use))
