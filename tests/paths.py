"""Where the repository's folders are, for every test, imported as ``tests.paths``: a test
module names ``ROOT``, ``EXAMPLES`` or ``DOCS`` from here instead of counting its own depth
(``Path(__file__).parents[n]``), so that it can move with the package it tests."""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"
DOCS = ROOT / "docs"
