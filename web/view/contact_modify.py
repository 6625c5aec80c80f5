"""*Modify to 1* and *Modify to 0* on the contacts *Details* shows, as TIA Portal offers them
on an operand of a block's or a sequence's status (docs/view.md, "Modify a contact").

An engineer looking at why a step does not switch sees its transitions' contacts, red and
green; the one that blocks is often a bit to set by hand while commissioning. For the step
or transition *Details* shows, :func:`contact_operands` lists the operands of its contacts
that are bits one may write — a symbol (``"Start"``) or a bit address of the inputs,
outputs, flags or a DB (``I0.3``, ``M10.1``, ``DB20.DBX0.1``), each once, in the order
they stand in the conditions: a step's outgoing transitions, its interlock, its
supervision. A comparison, a step's or a transition's attribute (``S3.X``, ``T1.TT``) or
a word is left out. :class:`ContactModify` puts them in a list with the two buttons in
the *Details* folder of a page whose role may ``modify``; each button sends one
``modify`` command (``engine/modify.py``: written once, audited).
"""

from __future__ import annotations

import re
from collections.abc import Callable
from typing import Final

import viser

from s7graph.web.bus.protocol import ChartLayout
from s7graph.web.view.watch_table import set_choices

__all__ = ["NONE", "ContactModify", "contact_operands"]

NONE: Final = "(no contact to modify)"
MAX_OPERANDS: Final = 64
_BIT: Final = re.compile(
    r'^(?:"[^"]{1,62}"|[IQM]\s*\d{1,5}\.[0-7]|DB\s*\d{1,5}\.DBX\s*\d{1,5}\.[0-7])$',
    re.IGNORECASE,
)


def contact_operands(layout: ChartLayout, key: tuple[str, int]) -> list[str]:
    """The bit operands of the contacts of what *Details* shows: ``("T", n)`` transition
    ``n``'s condition; ``("S", n)`` step ``n``'s outgoing transitions, interlock and
    supervision (``n`` 0: none)."""
    kind, number = key
    spans: list[tuple[str, list[tuple[int, int]]]] = []
    if kind == "T":
        spans += [(t.condition, t.contacts) for t in layout.transitions if t.number == number]
    else:
        spans += [(t.condition, t.contacts) for t in layout.transitions if number in t.sources]
        step = layout.step(number)
        if step is not None:
            spans.append((step.interlock_condition, step.interlock_contacts))
            spans.append((step.supervision_condition, step.supervision_contacts))
    out: dict[str, None] = {}
    for text, contacts in spans:
        for start, end in contacts:
            operand = text[start:end].strip()
            if _BIT.match(operand):
                out.setdefault(operand)
    return list(out)[:MAX_OPERANDS]


class ContactModify:
    """The list of contacts and *Modify to 1* / *Modify to 0* in a page's *Details* folder
    (render thread) for the chart ``layout`` (set it again after an online change);
    ``modify(operand, value)`` sends one ``modify`` as the page's user (the watch table's
    *Modify now* sends through the same)."""

    def __init__(
        self,
        client: viser.ClientHandle,
        folder: viser.GuiFolderHandle,
        layout: ChartLayout,
        modify: Callable[[str, str], object],
    ) -> None:
        self.layout = layout
        self._send = modify
        self._shown: tuple[ChartLayout, tuple[str, int]] | None = None
        self._options: tuple[str, ...] = (NONE,)
        gui = client.gui
        with folder:
            self.choice = gui.add_dropdown(
                "Contact",
                self._options,
                initial_value=NONE,
                hint="a contact of the step or transition shown, to write once by hand",
            )
            self.on = gui.add_button(
                "Modify to 1",
                disabled=True,
                hint="write TRUE once (STEP 7's Modify); the program may write it again",
            )
            self.off = gui.add_button(
                "Modify to 0",
                disabled=True,
                hint="write FALSE once (STEP 7's Modify); the program may write it again",
            )
        self.on.on_click(lambda _: self._modify("TRUE"))
        self.off.on_click(lambda _: self._modify("FALSE"))

    def show(self, key: tuple[str, int]) -> None:
        """Offer the contacts of what *Details* shows (``contact_operands``; none: the
        buttons disabled); the choice stays while it is still offered."""
        if self._shown == (self.layout, key):
            return
        self._shown = (self.layout, key)
        operands = contact_operands(self.layout, key)
        options = tuple(operands) or (NONE,)
        if options == self._options:
            return
        self._options = options
        set_choices(self.choice, options)
        self.on.disabled = self.off.disabled = not operands

    def _modify(self, value: str) -> None:
        operand = str(self.choice.value)
        if operand in self._options and operand != NONE:
            self._send(operand, value)

    def remove(self) -> None:
        """Take the list and the buttons off the page."""
        for handle in (self.choice, self.on, self.off):
            handle.remove()
