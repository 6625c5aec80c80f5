"""The pages' watch table: STEP 7's *Monitor/Modify Variables*, TIA Portal's watch table
(docs/view.md, "The watch table"), on a chart's page and a program's page alike.

A *Watch* folder: the operands typed into *Operands*, comma-separated — an address
(``MW0:INT``, ``Q4.0``, ``DB20.DBW2``, ``T5``), a symbol (``"Start"``) or a DB variable by
name (``DB20.avg``, ``DB10.ctu.CV``, ``DB20.speeds[2]``), each optionally with the type to
show it as — as ``s7graph watch --address`` takes them (``web.bus.watch.split_operands``), at
most ``MAX_WATCH``. While a page has operands, the CPU reads them all at one of its scan
boundaries every ``POLL_S`` (the bus's ``watch``: the values of one scan, never torn) and
the table shows each value as S7 writes it (``TRUE``, ``W#16#00FF``, ``-5``,
``S5T#1S200MS``) with its type, or why it cannot be read. Reading is a viewer's right:
every page watches. A page whose role may ``modify`` gets *Modify operand* (the watched
operands that name an address or a symbol), *Modify value* and *Modify now* — TIA Portal's
"modify once and now": one ``modify`` command (``engine/modify.py``).

:func:`refresh` asks once per distinct list of operands for all the pages given; it waits
for the CPU's answer, so the views call it from a thread of its own, never from the
thread that paints the chart.
"""

from __future__ import annotations

import html
import threading
from collections.abc import Callable, Iterable, Sequence
from typing import Final, Protocol

import viser

from s7graph.web.bus.protocol import MAX_WATCH, WatchValues
from s7graph.web.bus.watch import parse_item, split_operands
from s7graph.web.commands import MAX_FORCE_TEXT
from s7graph.web.view import texts

__all__ = [
    "POLL_S",
    "TIMEOUT_S",
    "Modifying",
    "Watch",
    "WatchTable",
    "Watched",
    "refresh",
    "set_choices",
    "watch_html",
    "watch_target",
]

POLL_S: Final = 0.5
"""How often the values of a page's operands are read."""
TIMEOUT_S: Final = 2.0
"""How long one request waits for the CPU's next scan boundary (then the table says so)."""

NO_OPERAND: Final = "(no operand watched)"  # Modify's choice while none can be modified
Watch = Callable[[Sequence[str]], WatchValues]
"""Reads operands at the CPU's next scan boundary (``BusClient.watch``)."""


def watch_html(answer: WatchValues | None) -> str:
    """The watch table: each operand, its value as S7 writes it (or why not), its type."""
    if answer is None:
        return texts.small('<span style="color:#777">type operands above: MW0:INT, Q4.0</span>')
    if answer.error:
        return texts.small(f'<span style="color:#c00">{html.escape(answer.error)}</span>')
    rows = []
    for v in answer.values:
        kind = f"<span style='color:#777'>{html.escape(v.type)}</span>"
        shown = (
            f'<span style="color:#c00">{html.escape(v.error)}</span>'
            if v.error
            else f"<b>{html.escape(v.text)}</b> {kind}"
        )
        rows.append(f"<tr><td><code>{html.escape(v.address)}</code></td><td>{shown}</td></tr>")
    head = f"cycle {answer.cycle} · {html.escape(answer.state)}"
    return texts.small(f"{head}<table>{''.join(rows)}</table>")


class WatchTable:
    """The *Watch* folder of one page (``gui``: the page's); with :meth:`enable_modify`,
    *Modify* of one of its operands."""

    def __init__(self, gui: viser.GuiApi, *, expand: bool = True) -> None:
        self._gui = gui
        with gui.add_folder("Watch", expand_by_default=expand) as self.folder:
            self.operands = gui.add_text(
                "Operands",
                "",
                hint="comma-separated: MW0:INT, Q4.0, T5, DB20.DBW2, a symbol, DB20.avg, "
                "DB10.ctu.CV, DB20.speeds[2]",
            )
            self.html = gui.add_html(watch_html(None))
        self._shown = watch_html(None)
        self._modify: Modifying | None = None
        self._lock = threading.Lock()

    def asked(self) -> tuple[str, ...]:
        """The operands this page watches (at most ``MAX_WATCH``); *Modify* offers them."""
        asked = tuple(split_operands(str(self.operands.value))[:MAX_WATCH])
        with self._lock:
            if self._modify is not None:
                self._modify.offer(asked)
        return asked

    def enable_modify(self, send: Callable[[str, str], object] | None) -> None:
        """*Modify* for a page whose role may modify (``send(operand, value)`` sends one
        ``modify`` command); ``None`` takes it away."""
        with self._lock:
            if send is not None and self._modify is None:
                with self.folder:
                    self._modify = Modifying(self._gui, send)
                self._modify.offer(tuple(split_operands(str(self.operands.value))[:MAX_WATCH]))
            elif send is None and self._modify is not None:
                self._modify.remove()
                self._modify = None

    def show(self, answer: WatchValues | None) -> None:
        """Show ``answer`` (None: nothing asked); sent only when it changed."""
        shown = watch_html(answer)
        if shown != self._shown:
            self._shown = shown
            self.html.content = shown


class Watched(Protocol):
    """What :func:`refresh` needs of a table: what it asks, where the answer goes."""

    def asked(self) -> tuple[str, ...]: ...

    def show(self, answer: WatchValues | None) -> None: ...


class Modifying:
    """*Modify* in a watch table: which operand, the value, the button (an engineer's)."""

    def __init__(self, gui: viser.GuiApi, send: Callable[[str, str], object]) -> None:
        self._send = send
        self._options: tuple[str, ...] = (NO_OPERAND,)
        self.choice = gui.add_dropdown(
            "Modify operand", self._options, hint="one of the operands watched"
        )
        self.value = gui.add_text(
            "Modify value", "", hint="TRUE/FALSE, a number or an S7 literal (16#00FF, T#5S)"
        )
        self.button = gui.add_button(
            "Modify now",
            disabled=True,
            hint="write the value once (STEP 7's Modify); the program may write it again",
        )
        self.button.on_click(lambda _: self._clicked())

    def offer(self, asked: tuple[str, ...]) -> None:
        """The operands to choose from: those watched (an address, a symbol, a DB
        variable by name)."""
        options = tuple(a for a in (watch_target(a) for a in asked) if a) or (NO_OPERAND,)
        if options == self._options:
            return
        self._options = options
        set_choices(self.choice, options)
        self.button.disabled = options == (NO_OPERAND,)

    def _clicked(self) -> None:
        operand, value = str(self.choice.value), str(self.value.value).strip()
        if operand in self._options and operand != NO_OPERAND and value:
            self._send(operand, value)

    def remove(self) -> None:
        for handle in (self.choice, self.value, self.button):
            handle.remove()


def set_choices(choice: viser.GuiDropdownHandle[str], options: tuple[str, ...]) -> None:
    """Give ``choice`` its ``options``, keeping what is chosen while it is still offered."""
    if str(choice.value) not in options:
        choice.value = options[0]  # type: ignore[misc]
    choice.options = options


def watch_target(text: str) -> str:
    """The operand a watched ``text`` names without the type to show it as (``MW0:INT`` →
    ``MW0``; a DB variable by name as it is, ``"Data".temps[2]``); "" for a spelling that
    is no operand or one too long for a command."""
    item = parse_item(text)
    if item.error or len(item.target) > MAX_FORCE_TEXT:
        return ""
    return item.target


def refresh(tables: Iterable[Watched], watch: Watch) -> None:
    """Read the operands of ``tables`` (one request per distinct list) and show them; a
    table without operands shows how to type them."""
    answers: dict[tuple[str, ...], WatchValues] = {}
    for table in tables:
        asked = table.asked()
        if not asked:
            table.show(None)
            continue
        if asked not in answers:
            answers[asked] = watch(list(asked))
        table.show(answers[asked])
