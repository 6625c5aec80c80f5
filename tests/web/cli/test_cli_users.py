"""``s7graph users`` on a ``--file`` that cannot be the users file: one line naming it and
the way on, exit 2, nothing written (docs/cli.md, "s7graph users, s7graph audit")."""

from __future__ import annotations

import io
from pathlib import Path

import pytest

from s7graph.web.cli import main


def _said(capsys: pytest.CaptureFixture[str], *argv: str) -> str:
    assert main(list(argv)) == 2
    out, err = capsys.readouterr()
    assert out == "" and len(err.splitlines()) == 1
    return err.strip()


@pytest.mark.parametrize("command", [["list"], ["remove", "olga"], ["add", "olga"]])
def test_a_folder_as_the_users_file_is_said_to_be_a_folder(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    command: list[str],
) -> None:
    """Before: ``others may read it (mode 1777); run chmod 600 /tmp`` for ``--file /tmp``."""
    monkeypatch.setattr("sys.stdin", io.StringIO("correct horse\n"))
    role = ["--role", "operator", "--password-stdin"] if command[0] == "add" else []
    folder = tmp_path / "plant"
    folder.mkdir(mode=0o777)
    said = _said(capsys, "users", *command, "--file", str(folder), *role)
    assert said == (
        f"s7graph: error: {folder}: a folder, not a users file; give --file the path of a file"
    )
    assert list(folder.iterdir()) == []


def test_listing_a_users_file_that_is_not_there_says_so_and_how_to_make_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Before: nothing printed and exit 0, as for a file without users."""
    path = tmp_path / "userz.json"
    assert _said(capsys, "users", "list", "--file", str(path)) == (
        f"s7graph: error: {path}: no such users file "
        f"(s7graph users add NAME --role ROLE --file {path})"
    )
    assert not path.exists()
