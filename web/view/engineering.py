"""What an editor page needs of the CPU besides commands: the running chart's ``.s7g``
source, the files of the CPU's project directory, and a sender for the engineering
commands (``download``, ``undo_download``, ``save``, ``open``), which may take longer than
an operator's (the CPU compiles the chart off its scan thread and writes the file first).
``BusClient`` provides all three (``web.view.edge``'s ``ViewSide``)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol

import viser

from s7graph.web.bus.protocol import (
    ChartLayout,
    ChartSource,
    Command,
    CommandReply,
    ProjectFiles,
    StepStateUpdate,
)

if TYPE_CHECKING:
    from s7graph.web.view.drawing import Picture

__all__ = ["EditorPage", "Engineering", "ViewHost"]


@dataclass(frozen=True, slots=True)
class Engineering:
    source: Callable[[], ChartSource | None]
    project: Callable[[], ProjectFiles | None]
    send: Callable[[Command], CommandReply]


class ViewHost(Protocol):
    """The view a page belongs to: the chart the CPU runs, where it is drawn, and its
    newest state."""

    layout: ChartLayout
    picture: Picture

    def latest(self) -> StepStateUpdate | None: ...


class EditorPage(Protocol):
    """The page panel an editor belongs to (``web.view.panel.ClientPanel``)."""

    client: viser.ClientHandle
    control_folder: viser.GuiFolderHandle

    @property
    def wiring(self) -> Any: ...

    @property
    def fb(self) -> str: ...

    def engineer_command(self, command: Command) -> CommandReply: ...

    def fit(self, aim: Callable[[], tuple[float, float, float] | None]) -> None: ...
