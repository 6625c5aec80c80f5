"""Record a run as a rerun ``.rrd`` timeline (the optional ``[trace]`` extra).

Each :class:`StepStateUpdate` becomes one row on the ``cycle`` sequence timeline and the
``plc_time`` duration axis: a scalar per step (1 active, 0 inactive, logged on change),
a scalar per numeric value (on change), and a text log line per step event and mode
change. Entity paths: ``s7graph/<fb>/step/S<n>``, ``s7graph/<fb>/value/<name>``,
``s7graph/<fb>/events``, ``s7graph/<fb>/chart`` (static).
"""

from __future__ import annotations

import re
from pathlib import Path
from types import ModuleType

from s7graph.web.bus.protocol import ChartLayout, StepStateUpdate

_rr: ModuleType | None
try:  # rerun-sdk is ~670 MB installed, so it is optional
    import rerun as _rr
except ImportError:  # pragma: no cover - depends on the environment
    _rr = None

__all__ = ["Recorder", "RecorderUnavailable", "available"]

ERROR_EVENTS = frozenset({"V1", "L1"})  # supervision / interlock error came
_ENTITY_SAFE = re.compile(r"[^A-Za-z0-9_\-]")


class RecorderUnavailable(RuntimeError):
    """rerun-sdk is not installed."""


def available() -> bool:
    """Whether rerun-sdk can be imported."""
    return _rr is not None


def _rerun() -> ModuleType:
    if _rr is None:
        raise RecorderUnavailable("recording needs rerun-sdk: pip install 's7graph[trace]'")
    return _rr


class Recorder:
    """Turns the updates of one FB into a rerun recording, to a file or to memory."""

    def __init__(
        self,
        layout: ChartLayout,
        path: str | Path | None = None,
        *,
        application_id: str = "s7graph",
    ) -> None:
        rr = _rerun()
        self._rr = rr
        self.layout = layout
        self.path = Path(path) if path is not None else None
        self._rec = rr.RecordingStream(application_id)
        self._memory = None
        if self.path is not None:
            self._rec.save(str(self.path))
        else:
            self._memory = rr.memory_recording(recording=self._rec)
        self._root = f"s7graph/{layout.fb}"
        self._active: dict[int, bool] = {}
        self._values: dict[str, float] = {}
        self._mode: str | None = None
        self._log_chart()

    def _log_chart(self) -> None:
        rr = self._rr
        lines = [f"# {self.layout.fb}", ""]
        for s in self.layout.steps:
            marks = "".join(
                m for m, on in (("*", s.initial), (" C", s.interlock), (" V", s.supervision)) if on
            )
            lines.append(f"- S{s.number} {s.name}{marks}")
        for t in self.layout.transitions:
            dst = ",".join(f"S{n}" for n in t.targets) or "STOP"
            src = ",".join(f"S{n}" for n in t.sources)
            lines.append(f"- T{t.number} {t.name}: {src} -> {dst} := {t.condition or 'TRUE'}")
        doc = rr.TextDocument("\n".join(lines), media_type="text/markdown")
        self._rec.log(f"{self._root}/chart", doc, static=True)
        for s in self.layout.steps:
            style = rr.SeriesLines(colors=[40, 170, 60], names=f"S{s.number} {s.name}".strip())
            self._rec.log(self._step_path(s.number), style, static=True)

    def chart_changed(self, layout: ChartLayout) -> None:
        """The FB runs another chart (an online change): record its steps from now on
        (the chart text and a style for each step again; a step gone ends inactive)."""
        gone = {s.number for s in self.layout.steps} - {s.number for s in layout.steps}
        for number in sorted(gone):
            if self._active.pop(number, False):
                self._rec.log(self._step_path(number), self._rr.Scalars(0.0))
        self.layout = layout
        self._log_chart()

    def _step_path(self, number: int) -> str:
        return f"{self._root}/step/S{number}"

    def record(self, update: StepStateUpdate) -> None:
        """Add one scan to the timeline (only what changed is logged)."""
        rr, rec = self._rr, self._rec
        rec.set_time("cycle", sequence=update.cycle)
        rec.set_time("plc_time", duration=update.t_ms / 1000.0)
        active = set(update.active)
        for s in self.layout.steps:
            now = s.number in active
            if self._active.get(s.number) != now:
                self._active[s.number] = now
                rec.log(self._step_path(s.number), rr.Scalars(1.0 if now else 0.0))
        if update.mode != self._mode:
            if self._mode is not None:
                text = f"mode {self._mode} -> {update.mode}"
                rec.log(f"{self._root}/events", rr.TextLog(text, level="INFO"))
            self._mode = update.mode
        for event, step in update.events:
            level = "ERROR" if event in ERROR_EVENTS else "INFO"
            rec.log(f"{self._root}/events", rr.TextLog(f"{event} S{step}", level=level))
        for name, value in update.values.items():
            if isinstance(value, bool | int | float) and self._values.get(name) != float(value):
                self._values[name] = float(value)
                path = f"{self._root}/value/{_ENTITY_SAFE.sub('_', name)}"
                rec.log(path, rr.Scalars(float(value)))

    def close(self) -> bytes | None:
        """Flush and close; a memory recording returns its ``.rrd`` bytes."""
        data = None
        if self._memory is not None:
            self._rec.flush()
            data = bytes(self._memory.drain_as_bytes())
        self._rec.disconnect()
        return data

    def __enter__(self) -> Recorder:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
