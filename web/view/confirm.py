"""A question before an operation that stops the plant or wipes its memory — CPU to STOP,
memory reset (MRES) — as TIA Portal asks before either: one table of the questions, one
modal that asks (docs/view.md, "Diagnostics")."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Final

from s7graph.web.commands import Command, Mres, Stop

__all__ = ["QUESTIONS", "ask", "question"]

QUESTIONS: Final[dict[type[Command], tuple[str, str, str]]] = {
    Stop: (
        "CPU to STOP",
        "The CPU stops: every output goes to 0 and the sequences stand still until the CPU "
        "is started again.",
        "Stop the CPU",
    ),
    Mres: (
        "Memory reset (MRES)",
        "Every memory area, DB and instance DB goes back to its initial values and the "
        "force jobs are deleted; the program and the diagnostic buffer are kept.",
        "Reset the memory",
    ),
}
"""Per op that needs a yes: the question's title, what it does, the button that does it."""


def ask(gui: Any, kind: type[Command], go: Callable[[], object]) -> None:
    """``go`` at once for an op without a question; else the question of ``kind`` in a
    modal of ``gui`` (a viser page's), ``go`` on its yes, nothing on Cancel."""
    found = QUESTIONS.get(kind)
    if found is None:
        go()
        return
    title, what, label = found
    question(gui, title, what, label, go)


def question(
    gui: Any, title: str, what: str, yes: str, go: Callable[[], object], *, no: str = "Cancel"
) -> None:
    """A modal of ``gui`` saying ``what``: its button ``yes`` closes it and does ``go``,
    ``no`` only closes it."""
    with gui.add_modal(title) as modal:
        gui.add_markdown(what)
        agreed = gui.add_button(yes, color="red")
        refused = gui.add_button(no)

    def answer(_: object) -> None:
        modal.close()
        go()

    agreed.on_click(answer)
    refused.on_click(lambda _: modal.close())
