"""A download rewrites the instance DB's row with the new chart's fingerprint, even when
none of its data changed (engine/persistence.py ``stage``): a restart with the downloaded
chart file recognises the state as its own and may resume hot, instead of taking it for
another chart's and carrying it over (which blocks a hot restart)."""

from __future__ import annotations

from pathlib import Path

from s7graph.engine.clock import VirtualClock
from s7graph.engine.persistence import StateStore
from s7graph.sequencer.change.carry import fingerprint
from s7graph.sequencer.change.online import swap
from s7graph.web.harness.persist import open_state
from s7graph.web.harness.session import ChartSession, compile_text, load_chart
from tests.web.bus.test_online_change import CHART


def test_a_download_whose_data_did_not_change_still_writes_the_new_charts_row(
    tmp_path: Path,
) -> None:
    path = tmp_path / "fill.s7g"
    path.write_text(CHART, encoding="utf-8")
    session = ChartSession(*load_chart(path), VirtualClock())
    session.start()
    session.set("go", True)
    for _ in range(5):
        session.clock.advance(10)  # type: ignore[attr-defined]
        session.scan()
    store = StateStore(tmp_path / "state.sqlite", hot=True)
    store.save(session.cpu, clean=False)
    assert store.stage(session.cpu) is None  # nothing changed since

    edited = CHART.replace(":= full;", ":= full OR empty;")  # the same steps, the same data
    new_cc, _ = compile_text(edited, str(path))
    swap(session.graph, new_cc, session.cpu)
    batch = store.stage(session.cpu)
    assert batch is not None and 1 in batch.instances
    assert batch.instances[1][2] == fingerprint(new_cc)
    store.write(batch)
    store.close()

    path.write_text(edited, encoding="utf-8")  # the chart file a download writes
    restarted = ChartSession(*load_chart(path), VirtualClock())
    opened = open_state(tmp_path / "state.sqlite", restarted.cpu, hot=True)
    try:
        assert opened.report is not None and opened.report.changed == []
        assert "program download" not in restarted.cpu.hot_blockers
        assert restarted.graph.state.x == session.graph.state.x
    finally:
        opened.store.close()
