"""The shell tells a refused command from one applied but not confirmed durable, and from
one not answered, by the reply's ``kind``; the reason's words decide only for a reply
without a kind (an older CPU's), or with a kind this shell does not know."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from pathlib import Path

import pytest

from s7graph.web.bus.protocol import CommandReply
from s7graph.web.cli import remote
from s7graph.web.cli.net import NetOptions
from s7graph.web.commands import Ack, NoArgs
from tests.paths import EXAMPLES


def answering(monkeypatch: pytest.MonkeyPatch, reply: CommandReply) -> None:
    """The shell logs in and gets ``reply`` to its command (a download's preview
    applies)."""

    class Shell:
        fb = "Seq"

        def send(self, kind: object, args: object, timeout: float = 0.0) -> CommandReply:
            if getattr(args, "preview", False):
                return CommandReply(applied=True, version=3, lines=["S2: renamed"])
            return reply

    @contextlib.contextmanager
    def logged_in(*_: object, **__: object) -> Iterator[Shell]:
        yield Shell()

    monkeypatch.setattr(remote, "_logged_in", logged_in)


@pytest.mark.parametrize(
    ("reason", "kind", "said"),
    [
        # the kind decides, whatever the words
        ("the state file did not commit in 2 s", "timeout", "ack not confirmed: the state"),
        ("not confirmed: msg 7", "state", "ack refused: not confirmed: msg 7"),
        # no kind (an older CPU), or one not known: the words decide
        ("not confirmed: applied in cycle 9, but", "", "ack not confirmed: applied in"),
        ("not confirmed: applied in cycle 9, but", "later", "ack not confirmed: applied in"),
        ("the step is not active", "", "ack refused: the step is not active"),
    ],
)
def test_a_refusal_is_told_from_an_unconfirmed_command_by_its_kind(
    reason: str,
    kind: str,
    said: str,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    answering(monkeypatch, CommandReply(applied=False, reason=reason, kind=kind))
    rc = remote.send_command(NetOptions(), fb=None, user="op", kind=Ack, args=NoArgs())
    assert rc == 1
    assert capsys.readouterr().err.startswith(f"s7graph: {said}")


@pytest.mark.parametrize(
    ("reason", "kind", "taken"),
    [
        ("CPU bus closed", "communication", True),
        ("no answer from CPU 'cpu1' within 30 s", "communication", True),
        ("no answer from CPU 'cpu1' in a file name", "argument", False),
        ("no answer from CPU 'cpu1' within 30 s", "", True),  # an older client's reply
    ],
)
def test_a_download_not_answered_is_told_by_its_kind_communication(
    reason: str,
    kind: str,
    taken: bool,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """No answer (kind ``communication``) may have taken effect; a refusal did not."""
    answering(monkeypatch, CommandReply(applied=False, reason=reason, kind=kind))
    chart = tmp_path / "c.s7g"
    chart.write_text((EXAMPLES / "drill" / "drill.s7g").read_text(encoding="utf-8"))
    rc = remote.download_command(NetOptions(), chart, fb=None, user="eng", yes=True)
    assert rc == 1
    err = capsys.readouterr().err
    if taken:
        assert err.startswith(f"s7graph: download not confirmed: {reason}; it may or may not")
    else:
        assert err.startswith(f"s7graph: download refused: {reason}")
