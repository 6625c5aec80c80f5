"""Buttons that open a block's S7-SCL source read-only: the Details folder's links from a
step's ``CALL`` rows to the blocks they call, and a program's page's list of its blocks.

When the step shown in *Details* has action rows that call an FB or an FC (``CALL FB 17,
DB 10 (…)``, ``CALL FC 3 (…)``, ``CALL "Counter", "Inst"``), the folder gets a button per
block called — *FB 17 source* — that opens the block's S7-SCL source as the CPU runs it
(``s7graph/<cpu>/blocks``, ``web.bus.block_sources``) in a read-only window of this page,
as the engineering station opens a block online. A block the CPU has no source of (a
system block, a block of a Python program) says so in a notice. The source is read when
the button is pressed: after an online change it is the one running then. A program's
page (``web.view.program_view``) lists every OB, FB, FC and DB the CPU has a source of the
same way (:func:`listed_blocks`, :class:`BlockButtons`). Every text is escaped.
"""

from __future__ import annotations

import html
import re
from collections.abc import Callable, Sequence
from typing import Any

import viser

from s7graph.web.bus.protocol import BlockSource, BlockSources, ChartLayout

__all__ = [
    "BlockButtons",
    "BlockLinks",
    "called_blocks",
    "find_block",
    "listed_blocks",
    "source_html",
]

_CALLED = re.compile(r'\s*(?:(FB|FC)\s*(\d{1,5})\b|"([^"]{1,128})")', re.IGNORECASE)
_LABEL = re.compile(r"([A-Z]+)(\d+)$", re.IGNORECASE)
MAX_LINKS = 16  # buttons of one step at most
MAX_BLOCKS = 256  # buttons of a program's list at most


def called_blocks(layout: ChartLayout, step: int) -> list[tuple[str, str]]:
    """The blocks step ``step``'s ``CALL`` rows call, each once, in row order: ``(key,
    label)`` — the key ``FB17`` or a symbol's name ``"Counter"``, the label as the chart
    writes it (``FB 17``)."""
    info = layout.step(step)
    out: dict[str, str] = {}
    for row in info.actions if info is not None else []:
        found = _CALLED.match(row.operand) if row.qualifier.upper() == "CALL" else None
        if found is None:
            continue
        if found[1]:
            kind, number = found[1].upper(), int(found[2])
            out.setdefault(f"{kind}{number}", f"{kind} {number}")
        else:
            out.setdefault(f'"{found[3]}"', f'"{found[3]}"')
    return list(out.items())[:MAX_LINKS]


def find_block(sources: BlockSources, key: str) -> BlockSource | None:
    """The source of ``key`` (``FB17``, or ``"Counter"``: by the block's name), if any."""
    if key.startswith('"'):
        name = key.strip('"').casefold()
        return next((b for b in sources.blocks if b.name.casefold() == name), None)
    return next((b for b in sources.blocks if b.label.upper() == key), None)


def source_html(block: BlockSource) -> str:
    """The block's text, read-only, with where it was written."""
    name = f" {block.name}" if block.name and block.name != block.label else ""
    where = f"{block.file}, line {block.line}" if block.file else f"line {block.line}"
    return (
        f"<div style='font-size:0.8em'><b>{html.escape(block.label + name)}</b> "
        f"<i>({html.escape(where)}; read-only)</i></div>"
        "<pre class='s7-block-source' style='font-size:0.75em;max-height:60vh;overflow:auto;"
        f"white-space:pre;margin:0'>{html.escape(block.text)}</pre>"
    )


def listed_blocks(sources: BlockSources) -> list[tuple[str, str]]:
    """Every block of ``sources``, those left out too, in source order: ``(key, label)`` as
    :func:`find_block` takes the key (``FB17``) and the label as STEP 7 writes it (``FB 17``,
    ``FB 10 "Counter"`` for a named one)."""
    out: list[tuple[str, str]] = []
    for label, name in [(b.label, b.name) for b in sources.blocks] + [
        (left, "") for left in sources.left_out
    ]:
        split = _LABEL.match(label)
        shown = f"{split[1]} {split[2]}" if split is not None else label
        if name and name.casefold() != label.casefold():
            shown += f' "{name}"'
        out.append((label.upper(), shown))
    return out[:MAX_BLOCKS]


class BlockButtons:
    """Buttons in ``folder`` of one page, one per block, each opening the block's source
    read-only; ``read`` gives the CPU's sources (None: no answer), ``notify(title, body)``
    a notice."""

    def __init__(
        self,
        client: viser.ClientHandle,
        folder: viser.GuiFolderHandle,
        read: Callable[[], BlockSources | None] | None,
        notify: Callable[[str, str], None],
    ) -> None:
        self.client = client
        self.folder = folder
        self._read = read
        self._notify = notify
        self._placed: tuple[tuple[str, str], ...] | None = None
        self.buttons: list[viser.GuiButtonHandle] = []
        self._modal: Any = None  # the window open, if any

    def place(self, blocks: Sequence[tuple[str, str]]) -> None:
        """A button per ``(key, label)`` of ``blocks``, in order; unchanged ones stay."""
        wanted = tuple(blocks) if self._read is not None else ()
        if wanted == self._placed:
            return
        self._placed = wanted
        for button in self.buttons:
            button.remove()
        self.buttons = []
        with self.folder:
            for key, label in wanted:
                button = self.client.gui.add_button(
                    f"{label} source", hint=f"the S7-SCL source of {label}, read-only"
                )
                button.on_click(self._opener(key, label))
                self.buttons.append(button)

    def _opener(self, key: str, label: str) -> Callable[[Any], None]:
        def click(_: Any) -> None:
            self.open(key, label)

        return click

    def read(self) -> BlockSources | None:
        """The CPU's sources now (None: no reader, no answer or a bus error)."""
        try:
            return self._read() if self._read is not None else None
        except Exception:  # a bus error: the caller goes on without them
            return None

    def open(self, key: str, label: str) -> None:
        """Read the CPU's sources and open ``key``'s in a window, or say why not."""
        try:
            sources = self._read() if self._read is not None else None
        except Exception as exc:  # a bus error: said, never raised into viser
            self._notify(f"{label} source", f"cannot read it: {exc}")
            return
        if sources is None:
            self._notify(f"{label} source", "the CPU does not answer")
            return
        block = find_block(sources, key)
        if block is None:
            cut = key in sources.left_out
            why = "too large to send" if cut else "the CPU has no S7-SCL source of it"
            self._notify(f"{label} source", why)
            return
        gui = self.client.gui
        if self._modal is not None:
            self._modal.close()
        with gui.add_modal(f"{label} source") as modal:
            self._modal = modal
            gui.add_html(source_html(block))
            gui.add_button("Close").on_click(lambda _: modal.close())


class BlockLinks(BlockButtons):
    """The buttons of one page's Details folder (``folder``) for the shown step's calls in
    ``layout``; the rest as :class:`BlockButtons`."""

    def __init__(
        self,
        client: viser.ClientHandle,
        folder: viser.GuiFolderHandle,
        layout: ChartLayout,
        read: Callable[[], BlockSources | None] | None,
        notify: Callable[[str, str], None],
    ) -> None:
        super().__init__(client, folder, read, notify)
        self.layout = layout

    def show(self, step: int) -> None:
        """Buttons for the blocks step ``step`` calls (0: none); unchanged ones stay."""
        self.place(called_blocks(self.layout, step) if step > 0 else [])
