"""The garbage collector of an edge's own process (``web.collector``): what exists at the
start is frozen, the young generations are collected less often — and still collected."""

from __future__ import annotations

import json
import subprocess
import sys

SCRIPT = """
import gc, json, weakref
from s7graph.web.collector import GC_THRESHOLDS, quiet_collector

class Node:
    pass

quiet_collector()
frozen = gc.get_freeze_count()
a, b = Node(), Node()
a.other, b.other = b, a  # a cycle: only the collector frees it
gone = weakref.ref(a)
del a, b
kept = [[i] for i in range(3 * GC_THRESHOLDS[0])]  # the young generation fills
print(json.dumps([frozen, list(gc.get_threshold()), list(GC_THRESHOLDS), gone() is None]))
"""


def test_an_edges_process_freezes_its_start_and_still_collects_young_cycles() -> None:
    out = subprocess.run(
        [sys.executable, "-c", SCRIPT], capture_output=True, text=True, timeout=60, check=True
    )
    frozen, thresholds, wanted, collected = json.loads(out.stdout)
    assert frozen > 1000  # the interpreter's and s7graph's start, out of every collection
    assert thresholds == wanted and wanted[0] > 700  # young collections rarer than CPython's
    assert collected  # a cycle made afterwards is still freed by a young collection
