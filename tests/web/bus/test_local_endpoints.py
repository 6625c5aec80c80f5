"""A CPU listening on its own unix socket writes where, so a shell of the same machine and
user reaches it without ``--connect`` (``web.bus.local``, docs/cli.md, "The bus from a
shell"); a folder others may enter is never read, and a CPU that ended takes its file
away."""

from __future__ import annotations

import os
import socket
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from s7graph.web.bus import local
from s7graph.web.bus.cpu_side import CpuSide
from s7graph.web.bus.session import BusEnds
from s7graph.web.cli.net import NetOptions
from s7graph.web.cli.remote import _join


@pytest.fixture
def runtime(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    return tmp_path / "s7graph"


def test_a_cpu_on_its_own_socket_is_found_by_name_and_gone_when_it_ends(runtime: Path) -> None:
    side = CpuSide({}, cpu="line1")
    try:
        assert local.find("line1") == side.endpoint
        assert (runtime / "line1.endpoint").stat().st_mode & 0o777 == 0o600
        session = _join(NetOptions(cpu="line1"))  # no --connect: this machine's line1
        assert not isinstance(session, str), session
        session.close()  # type: ignore[no-untyped-call]
    finally:
        side.close()
    assert local.find("line1") is None
    said = _join(NetOptions(cpu="line1"))
    assert isinstance(said, str) and "no CPU line1 is on this machine's bus" in said


def test_a_folder_others_may_enter_is_not_read(runtime: Path) -> None:
    assert local.publish("line2", "unixsock-stream/x") is not None
    os.chmod(runtime, 0o777)
    assert local.find("line2", check=False) is None
    assert local.publish("line2", "unixsock-stream/y") is None


def test_an_endpoint_given_on_the_command_line_is_not_written(
    runtime: Path, tmp_path: Path
) -> None:
    """``--listen`` names the bus itself: nothing is written for the shell to find."""
    ends = BusEnds(listen=(f"unixsock-stream/{tmp_path}/own.sock",))
    side = CpuSide({}, cpu="line3", ends=ends)
    try:
        assert local.find("line3", check=False) is None
    finally:
        side.close()


def _until(what: Callable[[], bool], within_s: float = 5.0) -> bool:
    deadline = time.monotonic() + within_s
    while not what():
        if time.monotonic() > deadline:
            return False
        time.sleep(0.02)
    return True


def test_two_cpus_of_one_name_the_older_is_found_again_once_the_newer_ends(
    runtime: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Before: the newer ending took the file away, and the older, still running, was never
    found again. The newer's file stays the newer's while it runs; the older writes its own
    again once the file is gone (``local.KEEP_S``, here 0.05 s)."""
    monkeypatch.setattr(local, "KEEP_S", 0.05)
    older = CpuSide({}, cpu="line5")
    try:
        newer = CpuSide({}, cpu="line5")
        try:
            assert local.find("line5") == newer.endpoint
            time.sleep(0.3)  # six of the older's looks: a live newer's file is left to it
            assert local.find("line5") == newer.endpoint
        finally:
            newer.close()
        assert _until(lambda: local.find("line5") == older.endpoint)
    finally:
        older.close()
    time.sleep(0.2)  # nothing writes it again once the older ended
    assert local.find("line5", check=False) is None


def test_a_cpu_finds_its_file_again_after_a_killed_run_of_its_name_left_one(
    runtime: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A run killed leaves its file and a socket that takes no connection: the live CPU of
    that name writes its own over it."""
    monkeypatch.setattr(local, "KEEP_S", 0.05)
    side = CpuSide({}, cpu="line6")
    try:
        dead = tmp_path / "dead.sock"
        with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as s:
            s.bind(str(dead))  # bound, never listening: as a killed CPU's socket file
        assert local.publish("line6", f"unixsock-stream/{dead}") is not None
        assert _until(lambda: local.find("line6") == side.endpoint)
    finally:
        side.close()
    assert local.find("line6", check=False) is None


def test_a_cpu_ending_leaves_the_file_another_run_of_its_name_wrote(runtime: Path) -> None:
    side = CpuSide({}, cpu="line7")
    other = "unixsock-stream/elsewhere/bus.sock"
    local.publish("line7", other)
    side.close()
    assert local.find("line7", check=False) == other
