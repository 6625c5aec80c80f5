"""Simulated plants for ``s7graph sim`` / ``s7graph run`` (docs/cli.md, "s7graph sim").

A plant file is a Python module defining ``class Plant`` with
``cycle(self, io, t_ms: int, dt_ms: int) -> None``, called once per CPU cycle after the
outputs were written. ``io.get(name)`` reads an output or input (address, symbol or FB
pin); ``io.set(name, value)`` writes an input on the module side (the CPU reads it into the
process image at its next cycle). An error inside a plant becomes one ``PlantError`` line,
never a traceback.
"""

from __future__ import annotations

import importlib.util
import traceback
from pathlib import Path
from typing import Any, Protocol

from s7graph.engine.errors import S7Error, ScanAborted


class PlantError(S7Error):
    """A plant file that does not load, or raised inside ``cycle``."""


class PlantIO(Protocol):
    def get(self, name: str) -> Any: ...
    def set(self, name: str, value: Any) -> None: ...


def _where(exc: BaseException, path: Path) -> str:
    for frame in reversed(traceback.extract_tb(exc.__traceback__)):
        if Path(frame.filename).resolve() == path.resolve():
            return f"{path}:{frame.lineno}"
    return str(path)


class LoadedPlant:
    """A plant instance with error wrapping."""

    def __init__(self, path: Path, plant: Any) -> None:
        self.path = path
        self.plant = plant

    def cycle(self, io: PlantIO, t_ms: int | float, dt_ms: int | float) -> None:
        """One plant cycle; ``s7graph sim`` passes floats when the cycle time is fractional."""
        try:
            self.plant.cycle(io, t_ms, dt_ms)
        except ScanAborted:
            raise  # the runner's cycle monitoring: the CPU goes to STOP
        except S7Error as exc:
            raise PlantError(f"plant: {exc.message}", _where(exc, self.path)) from None
        except (Exception, SystemExit, KeyboardInterrupt) as exc:  # a plant error, never an exit
            raise PlantError(
                f"plant: {type(exc).__name__}: {exc}", _where(exc, self.path)
            ) from None


def load_plant(path: str | Path) -> LoadedPlant:
    """Import a plant file and instantiate its ``Plant`` class."""
    p = Path(path)
    if not p.is_file():
        raise PlantError(f"plant file {p} does not exist")
    spec = importlib.util.spec_from_file_location(f"s7graph_plant_{p.stem}", p)
    if spec is None or spec.loader is None:  # a suffix Python does not import
        raise PlantError(f"cannot load plant file {p}: a plant is a Python file (.py)")
    module = importlib.util.module_from_spec(spec)
    try:
        spec.loader.exec_module(module)
        cls = getattr(module, "Plant", None)
        if cls is None:
            raise PlantError(f"{p} defines no class Plant")
        plant = cls()
    except PlantError:
        raise
    except (Exception, SystemExit) as exc:  # sys.exit() in the file too: never a silent end
        raise PlantError(f"plant: {type(exc).__name__}: {exc}", _where(exc, p)) from None
    if not callable(getattr(plant, "cycle", None)):
        raise PlantError(f"{p}: Plant has no method cycle(io, t_ms, dt_ms)")
    return LoadedPlant(p, plant)
