"""Names of a package loaded when first used (PEP 562), so that a process importing one
module of a package does not pay for the modules beside it."""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping, MutableMapping
from typing import Any

__all__ = ["lazy_names"]


def lazy_names(
    space: MutableMapping[str, Any], package: str, exports: Mapping[str, tuple[str, ...]]
) -> Callable[[str], Any]:
    """The ``__getattr__`` of the package whose globals are ``space``: each name of
    ``exports`` (names by the submodule of ``package`` that defines them, ``package`` by its
    full name, whatever name it was imported by) is imported when first asked for, then
    kept in ``space``; any other name is an ``AttributeError``, as for a module without
    it."""
    home = {name: module for module, names in exports.items() for name in names}

    def __getattr__(name: str) -> Any:
        module = home.get(name)
        if module is None:
            raise AttributeError(f"module {space['__name__']!r} has no attribute {name!r}")
        value = space[name] = getattr(importlib.import_module(f"{package}.{module}"), name)
        return value

    return __getattr__
