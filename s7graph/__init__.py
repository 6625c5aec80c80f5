"""s7graph: S7-GRAPH-style sequential control on a soft PLC block runtime.

The layers, top to bottom (each imports only the ones below it):
``s7graph.web`` (command line, bus, browser view, recorder) → ``s7graph.sequencer`` (the
GRAPH FB) → ``s7graph.steps`` (the action and condition language) and ``s7graph.sfb``
(system blocks) → ``s7graph.engine`` (the soft CPU). See ``docs/architecture.md``.
"""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("s7graph")
except PackageNotFoundError:  # pragma: no cover - running from a source tree
    __version__ = "0+unknown"

__all__ = ["__version__"]
