"""engine/grammars.py: a parser built once is kept in the user's own cache folder and read
back; a folder others may write, a damaged file or no folder at all cost time, never a
wrong parser."""

from __future__ import annotations

from pathlib import Path

import pytest

from s7graph.engine.grammars import CACHE_ENV, cache_folder, lark_parser

GRAMMAR = """
start: pair+
pair: NAME "=" NUMBER ";"
%import common.CNAME -> NAME
%import common.INT -> NUMBER
%import common.WS
%ignore WS
"""
TEXT = "a = 1; b = 22;"


@pytest.fixture
def grammar(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.setenv(CACHE_ENV, str(tmp_path / "cache"))
    path = tmp_path / "pairs.lark"
    path.write_text(GRAMMAR)
    return path


def _tree(grammar: Path) -> str:
    return str(lark_parser(grammar, parser="lalr", lexer="contextual").parse(TEXT))


def test_a_parser_is_kept_in_the_users_own_folder_and_read_back(grammar: Path) -> None:
    fresh = _tree(grammar)
    folder = cache_folder()
    assert folder == grammar.parent / "cache" / "s7graph"
    assert folder.stat().st_mode & 0o777 == 0o700
    (kept,) = folder.iterdir()
    assert kept.name.startswith("pairs-") and kept.suffix == ".lark"
    assert _tree(grammar) == fresh  # read back from the file
    assert list(folder.iterdir()) == [kept]  # nothing left of the build


def test_other_options_or_another_grammar_are_kept_apart(grammar: Path) -> None:
    _tree(grammar)
    lark_parser(grammar, parser="lalr", lexer="basic")
    folder = cache_folder()
    assert folder is not None and len(list(folder.iterdir())) == 2
    grammar.write_text(GRAMMAR.replace('"="', '":"'))
    assert str(lark_parser(grammar, parser="lalr").parse("a : 1;")).startswith("Tree")
    assert len(list(folder.iterdir())) == 3


def test_a_damaged_file_is_built_again(grammar: Path) -> None:
    fresh = _tree(grammar)
    folder = cache_folder()
    assert folder is not None
    (kept,) = folder.iterdir()
    kept.write_bytes(b"not a parser")
    assert _tree(grammar) == fresh


def test_a_folder_others_may_write_is_not_used(grammar: Path) -> None:
    folder = grammar.parent / "cache" / "s7graph"
    folder.mkdir(parents=True)
    folder.chmod(0o777)
    assert cache_folder() is None
    assert _tree(grammar).startswith("Tree")
    assert list(folder.iterdir()) == []


def test_without_a_folder_the_parser_is_built_each_time(
    grammar: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    blocked = grammar.parent / "a-file"
    blocked.write_text("")
    monkeypatch.setenv(CACHE_ENV, str(blocked))
    assert cache_folder() is None
    assert _tree(grammar).startswith("Tree")
