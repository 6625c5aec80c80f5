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

A logged-in page signs its requests with its login (``BusClient.watch(..., token=...)``), so
the CPU keeps them in its user's own share of the watch queue and a flood of unsigned
requests never makes the page's table busy; a page not logged in asks unsigned. A refusal
is said in words (:func:`said`): *busy* keeps the last values read under it; a login the
CPU no longer takes for the watch (expired, logged out, not signed by its session) makes
the table ask unsigned from then on, once, saying so, until the page logs in again.

:func:`refresh` asks once per distinct list of operands and login for all the pages given;
it waits for the CPU's answer, so the views call it from a thread of its own, never from
the thread that paints the chart.
"""

from __future__ import annotations

import html
import threading
from collections.abc import Callable, Iterable, Sequence
from typing import Final, Protocol

import viser

from s7graph.web.bus.protocol import MAX_WATCH, WatchValues
from s7graph.web.bus.watch import REFUSED, parse_item, split_operands
from s7graph.web.bus.watch import login_refused as refused_for_login
from s7graph.web.commands import MAX_FORCE_TEXT
from s7graph.web.view import texts

__all__ = [
    "POLL_S",
    "TIMEOUT_S",
    "Modifying",
    "Watch",
    "WatchTable",
    "Watched",
    "login_refused",
    "refresh",
    "said",
    "set_choices",
    "watch_html",
    "watch_target",
]

POLL_S: Final = 0.5
"""How often the values of a page's operands are read."""
TIMEOUT_S: Final = 2.0
"""How long one request waits for the CPU's next scan boundary (then the table says so)."""

NO_OPERAND: Final = "(no operand watched)"  # Modify's choice while none can be modified
Watch = Callable[[Sequence[str], str], WatchValues]
"""Reads operands at the CPU's next scan boundary (``BusClient.watch``), the request signed
by the login of the token given ("": unsigned)."""

_BUSY: Final = "busy: "  # how it refuses one it has no place for now
_LOGIN_WORDS: Final = (  # the CPU's reason for refusing a login's watch -> the page's words
    ("token expired", "the login expired"),
    ("invalid token", "the CPU no longer knows this login (logged out, or the CPU restarted)"),
    ("not signed by the session", "the CPU did not take the login's signature"),
    ("replayed or out of order", "the CPU took a request of this login for a replay"),
    ("the token belongs to another user", "the login is another user's"),
    ("not logged in", "the CPU saw no login"),
)


def login_refused(answer: WatchValues) -> bool:
    """Whether the CPU refused a signed request for its login, not for a fault of its own
    (``web.bus.watch.login_refused``)."""
    return refused_for_login(answer.error)


def said(error: str) -> str:
    """The CPU's refusal of a request as the page says it: *busy* and a refused login in
    words a user acts on (what happens next, what to do), any other as the CPU said it."""
    if error.startswith(_BUSY):
        waiting = error.removeprefix(_BUSY).split(";", 1)[0]
        waiting = waiting.replace("from here", "from this view")  # the view's link, to the CPU
        advice = (
            " Log in: the watch of a logged-in page has places of its own."
            if "or log in" in error
            else ""
        )
        return f"The CPU is busy ({waiting}): asked again in {POLL_S:g} s.{advice}"
    if error.startswith(REFUSED):
        reason = error.removeprefix(REFUSED)
        for start, words in _LOGIN_WORDS:
            if reason.startswith(start):
                return f"{words} (the CPU said: {reason})"
        return reason
    return error


def watch_html(
    answer: WatchValues | None, *, note: str = "", earlier: WatchValues | None = None
) -> str:
    """The watch table: each operand, its value as S7 writes it (or why not), its type;
    ``note`` above it (why the page watches without its login); under a refusal that is
    only for now (*busy*) the values read ``earlier``."""
    top = f'<span style="color:#b60">{html.escape(note)}</span><br>' if note else ""
    if answer is None:
        hint = '<span style="color:#777">type operands above: MW0:INT, Q4.0</span>'
        return texts.small(top + hint)
    if answer.error:
        refused = f'<span style="color:#c00">{html.escape(said(answer.error))}</span>'
        if earlier is None or not answer.error.startswith(_BUSY):
            return texts.small(top + refused)
        return texts.small(top + refused + "<br>" + _rows(earlier))
    return texts.small(top + _rows(answer))


def _rows(answer: WatchValues) -> str:
    """The head (cycle, state) and a row per operand of a readable ``answer``."""
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
    return f"{head}<table>{''.join(rows)}</table>"


class WatchTable:
    """The *Watch* folder of one page (``gui``: the page's); with :meth:`enable_modify`,
    *Modify* of one of its operands. ``login`` gives the token of the page's login ("":
    none), which signs its requests."""

    def __init__(
        self,
        gui: viser.GuiApi,
        *,
        expand: bool = True,
        login: Callable[[], str] | None = None,
    ) -> None:
        self._gui = gui
        self._login = login
        self._dropped = ""  # a token the CPU refused for the watch: unsigned while it is held
        self._note = ""  # what the table says of it
        self._asking: tuple[str, ...] = ()  # the operands asked last
        self._read: tuple[tuple[str, ...], WatchValues] | None = None  # the last values
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
            self._asking = asked
            if self._modify is not None:
                self._modify.offer(asked)
        return asked

    def token(self) -> str:
        """The token that signs this page's requests: its login's ("": not logged in, or a
        login the CPU refused for the watch — until the page logs in again)."""
        token = self._login() if self._login is not None else ""
        with self._lock:
            if token != self._dropped:  # logged out, or in again: the refusal is over
                self._dropped = self._note = ""
            return "" if token == self._dropped else token

    def drop(self, token: str, why: str) -> None:
        """The CPU refused a request signed by ``token`` (``why``: its words): from now on
        the table asks unsigned while the page holds that login, and says so."""
        note = f"Watching without a login from now on: {said(why)}. Log out and in again."
        with self._lock:
            self._dropped, self._note = token, note

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
        """Show ``answer`` (None: nothing asked); sent only when it changed. A *busy*
        answer keeps the values last read for the same operands under it."""
        with self._lock:
            asking, note, read = self._asking, self._note, self._read
            if answer is not None and not answer.error:
                self._read = read = (asking, answer)
        earlier = read[1] if read is not None and read[0] == asking else None
        shown = watch_html(answer, note=note, earlier=earlier)
        if shown != self._shown:
            self._shown = shown
            self.html.content = shown


class Watched(Protocol):
    """What :func:`refresh` needs of a table: what it asks, as whom, where the answer goes,
    what to do when the CPU refuses its login."""

    def asked(self) -> tuple[str, ...]: ...

    def token(self) -> str: ...

    def drop(self, token: str, why: str) -> None: ...

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
    """Read the operands of ``tables`` (one request per distinct list and login) and show
    them; a table without operands shows how to type them. A request signed by a login the
    CPU refuses (:func:`login_refused`) is asked again unsigned at once, and the table
    drops that login for its watch."""
    answers: dict[tuple[tuple[str, ...], str], WatchValues] = {}

    def ask(asked: tuple[str, ...], token: str) -> WatchValues:
        if (asked, token) not in answers:
            answers[asked, token] = watch(list(asked), token)
        return answers[asked, token]

    for table in tables:
        asked = table.asked()
        if not asked:
            table.show(None)
            continue
        token = table.token()
        answer = ask(asked, token)
        if token and login_refused(answer):
            table.drop(token, answer.error)
            answer = ask(asked, "")
        table.show(answer)
