"""A CPU listening on its own unix socket writes where, so a shell of the same machine and
user reaches it without ``--connect`` (``web.bus.local``, docs/cli.md, "The bus from a
shell"); a folder others may enter is never read, and a CPU that ended takes its file
away."""

from __future__ import annotations

import os
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
    assert isinstance(said, str) and "no CPU line1 runs on this machine" in said


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
