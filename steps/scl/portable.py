"""A compiled S7-SCL source carried from one process to another (docs/scl.md, "Online
change"): compiled where compiling may hold the interpreter up, loaded where the blocks run.

``compile_portable`` compiles a source as ``compile_scl`` does and also gives it as bytes:
the checked tree, the declarations and the generated module without its code (pickled), the
module's code object (marshalled). ``load_portable`` makes the same ``SclProgram`` of those
bytes without parsing or compiling anything: it runs the module once and builds the engine
blocks. A block the source calls but does not write (a system block, a block of an earlier
source) travels by its label only and is resolved, on loading, among the ``blocks`` given —
the receiving process's own, never a copy.
"""

from __future__ import annotations

import dataclasses
import io
import marshal
import pickle
from collections.abc import Iterable, Mapping
from typing import Any, cast

from s7graph.engine.blocks import FB, FC
from s7graph.engine.symbols import SymbolTable
from s7graph.steps.scl.blocks import SclProgram, build_program
from s7graph.steps.scl.compile import translate
from s7graph.steps.scl.diagnostics import SclError

__all__ = ["compile_portable", "load_portable"]


class _Pickler(pickle.Pickler):
    def persistent_id(self, obj: Any) -> object:
        if isinstance(obj, FB | FC):
            return ("block", obj.label)
        return None


class _Unpickler(pickle.Unpickler):
    def __init__(self, data: bytes, blocks: Mapping[str, FB | FC]) -> None:
        super().__init__(io.BytesIO(data))
        self.blocks = blocks

    def persistent_load(self, pid: Any) -> object:
        kind, label = pid
        found = self.blocks.get(label) if kind == "block" else None
        if found is None:
            raise pickle.UnpicklingError(f"the source calls {label}, which is not loaded")
        return found


def compile_portable(
    text: str,
    file: str,
    *,
    blocks: Iterable[FB | FC] = (),
    symbols: SymbolTable | None = None,
) -> tuple[SclProgram, tuple[bytes, bytes]]:
    """``compile_scl(text, file, blocks=…, symbols=…)`` and the program as (tree, code)
    bytes for :func:`load_portable`; :class:`SclError` lists every problem."""
    source, prog, generated, diags = translate(text, file, blocks=list(blocks), symbols=symbols)
    if generated is None:
        raise SclError(diags)
    program = build_program(source, prog, generated, diags)
    buf = io.BytesIO()
    bare = dataclasses.replace(generated, code=cast(Any, None))  # marshalled apart
    _Pickler(buf, protocol=pickle.HIGHEST_PROTOCOL).dump((source, prog, bare, diags))
    return program, (buf.getvalue(), marshal.dumps(generated.code))


def load_portable(data: tuple[bytes, bytes], blocks: Iterable[FB | FC]) -> SclProgram:
    """The program :func:`compile_portable` gave as ``data``, its calls of blocks it does
    not write resolved among ``blocks``."""
    tree, code = data
    known = {b.label: b for b in blocks}
    source, prog, bare, diags = _Unpickler(tree, known).load()
    generated = dataclasses.replace(bare, code=marshal.loads(code))
    return build_program(source, prog, generated, diags)
