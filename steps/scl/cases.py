"""CASE arms whose values are constants' names (docs/scl.md, "Statements").

``CASE state OF Fill: …; 3..Drain: …`` — after the first arm, ``Drain:`` reads like a jump
label and ``Fill, 7:`` like a statement, so the parser leaves them inside the statement
list of the arm before. ``split_arms`` makes them arms again before anything else reads
the statements: a ``Fill:`` directly in an arm's list starts a new arm unless ``Fill`` is
declared in the block's LABEL section; ``Fill, 7:`` and ``Fill..9:`` always start one
(outside a CASE they are E242).
"""

from __future__ import annotations

from collections.abc import Callable, Container
from dataclasses import replace

from s7graph.steps.scl import model as m
from s7graph.steps.scl.diagnostics import Problem

Report = Callable[[Problem], None]


def split_arms(
    stmts: tuple[m.Stmt, ...], labels: Container[str], report: Report
) -> tuple[m.Stmt, ...]:
    """``stmts`` with every CASE's arms split at the values read as statements."""
    return tuple(_stmt(s, labels, report) for s in stmts)


def _stmt(s: m.Stmt, labels: Container[str], report: Report) -> m.Stmt:
    def body(stmts: tuple[m.Stmt, ...]) -> tuple[m.Stmt, ...]:
        return split_arms(stmts, labels, report)

    if isinstance(s, m.CaseHead):
        report(Problem("E242", "CASE values outside the arms of a CASE", s.loc))
        return _stmt(s.stmt, labels, report)
    if isinstance(s, m.Labeled):
        return replace(s, stmt=_stmt(s.stmt, labels, report))
    if isinstance(s, m.If):
        branches = tuple((cond, body(stmts)) for cond, stmts in s.branches)
        return replace(s, branches=branches, orelse=_maybe(body, s.orelse))
    if isinstance(s, m.For | m.While | m.Repeat):
        return replace(s, body=body(s.body))
    if isinstance(s, m.Case):
        arms = tuple(a for arm in s.arms for a in _arm(arm, labels, report))
        return replace(s, arms=arms, orelse=_maybe(body, s.orelse))
    return s


def _maybe(
    body: Callable[[tuple[m.Stmt, ...]], tuple[m.Stmt, ...]], stmts: tuple[m.Stmt, ...] | None
) -> tuple[m.Stmt, ...] | None:
    return None if stmts is None else body(stmts)


def _arm(arm: m.CaseArm, labels: Container[str], report: Report) -> list[m.CaseArm]:
    """``arm`` cut where a statement of its list starts a further arm."""
    arms: list[m.CaseArm] = []
    values, loc, current = arm.values, arm.loc, list[m.Stmt]()
    for s in arm.body:
        while True:
            head: tuple[tuple[m.CaseValue, m.CaseValue], ...] | None = None
            if isinstance(s, m.CaseHead):
                head = s.values
            elif isinstance(s, m.Labeled) and s.label.upper() not in labels:
                name = m.Path(m.Base("name", s.label, s.loc), (), s.loc)
                head = ((name, name),)
            if head is None or not isinstance(s, m.CaseHead | m.Labeled):
                break
            arms.append(m.CaseArm(values, split_arms(tuple(current), labels, report), loc))
            values, loc, current, s = head, s.loc, [], s.stmt
        current.append(s)
    arms.append(m.CaseArm(values, split_arms(tuple(current), labels, report), loc))
    return arms
