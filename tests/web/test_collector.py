"""The garbage collector of an edge's own process (``web.collector``): what exists at the
start is frozen; the OPC UA face's young generations are collected less often — and still
collected; the view keeps CPython's schedule."""

from __future__ import annotations

import json
import subprocess
import sys

SCRIPT = """
import gc, json, sys, weakref
from s7graph.web import collector

class Node:
    pass

default = gc.get_threshold()
getattr(collector, sys.argv[1])()
frozen = gc.get_freeze_count()
a, b = Node(), Node()
a.other, b.other = b, a  # a cycle: only the collector frees it
gone = weakref.ref(a)
del a, b
kept = [[i] for i in range(3 * max(gc.get_threshold()[0], 700))]  # the young generation fills
print(json.dumps([frozen, list(default), list(gc.get_threshold()), gone() is None]))
"""


def run(function: str) -> tuple[int, list[int], list[int], bool]:
    out = subprocess.run(
        [sys.executable, "-c", SCRIPT, function],
        capture_output=True,
        text=True,
        timeout=60,
        check=True,
    )
    frozen, default, thresholds, collected = json.loads(out.stdout)
    return frozen, default, thresholds, collected


def test_the_views_process_freezes_its_start_and_keeps_cpythons_schedule() -> None:
    frozen, default, thresholds, collected = run("freeze_start")
    assert frozen > 1000  # the interpreter's and s7graph's start, out of every collection
    assert thresholds == default  # a page closed, a chart replaced: their cycles still go
    assert collected


def test_the_opc_ua_face_also_collects_its_young_generations_less_often() -> None:
    from s7graph.web.collector import GC_THRESHOLDS

    frozen, default, thresholds, collected = run("quiet_collector")
    assert frozen > 1000
    assert thresholds == list(GC_THRESHOLDS) and thresholds[0] > default[0]
    assert collected  # a cycle made afterwards is still freed by a young collection
