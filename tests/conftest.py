"""Shared fixtures. Tests drive scans with the virtual clock; no sleeps in core tests."""

from __future__ import annotations

from pathlib import Path

import pytest

from s7graph.engine.clock import VirtualClock

ROOT = Path(__file__).resolve().parent.parent
SHARED = ROOT.parent / "shared"


@pytest.fixture
def clock() -> VirtualClock:
    return VirtualClock()
