"""The pages' watch table (web/view/watch_table.py): one request per distinct list of
operands and login for all the pages, at most ``MAX_WATCH`` operands, each value as S7
writes it or why it cannot be read, escaped; a page without operands is not asked for; a
refusal in words, *busy* over the values read last, a login the CPU refuses dropped once
for unsigned requests."""

from __future__ import annotations

from collections.abc import Iterator, Sequence

import pytest
import viser

from s7graph.web.access.login import NOT_SIGNED
from s7graph.web.bus.protocol import MAX_WATCH, WatchValue, WatchValues
from s7graph.web.bus.watch import split_operands
from s7graph.web.view.chart_view import make_server
from s7graph.web.view.watch_table import WatchTable, refresh, said, watch_html, watch_target

UNSIGNED_BUSY = (
    "busy: 32 watch requests not signed by a login are waiting; ask again, or log in: a "
    "watch signed by a login has places of its own"
)
EXPIRED = "watch refused: token expired: log in again"


class Table:
    """A watch table's two ends without a page: what is typed, as whom, what is shown."""

    def __init__(self, typed: str, token: str = "") -> None:
        self.typed, self.login = typed, token
        self.shown: list[WatchValues | None] = []
        self.dropped: list[tuple[str, str]] = []

    def asked(self) -> tuple[str, ...]:
        return tuple(split_operands(self.typed)[:MAX_WATCH])

    def token(self) -> str:
        return "" if any(t == self.login for t, _ in self.dropped) else self.login

    def drop(self, token: str, why: str) -> None:
        self.dropped.append((token, why))

    def show(self, answer: WatchValues | None) -> None:
        self.shown.append(answer)


def test_one_request_per_distinct_list_and_none_for_a_page_without_operands() -> None:
    asked: list[list[str]] = []

    def watch(operands: Sequence[str], token: str) -> WatchValues:
        asked.append(list(operands))
        return WatchValues(cycle=len(asked))

    tables = [Table("MW0, Q4.0"), Table(""), Table("MW0,Q4.0"), Table('"Start"')]
    refresh(tables, watch)
    assert asked == [["MW0", "Q4.0"], ['"Start"']]
    assert [t.shown for t in tables] == [
        [WatchValues(cycle=1)],
        [None],
        [WatchValues(cycle=1)],
        [WatchValues(cycle=2)],
    ]


def test_the_table_shows_each_value_or_why_not_escaped() -> None:
    values = WatchValues(
        cycle=7,
        values=[
            WatchValue(address='"Start"', value=True, text="TRUE", type="BOOL"),
            WatchValue(address="MW99999", error="<no> such address"),
        ],
    )
    shown = watch_html(values)
    assert "cycle 7 · RUN" in shown
    assert "<code>&quot;Start&quot;</code>" in shown and "<b>TRUE</b>" in shown
    assert "&lt;no&gt; such address" in shown and "<no>" not in shown
    refused = watch_html(WatchValues(error="no answer from CPU 'cpu1' within 2 s"))
    assert "no answer from CPU &#x27;cpu1&#x27; within 2 s" in refused
    assert "type operands above" in watch_html(None)


def test_modify_offers_the_watched_operands_without_their_display_type() -> None:
    shown = [watch_target(t) for t in ("MW0:INT", '"Start"', "DB20.DBW2", "DB10.count")]
    assert shown == ["MW0", '"Start"', "DB20.DBW2", "DB10.count"]
    assert watch_target('"Data".temps[2]') == '"Data".temps[2]'
    assert watch_target(":INT") == "" and watch_target("DB1." + "x" * 64) == ""


def test_each_login_signs_its_own_request_and_a_page_not_logged_in_asks_unsigned() -> None:
    asked: list[tuple[list[str], str]] = []

    def watch(operands: Sequence[str], token: str) -> WatchValues:
        asked.append((list(operands), token))
        return WatchValues(cycle=len(asked))

    tables = [Table("MW0", "t-olga"), Table("MW0"), Table("MW0", "t-ivan"), Table("MW0")]
    refresh(tables, watch)
    assert asked == [(["MW0"], "t-olga"), (["MW0"], ""), (["MW0"], "t-ivan")]
    assert [t.shown for t in tables] == [
        [WatchValues(cycle=1)],
        [WatchValues(cycle=2)],
        [WatchValues(cycle=3)],
        [WatchValues(cycle=2)],
    ]


def test_a_login_the_cpu_refuses_is_dropped_once_and_asked_again_unsigned_at_once() -> None:
    asked: list[str] = []

    def watch(operands: Sequence[str], token: str) -> WatchValues:
        asked.append(token)
        return WatchValues(error=EXPIRED) if token else WatchValues(cycle=len(asked))

    olga = Table("MW0", "t-olga")
    refresh([olga], watch)
    assert asked == ["t-olga", ""] and olga.dropped == [("t-olga", EXPIRED)]
    assert olga.shown == [WatchValues(cycle=2)]  # the values, not the refusal
    refresh([olga], watch)
    assert asked == ["t-olga", "", ""] and len(olga.dropped) == 1  # once


def test_a_fault_of_the_cpu_or_no_answer_keeps_the_login() -> None:
    faults = [
        "watch refused: internal error in the CPU while reading a watch request: boom",
        "no answer from CPU 'cpu1' within 2 s",
        UNSIGNED_BUSY,
    ]
    for fault in faults:
        olga = Table("MW0", "t-olga")
        refresh([olga], lambda operands, token, fault=fault: WatchValues(error=fault))
        assert olga.dropped == [] and olga.shown == [WatchValues(error=fault)]


def test_a_refusal_is_said_in_words_with_what_happens_next() -> None:
    busy = said(UNSIGNED_BUSY)
    assert busy.startswith("The CPU is busy (32 watch requests not signed by a login are ")
    assert "asked again in 0.5 s" in busy and "Log in:" in busy and "busy:" not in busy
    mine = said("busy: 8 watch requests of olga are waiting; ask again once they are answered")
    assert mine == "The CPU is busy (8 watch requests of olga are waiting): asked again in 0.5 s."
    ours = said("busy: 8 watch requests from here are waiting; ask again once they are answered")
    assert ours.startswith("The CPU is busy (8 watch requests from this view are waiting)")
    assert said(EXPIRED).startswith("the login expired (the CPU said: token expired")
    gone = said("watch refused: invalid token: log in again")
    assert gone.startswith("the CPU no longer knows this login (logged out")
    assert said(f"watch refused: {NOT_SIGNED}").startswith("the CPU did not take the login's")
    assert said("no answer from CPU 'cpu1' within 2 s") == "no answer from CPU 'cpu1' within 2 s"


@pytest.fixture
def gui() -> Iterator[viser.GuiApi]:
    server, _ = make_server(port=0)
    try:
        yield server.gui
    finally:
        server.stop()


def test_busy_is_said_over_the_values_read_last_for_the_same_operands(
    gui: viser.GuiApi,
) -> None:
    table = WatchTable(gui)
    table.operands.value = "MW0:INT"
    read = WatchValues(cycle=7, values=[WatchValue(address="MW0", text="12", type="INT")])
    refresh([table], lambda operands, token: read)
    refresh([table], lambda operands, token: WatchValues(error=UNSIGNED_BUSY))
    shown = str(table.html.content)
    assert "The CPU is busy" in shown and "cycle 7" in shown and "<b>12</b>" in shown
    table.operands.value = "Q4.0"  # other operands: no values of theirs read yet
    refresh([table], lambda operands, token: WatchValues(error=UNSIGNED_BUSY))
    assert "The CPU is busy" in str(table.html.content)
    assert "<b>12</b>" not in str(table.html.content)


def test_a_dropped_login_is_said_until_the_page_logs_out_or_in_again(gui: viser.GuiApi) -> None:
    page_token = ["t-olga"]
    asked: list[str] = []

    def watch(operands: Sequence[str], token: str) -> WatchValues:
        asked.append(token)
        if token == "t-olga":
            return WatchValues(error=EXPIRED)
        return WatchValues(cycle=len(asked))

    table = WatchTable(gui, login=lambda: page_token[0])
    table.operands.value = "MW0"
    refresh([table], watch)
    refresh([table], watch)
    assert asked == ["t-olga", "", ""]
    shown = str(table.html.content)
    assert "Watching without a login from now on: the login expired" in shown
    assert "Log out and in again" in shown and "cycle 3" in shown
    page_token[0] = "t-olga-2"  # logged in again: signed again, nothing said
    refresh([table], watch)
    assert asked[-1] == "t-olga-2" and "Watching without" not in str(table.html.content)
    page_token[0] = "t-olga"  # the old login again (never, in a page): dropped anew
    refresh([table], watch)
    assert asked[-2:] == ["t-olga", ""] and "Watching without" in str(table.html.content)
    page_token[0] = ""  # logged out: unsigned, nothing said
    refresh([table], watch)
    assert asked[-1] == "" and "Watching without" not in str(table.html.content)
