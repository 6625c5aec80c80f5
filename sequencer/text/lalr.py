"""The fast LALR loop of the chart parser (docs/chart-format.md; called by
``sequencer/text/parse.py``).

A chart without syntax errors is parsed by the loop below: the same LALR table and the
same per-state scanners as lark's parser and contextual lexer, without lark's per-token
machinery. Anything unexpected (a character no terminal matches, a token the state does
not accept) makes it give up; parse_chart then parses again with lark, which reports the
syntax errors and recovers. The fast path never reports anything itself.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from typing import Any

from lark import Lark, Token
from lark.parsers.lalr_analysis import Shift


class _Tables:
    """The LALR table and the lexers of the chart parser (``parse._parser``), indexed
    for :func:`_fast_parse`."""

    def __init__(self, lark: Lark) -> None:
        table = lark.parser.parser.parser.parse_table
        self.rules: list[Any] = list(lark.rules)
        index = {id(r): i for i, r in enumerate(self.rules)}
        # per state: terminal or rule name (plain str: lark's are Tokens, slow to compare)
        # -> next state (shift / goto, >= 0) or -1 - rule index (reduce)
        self.actions: dict[int, dict[str, int]] = {
            state: {
                str(sym): arg if action is Shift else -1 - index[id(arg)]
                for sym, (action, arg) in acts.items()
            }
            for state, acts in table.states.items()
        }
        self.start: int = table.start_states["start"]
        self.end: int = table.end_states["start"]
        # reduce: (children, rule name, passes its only child through unchanged)
        self.reduce: list[tuple[int, str, bool]] = [
            (len(r.expansion), str(r.origin.name), _is_pass_through(r)) for r in self.rules
        ]
        # per state: (compiled union of the terminals, ignored, may hold newlines, callbacks)
        self.lexers = _Lexers(lark.parser.lexer.lexers)


_Lexer = tuple[Any, frozenset[str], frozenset[str], dict[str, Any]]


class _Lexers(dict[int, _Lexer]):
    """Per parser state: (compiled union of its terminals, ignored, may hold newlines,
    callbacks) — made when the state is first reached: compiling the unions of all states
    took longer than parsing most charts, and a chart reaches a part of them."""

    def __init__(self, lark_lexers: dict[int, Any]) -> None:
        super().__init__()
        self._lark = lark_lexers

    def __missing__(self, state: int) -> _Lexer:
        lexer = self._lark[state]
        mres = lexer.scanner._mres
        if len(mres) != 1:  # lark split the union; not the case for this grammar
            raise RuntimeError("fast parser: one scanner regex per state expected")
        made = self[state] = (mres[0], lexer.ignore_types, lexer.newline_types, lexer.callback)
        return made


def _is_pass_through(rule: Any) -> bool:
    """``?a: b`` — the builder returns the child itself (see lark's ExpandSingleChild)."""
    if not rule.options.expand1 or rule.alias or len(rule.expansion) != 1:
        return False
    sym = rule.expansion[0]
    if (sym.is_term and sym.filter_out) or (not sym.is_term and sym.name.startswith("_")):
        return False
    return not any(rule.options.empty_indices or ())


_WS_CHARS = " \t\f\r\n"  # common.WS, the %ignore'd blanks
_WS = re.compile(r"[ \t\f\r\n]+")


class _GiveUp(Exception):
    """The fast path met something it leaves to lark."""


def _fast_parse(text: str, callbacks: dict[Any, Callable[[list[Any]], Any]], t: _Tables) -> Any:
    """Parse ``text`` with the reduce ``callbacks`` and the tables ``t`` of the chart
    parser; raise :class:`_GiveUp` at a syntax error."""
    actions, lexers, reduce_info = t.actions, t.lexers, t.reduce
    calls = [callbacks[r] for r in t.rules]
    end_state = t.end
    states = [t.start]
    values: list[Any] = []
    pos, line, line_start, n = 0, 1, 0, len(text)
    new_token = Token
    while True:
        # -- the next token, lexed for the state the parser is in
        state = states[-1]
        mre, ignore, newline_types, lex_callbacks = lexers[state]
        while True:
            if pos < n and text[pos] in _WS_CHARS:
                # only WS can match at a blank (no other terminal starts with one)
                blank_end = _WS.match(text, pos).end()  # type: ignore[union-attr]
                newlines = text.count("\n", pos, blank_end)
                if newlines:
                    line += newlines
                    line_start = text.rindex("\n", pos, blank_end) + 1
                pos = blank_end
            if pos >= n:
                ttype = "$END"
                tok = None
                break
            m = mre.match(text, pos)
            if m is None:
                raise _GiveUp
            value = m.group(0)
            ttype = m.lastgroup
            ignored = ttype in ignore
            tok = None
            if not ignored or ttype in lex_callbacks:
                tok = new_token(ttype, value, pos, line, pos - line_start + 1)
            if ttype in newline_types:
                newlines = value.count("\n")
                if newlines:
                    line += newlines
                    line_start = pos + value.rindex("\n") + 1
            pos += len(value)
            if tok is not None:
                tok.end_line = line
                tok.end_column = pos - line_start + 1
                tok.end_pos = pos
                if ttype in lex_callbacks:
                    tok = lex_callbacks[ttype](tok)
                if not ignored:
                    ttype = tok.type
                    break
        # -- feed it: reduce as long as the table says so, then shift
        while True:
            act = actions[state].get(ttype)
            if act is None:
                raise _GiveUp
            if act >= 0:
                if tok is None:  # $END is never shifted
                    raise _GiveUp
                states.append(act)
                values.append(tok)
                break
            rule = -1 - act
            size, origin, pass_through = reduce_info[rule]
            if pass_through:
                del states[-1]
            elif size:
                children = values[-size:]
                del states[-size:]
                del values[-size:]
                values.append(calls[rule](children))
            else:
                values.append(calls[rule]([]))
            state = actions[states[-1]][origin]
            states.append(state)
            if tok is None and state == end_state:
                return values[-1]
