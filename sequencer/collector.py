"""The garbage collector paused while a chart is built (``parse_chart``, ``compile_chart``).

Building a chart creates container objects by the hundred thousand (syntax tree, model,
generated source, code objects) and drops almost none: each pass of the cyclic collector
walks them all for nothing, and its full passes come at intervals that grow with the heap,
so a 25,000-step chart paid per step more than a 2,500-step one (``bench/compile.py``).
Reference counting still frees whatever is dropped; the collector is back as it was when
the chart is built, and then finds the few cycles left, if any.
"""

from __future__ import annotations

import gc
from collections.abc import Iterator
from contextlib import contextmanager


@contextmanager
def collector_paused() -> Iterator[None]:
    """The cyclic garbage collector off for the ``with`` block, if it was on (a block inside
    another, or one run while the caller keeps it off, changes nothing)."""
    if not gc.isenabled():
        yield
        return
    gc.disable()
    try:
        yield
    finally:
        gc.enable()
