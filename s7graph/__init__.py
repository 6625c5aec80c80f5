"""s7graph: S7-GRAPH-style sequential control on a soft PLC block runtime.

The layers, top to bottom (each imports only the ones below it):
``s7graph.web`` (command line, bus, browser view, recorder) → ``s7graph.sequencer`` (the
GRAPH FB) → ``s7graph.steps`` (the action and condition language) and ``s7graph.sfb``
(system blocks) → ``s7graph.engine`` (the soft CPU). See ``docs/architecture.md``.
"""

from __future__ import annotations

__all__ = ["__version__"]


def __getattr__(name: str) -> str:
    """``__version__``, read from the installed package's metadata when first asked for (not
    at every import: reading it costs each process about 20 ms)."""
    if name != "__version__":
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    from importlib.metadata import PackageNotFoundError, version

    try:
        found = version("s7graph")
    except PackageNotFoundError:  # pragma: no cover - running from a source tree
        found = "0+unknown"
    globals()["__version__"] = found
    return found
