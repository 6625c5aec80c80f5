"""The lark parsers of the grammars in the tree (charts, S7-SCL, structured text), each built
once per machine rather than once per process.

Building an LALR parser from a grammar takes lark about a fifth of a second, and every
``s7graph`` process that reads a chart or a block did it again. :func:`lark_parser` keeps
the built parser in the user's cache folder (lark's ``cache`` option, lark's own format:
the file holds the hash of the grammar, the options, lark's and Python's versions, and lark
builds afresh when any differs) and reads it back in milliseconds. The folder is the
user's alone (``$XDG_CACHE_HOME/s7graph`` or ``~/.cache/s7graph``, mode 0700, owned by the
user, not writable by others); without one, or when it cannot be written, the parser is
built as before. The cache changes how long a start takes, never what a parser does.
"""

from __future__ import annotations

import hashlib
import os
import stat
import sys
from pathlib import Path
from typing import Any

from lark import Lark, __version__

__all__ = ["cache_folder", "lark_parser"]

CACHE_ENV = "XDG_CACHE_HOME"
"""Where the user's caches are (the XDG base directory rule); ``~/.cache`` without it."""


def cache_folder() -> Path | None:
    """The user's own cache folder of s7graph, made if missing; None when there is none
    that only the user can write (not the user's, writable by others, or not makeable)."""
    base = os.environ.get(CACHE_ENV) or str(Path.home() / ".cache")
    folder = Path(base) / "s7graph"
    try:
        folder.mkdir(mode=0o700, parents=True, exist_ok=True)
        st = folder.stat()
    except (OSError, RuntimeError):  # RuntimeError: no home folder to expand
        return None
    if st.st_uid != os.getuid() or st.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
        return None
    return folder


def lark_parser(grammar: Path, **options: Any) -> Lark:
    """``Lark(grammar's text, **options)`` (an LALR parser), read from the cache folder when
    it was built before with the same grammar and options, else built and kept there."""
    text = grammar.read_text(encoding="utf-8")
    folder = cache_folder()
    if folder is None:
        return Lark(text, **options)
    hashable = sorted((k, repr(v)) for k, v in options.items() if k != "lexer_callbacks")
    key = repr((text, hashable, __version__, sys.version_info[:2]))
    name = f"{grammar.stem}-{hashlib.sha256(key.encode()).hexdigest()[:24]}.lark"
    cache = folder / name
    if cache.is_file():
        return Lark(text, cache=str(cache), **options)
    # built into a file of this process's own, then moved into place in one step: a process
    # starting meanwhile reads a whole file or none
    own = folder / f"{name}.{os.getpid()}.tmp"
    parser = Lark(text, cache=str(own), **options)
    try:
        os.replace(own, cache)
    except OSError:
        own.unlink(missing_ok=True)
    return parser
