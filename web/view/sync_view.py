"""The page's *Synchronization* folder: where the process stands in the chart, to resume
the sequence there (docs/view.md, "Synchronization"; ``sequencer.sync``).

*Find steps* asks the CPU to judge every step against the process values at its next
scan boundary (the bus's ``fb/<fb>/sync``) and lists the steps where the sequence could go
on — the interlock holds and no leaving transition does — the likeliest first (a
transition into them holds too), each with its sequence, with the active steps marked.
Asking is a viewer's right. A page whose role may ``set_steps`` also gets *Resume at* (the
steps found) and *Set in MAN*: one ``set_steps`` command, which the CPU carries out in MAN
only — the chosen step becomes the active step of its sequence in one call, the steps
active there leave with their final scan, other sequences keep theirs
(``sequencer.placing``); the operator then switches back to AUTO.
"""

from __future__ import annotations

import html
import threading
from collections.abc import Callable, Iterable, Mapping
from typing import Any, Final

import numpy as np
import viser

from s7graph.web.bus.protocol import SyncReport, SyncStepInfo
from s7graph.web.view import texts
from s7graph.web.view.drawing import BOX_H, BOX_W, rect_segments
from s7graph.web.view.watch_table import set_choices

__all__ = ["MARK", "TIMEOUT_S", "Sync", "SyncView", "found", "mark_segments", "sync_html"]

TIMEOUT_S: Final = 5.0
"""How long *Find steps* waits for the CPU's next scan boundary."""
MARK: Final = (255, 140, 0)
"""The colour of the frames around the steps found on the chart."""
MARGIN: Final = 0.12  # how far a frame stands outside its step's box (scene units)
NOTHING: Final = "(find steps first)"  # *Resume at* before a search found a step
Sync = Callable[[], SyncReport]
"""Judges the FB's steps at the CPU's next scan boundary (``BusClient.synchronization``)."""


def found(report: SyncReport) -> list[SyncStepInfo]:
    """The steps where the sequence could go on, the likely ones first, each in chart
    order."""
    return [s for s in report.ordered() if s.fits]


def _verdict(step: SyncStepInfo) -> str:
    text = html.escape(step.verdict)
    if step.likely:
        return f'<b style="color:#080">{text}</b>'
    return f'<span style="color:{"#080" if step.fits else "#777"}">{text}</span>'


def sync_html(report: SyncReport | None) -> str:
    """The steps found (likely first), then the others with why they do not fit."""
    if report is None:
        return texts.small(
            '<span style="color:#777">Find steps judges every step against the process '
            "values now: where the sequence could go on</span>"
        )
    if report.error:
        return texts.small(f'<span style="color:#c00">{html.escape(report.error)}</span>')
    ordered = report.ordered()
    rows = []
    for step in ordered:
        name = html.escape(step.label)
        active = " · <b>active</b>" if step.active else ""
        rows.append(
            f"<tr><td>{name}</td><td>seq {step.sequence}</td><td>{_verdict(step)}{active}</td></tr>"
        )
    head = (
        f"cycle {report.cycle} · {html.escape(report.state)} · {html.escape(report.mode)} · "
        f"{sum(s.fits for s in ordered)} of {len(report.steps)} steps fit"
    )
    return texts.small(f"{head}<table>{''.join(rows)}</table>")


def mark_segments(places: Mapping[int, tuple[float, float]], steps: Iterable[int]) -> Any:
    """Line segments (float32, ``(n, 2, 3)``) of a frame around each of ``steps`` that has
    a place (its box's centre in the scene), just outside the box."""
    w, h = BOX_W + 2 * MARGIN, BOX_H + 2 * MARGIN
    out = []
    for n in steps:
        if n in places:
            out += rect_segments(*places[n], w, h, z=0.05)
    return np.array(out, np.float32).reshape(-1, 2, 3)


class SyncView:
    """The *Synchronization* folder of one page (``gui``: the page's), the steps found
    framed on the chart in ``scene`` (the page's own) at the places ``places`` gives; with
    :meth:`enable_activate`, *Resume at* and *Set in MAN*."""

    def __init__(
        self,
        gui: viser.GuiApi,
        sync: Sync,
        *,
        scene: viser.SceneApi | None = None,
        places: Callable[[], Mapping[int, tuple[float, float]]] = dict,
    ) -> None:
        self._sync = sync
        self._scene, self._places = scene, places
        self._marks: list[Any] = []
        self._lock = threading.Lock()
        self._activate: Callable[[int], object] | None = None
        self._steps: dict[str, int] = {}  # a label in *Resume at* -> its step
        with gui.add_folder("Synchronization", expand_by_default=False) as self.folder:
            self.find = gui.add_button(
                "Find steps",
                hint="where the process stands: the steps whose interlock holds and whose "
                "next transition does not (S7-GRAPH's synchronization)",
            )
            self.clear = gui.add_button(
                "Clear marks",
                disabled=True,
                hint="take the frames of the steps found off the chart",
            )
            self.html = gui.add_html(sync_html(None))
            self.choice = gui.add_dropdown(
                "Resume at", (NOTHING,), hint="one of the steps found", visible=False
            )
            self.button = gui.add_button(
                "Set in MAN",
                disabled=True,
                visible=False,
                hint="the chosen step becomes the active step of its sequence in one call, "
                "the steps active there leave; in MAN only",
            )
        self.find.on_click(lambda _: self.search())
        self.clear.on_click(lambda _: self._mark([]))
        self.button.on_click(lambda _: self._activate_chosen())

    def search(self) -> None:
        """Ask the CPU (waits for its answer: viser's callback thread) and show it."""
        report = self._sync()
        fitting = found(report)
        steps = {s.label: s.number for s in fitting}
        with self._lock:
            self._steps = steps
            set_choices(self.choice, tuple(steps) or (NOTHING,))
            self.button.disabled = self._activate is None or not steps
        self.html.content = sync_html(report)
        self._mark(fitting)

    @property
    def framed(self) -> tuple[str, ...]:
        """The scene nodes of the frames on the chart now (``/sync/likely``, ``/sync/fits``)."""
        return tuple(node.name for node in self._marks)

    def _mark(self, steps: list[SyncStepInfo]) -> None:
        """Frame ``steps`` on the chart — the likely ones thicker — instead of the last."""
        with self._lock:
            self._frame(steps)

    def _frame(self, steps: list[SyncStepInfo]) -> None:
        for node in self._marks:
            node.remove()
        self._marks = []
        self.clear.disabled = not steps
        if self._scene is None or not steps:
            return
        places = self._places()
        for name, group, width in (
            ("likely", [s.number for s in steps if s.likely], 5.0),
            ("fits", [s.number for s in steps if not s.likely], 2.5),
        ):
            segments = mark_segments(places, group)
            if len(segments):
                self._marks.append(
                    self._scene.add_line_segments(
                        f"/sync/{name}",
                        segments,
                        colors=MARK,
                        thickness=width,
                        thickness_units="screen",
                    )
                )

    def enable_activate(self, activate: Callable[[int], object] | None) -> None:
        """*Resume at* and *Set in MAN* for a page whose role may ``set_steps``
        (``activate(step)`` sends it); ``None`` hides them."""
        with self._lock:
            self._activate = activate
            self.choice.visible = self.button.visible = activate is not None
            self.button.disabled = activate is None or not self._steps

    def _activate_chosen(self) -> None:
        with self._lock:
            step, activate = self._steps.get(str(self.choice.value)), self._activate
        if step is not None and activate is not None:
            activate(step)
