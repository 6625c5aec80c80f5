"""Reading on after a syntax error, so that one pass reports up to ``MAX_SYNTAX_ERRORS``
(docs/scl.md, "Diagnostics").

The LALR parser is fed token by token. At an error the tokens are skipped up to the next
``;``, ``THEN``, ``DO``, ``OF``, ``ELSE``, ``ELSIF``, ``UNTIL``, ``BEGIN`` or ``END_…``
keyword; there the parser's stack is cut back to the innermost construct that takes that
token, and reading goes on. Errors met while skipping, or at the very token after the
resumption, are not reported: they would repeat the first one (yacc waits three tokens;
one is enough for statements ended by ``;``). The tree of a
source with errors is never used.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from functools import cache
from typing import Any

from lark import Lark, Token
from lark.exceptions import UnexpectedCharacters, UnexpectedInput, UnexpectedToken

MAX_SYNTAX_ERRORS = 10
"""Syntax errors reported for one source, at most."""

QUIET_TOKENS = 1
"""Tokens to read after a resumption before errors count again."""
_SYNC = frozenset({"THEN", "DO", "OF", "ELSE", "ELSIF", "UNTIL", "BEGIN"})

Describe = Callable[[UnexpectedInput], Any]


def parse_all(parser: Lark, text: str, describe: Describe) -> tuple[Any, list[Any]]:
    """The tree of ``text`` (None when it has errors) and ``describe(error)`` of each of
    its first ``MAX_SYNTAX_ERRORS`` syntax errors."""
    ip = parser.parse_interactive(text)
    state: Any = ip.parser_state
    thread: Any = ip.lexer_thread  # lark's LexerThread (its lex() is untyped)
    found: list[Any] = []
    skipping, quiet = False, 0
    last: Token | None = None

    def fail(exc: UnexpectedInput) -> None:
        nonlocal skipping
        if not skipping and not quiet:
            found.append(describe(exc))
        skipping = True

    def sync(tok: Token) -> None:
        nonlocal skipping, quiet
        tok = _keyword(parser, tok)
        if _is_sync(tok) and _resume(state, tok):
            skipping, quiet = False, QUIET_TOKENS

    while len(found) < MAX_SYNTAX_ERRORS:
        try:
            for tok in thread.lex(state):
                if skipping:
                    sync(tok)
                else:
                    try:
                        state.feed_token(tok)
                        quiet = max(quiet - 1, 0)
                    except UnexpectedToken as exc:
                        fail(exc)
                        sync(tok)
                last = tok
                if len(found) >= MAX_SYNTAX_ERRORS:
                    break
            break
        except UnexpectedCharacters as exc:
            fail(exc)
            pos = thread.state.line_ctr.char_pos
            thread.state.line_ctr.feed(text[pos : pos + 1])
        except UnexpectedToken as exc:  # a word the lexer knows, not here: it is read
            fail(exc)
            sync(exc.token)
    if len(found) >= MAX_SYNTAX_ERRORS:
        return None, found
    end = Token.new_borrow_pos("$END", "", last) if last else Token("$END", "", 0, 1, 1)
    try:
        tree = state.feed_token(end, True)
    except UnexpectedToken as exc:
        fail(exc)
        return None, found
    return (tree if not found else None), found


def _is_sync(tok: Token) -> bool:
    word = str(tok).upper()
    return tok.type != "NAME" and (word == ";" or word in _SYNC or word.startswith("END_"))


def _keyword(parser: Lark, tok: Token) -> Token:
    """``tok`` as the keyword it spells (read as a name where the keyword was not
    expected), else ``tok``."""
    if tok.type != "NAME":
        return tok
    name = _keywords(parser).get(str(tok).upper())
    return Token.new_borrow_pos(name, str(tok), tok) if name else tok


@cache
def _keywords(parser: Lark) -> dict[str, str]:
    """Each keyword of the grammar (upper case) → the name of its terminal."""
    out: dict[str, str] = {}
    for term in parser.terminals:
        if term.name in ("NAME", "LITERAL", "ATTRIBUTE"):
            continue
        if term.pattern.type == "str" and re.fullmatch(r"[A-Za-z_]+", term.pattern.value):
            out[term.pattern.value.upper()] = term.name
        elif term.pattern.type == "re":
            for word in re.findall(r"[A-Z][A-Z_]+", term.pattern.value):
                if re.fullmatch(term.pattern.to_regexp(), word, re.I):
                    out.setdefault(word, term.name)
    return out


def _resume(state: Any, tok: Token) -> bool:
    """Cut ``state``'s stack back to the innermost construct that takes ``tok`` and feed
    it; False (``state`` unchanged) when none does."""
    for depth in range(len(state.state_stack), 0, -1):
        trial = state.copy(deepcopy_values=False)
        del trial.state_stack[depth:]
        del trial.value_stack[depth - 1 :]
        try:
            trial.feed_token(tok, tok.type == "$END")
        except Exception:
            continue
        state.state_stack[:] = trial.state_stack
        state.value_stack[:] = trial.value_stack
        return True
    return False
