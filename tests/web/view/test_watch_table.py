"""The pages' watch table (web/view/watch_table.py): one request per distinct list of
operands for all the pages, at most ``MAX_WATCH`` operands, each value as S7 writes it or
why it cannot be read, escaped; a page without operands is not asked for."""

from __future__ import annotations

from collections.abc import Sequence

from s7graph.web.bus.protocol import MAX_WATCH, WatchValue, WatchValues
from s7graph.web.bus.watch import split_operands
from s7graph.web.view.watch_table import refresh, watch_html, watch_target


class Table:
    """A watch table's two ends without a page: what is typed, what is shown."""

    def __init__(self, typed: str) -> None:
        self.typed = typed
        self.shown: list[WatchValues | None] = []

    def asked(self) -> tuple[str, ...]:
        return tuple(split_operands(self.typed)[:MAX_WATCH])

    def show(self, answer: WatchValues | None) -> None:
        self.shown.append(answer)


def test_one_request_per_distinct_list_and_none_for_a_page_without_operands() -> None:
    asked: list[list[str]] = []

    def watch(operands: Sequence[str]) -> WatchValues:
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
