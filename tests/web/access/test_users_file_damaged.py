"""A users file that is not one is refused naming the file and what is wrong, in words —
never Python's own (``RecursionError``, ``list indices must be integers``, ``('users')``)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from s7graph.web.access.users import UsersError, UsersFile


@pytest.mark.parametrize(
    ("content", "why"),
    [
        (b"[" * 100_000, "not a users file (nested too deep)"),
        (b"[1, 2]", "not a users file (no table of users)"),
        (b'{"olga": {"role": "god"}}', "not a users file (no table of users)"),
        (b'{"version": 99, "users": {}}', "not a users file (unknown version)"),
        (b"\xff", "not a users file ('utf-8' codec can't decode byte 0xff"),
    ],
)
def test_a_users_file_that_is_not_one_says_what_is_wrong(
    tmp_path: Path, content: bytes, why: str
) -> None:
    path = tmp_path / "users.json"
    path.write_bytes(content)
    os.chmod(path, 0o600)
    with pytest.raises(UsersError) as refused:
        UsersFile(path).load()
    assert str(refused.value).startswith(f"{path}: {why}")
    assert "Error" not in str(refused.value)
