"""A question before an operation that stops the plant or wipes its memory — CPU to STOP,
memory reset (MRES) — as TIA Portal asks before either: one table of the questions, one
modal that asks (docs/view.md, "Diagnostics")."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Final

from s7graph.web.commands import Command, Mres, Stop

__all__ = ["QUESTIONS", "ask"]

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
    question = QUESTIONS.get(kind)
    if question is None:
        go()
        return
    title, what, label = question
    with gui.add_modal(title) as modal:
        gui.add_markdown(what)
        yes = gui.add_button(label, color="red")
        no = gui.add_button("Cancel")

    def answer(_: object) -> None:
        modal.close()
        go()

    yes.on_click(answer)
    no.on_click(lambda _: modal.close())
