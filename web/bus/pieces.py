"""An object pickled as many small pickles, so that loading it never holds the
interpreter's lock for long (``web.bus.compiler``: a compiled chart coming back from the
compiler's process).

Unpickling one pickle is one C call that holds the lock throughout; a 1 MB chart's model
is some 10 MB of pickle and 0.3 s of such work. :func:`dumps_in_pieces` pickles every
object of the given types on its own (the steps and transitions of a chart: a few kB to
some 100 kB each) and the rest last, referring to them by index; :func:`loads_in_pieces`
loads them one by one, so the interpreter may switch threads between two of them.
"""

from __future__ import annotations

import io
import pickle
from collections.abc import Callable
from typing import Any, Final

from s7graph.sequencer.text.model import Step, Transition

__all__ = ["PIECES", "dumps_in_pieces", "loads_in_pieces"]

PIECES: Final = (Step, Transition)
"""The objects pickled apart (:func:`dumps_in_pieces`): each a few kB to some 100 kB."""


def dumps_in_pieces(obj: object, kinds: tuple[type, ...] = PIECES) -> list[bytes]:
    """``obj`` pickled as many small pickles: every object of a type in ``kinds`` on its
    own (referred to by its index), ``obj`` itself last. Unpickling one piece is one C call
    that holds the interpreter's lock; small pieces keep each such call short."""
    pieces: list[bytes] = []
    index: dict[int, int] = {}

    class _Pickler(pickle.Pickler):
        def __init__(self, file: io.BytesIO, root: object) -> None:
            super().__init__(file, protocol=pickle.HIGHEST_PROTOCOL)
            self.root = root

        def persistent_id(self, o: object) -> int | None:
            if o is self.root or type(o) not in kinds:
                return None
            k = index.get(id(o))
            if k is None:
                k = index[id(o)] = _dump(o)
            return k

    def _dump(o: object) -> int:
        buf = io.BytesIO()
        _Pickler(buf, o).dump(o)
        pieces.append(buf.getvalue())
        return len(pieces) - 1

    _dump(obj)
    return pieces


def loads_in_pieces(pieces: list[bytes], after_each: Callable[[], object] | None = None) -> Any:
    """What :func:`dumps_in_pieces` pickled (each piece refers to earlier ones only);
    ``after_each`` is called after each piece."""
    done: list[object] = []

    class _Unpickler(pickle.Unpickler):
        def persistent_load(self, pid: object) -> object:
            return done[int(pid)]  # type: ignore[call-overload]

    for piece in pieces:
        done.append(_Unpickler(io.BytesIO(piece)).load())
        if after_each is not None:
            after_each()
    return done[-1]
