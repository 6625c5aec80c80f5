"""Every text the page shows, as escaped HTML: status line, alarms, alarm history, audit,
step details, login state and the "disconnected" banner.

Whatever came over the bus or from a user (names, message texts, reasons, conditions)
goes through ``html.escape`` here; nothing else builds HTML for the page.
"""

from __future__ import annotations

import html
from collections.abc import Iterable, Mapping

from s7graph.sequencer.checks.diagnostics import Diagnostic
from s7graph.web.bus.cycle_text import clock, cycle_lines
from s7graph.web.bus.protocol import (
    AlarmEntry,
    AlarmHistory,
    AlarmList,
    AuditEntry,
    ChartLayout,
    Contact,
    CycleStats,
    ForceList,
    PermanentContact,
    StepDetail,
    StepStateUpdate,
)
from s7graph.web.commands import Command
from s7graph.web.view.status_layer import value_text

__all__ = [
    "ack_label",
    "alarms_html",
    "audit_html",
    "banner_html",
    "clip",
    "command_words",
    "describe",
    "detail_html",
    "diagnostic_button",
    "diagnostic_line",
    "diagnostics_html",
    "editor_status_html",
    "force_mark",
    "forces_html",
    "history_html",
    "lines_html",
    "log_html",
    "login_html",
    "login_notice",
    "permanent_html",
    "rows_note",
    "small",
    "status_html",
    "step_rows",
    "step_state",
    "title",
    "transition_html",
]


def clip(text: str, n: int) -> str:
    return text if len(text) <= n else text[: n - 1] + "…"


def title(prefix: str, number: int, name: str, width: int) -> str:
    """``S3  Fill``; just ``S3`` when the name is empty or only repeats the number."""
    short = f"{prefix}{number}"
    return short if name in ("", short) else f"{short}  {clip(name, width)}"


def command_words(command: Command) -> str:
    """What a command's notice calls it, in the words of the page's buttons (never the
    op's wire name): ``mode MAN``, ``activate step 3``, ``CPU to STOP``, ``resume``."""
    op, args = command.op, command.args
    words = type(command).words
    if (on := getattr(args, "on", None)) is not None:
        if op == "halt":
            return "halt" if on else "resume"
        return f"{words} {'on' if on else 'off'}"
    if (mode := getattr(args, "mode", None)) is not None:
        return f"{words} {mode}"
    if (step := getattr(args, "step", None)) is not None:
        return f"{words} {step}"
    if steps := getattr(args, "steps", None):
        return f"{words}{'s' if len(steps) > 1 else ''} {', '.join(map(str, steps))}"
    return words


def small(body: str) -> str:
    return f'<div style="font-size:0.8em;line-height:1.5">{body}</div>'


def ack_label(entry: AlarmEntry) -> str:
    if entry.step is not None and entry.kind:
        what = "supervision" if entry.kind == "SV" else "interlock"
        return f"Acknowledge S{entry.step} {what}"
    return clip(f"Acknowledge message {entry.msg_id}", 64)


def alarms_html(alarms: AlarmList | None, *, empty: str = "no messages") -> str:
    """Every listed message: time, state, text, step, who acknowledged it and when."""
    if alarms is None or not alarms.entries:
        return small(f'<span style="color:#777">{html.escape(empty)}</span>')
    rows = []
    for e in reversed(alarms.entries):  # newest first
        colour = "#c00" if e.state == "incoming" else "#a60"
        where = f" · S{e.step}" if e.step is not None else ""
        ack = (
            f"acknowledged by {html.escape(e.ack_user or '?')} {clock(e.ack_ms)}"
            if e.acked
            else "<b>unacknowledged</b>"
        )
        rows.append(
            f'<div style="border-left:3px solid {colour};padding-left:4px;margin-bottom:4px">'
            f'{clock(e.came_ms)} <span style="color:{colour}">{e.state}</span>'
            f"{html.escape(where)} · {ack}<br>{html.escape(e.text)}</div>"
        )
    return small("".join(rows))


def mark(c: Contact) -> str:
    tick = '<span style="color:#080">✓</span>' if c.ok else '<span style="color:#c00">✗</span>'
    return f"&nbsp;&nbsp;{tick} {html.escape(c.text)}"


def step_state(d: StepDetail) -> str:
    parts = ["active", f"T {d.t_ms / 1000:.1f} s", f"U {d.u_ms / 1000:.1f} s"]
    if d.interlock_error:
        parts.append('<span style="color:#c00">interlock error</span>')
    if d.supervision_fault:
        parts.append('<span style="color:#c00">supervision fault</span>')
    return " · ".join(parts)


def step_rows(d: StepDetail) -> list[str]:
    rows = []
    if d.interlock:
        state = "holds" if d.interlock_ok else '<span style="color:#c00">lost</span>'
        rows += [f"Interlock (C): {state}", *map(mark, d.interlock)]
    if d.supervision:
        state = '<span style="color:#c00">fault</span>' if d.supervision_fault else "ok"
        rows += [f"Supervision (V): {state}", *map(mark, d.supervision)]
    for t in d.transitions:
        holds = "holds" if t.holds else '<span style="color:#c00">does not hold</span>'
        name = html.escape(title("T", t.number, t.name, 10_000))
        rows += [f"<b>{name}</b>: {holds}", *map(mark, t.contacts)]
    if not d.transitions:
        rows.append("no valid transition leaves it (a step before it is inactive)")
    return rows


def describe(args: dict[str, object]) -> str:
    return " ".join(f"{k}={v}" for k, v in args.items())


def log_html(lines: list[str]) -> str:
    if not lines:
        return '<div style="font-size:0.8em;color:#777">no events yet</div>'
    body = "<br>".join(html.escape(line) for line in lines)
    style = "font-family:monospace;font-size:0.75em;max-height:14em;overflow:auto"
    return f'<div style="{style}">{body}</div>'


def status_html(
    update: StepStateUpdate | None,
    cpu_cycle: int,
    cpu_state: str,
    stats: CycleStats | None,
    forces: int = 0,
    reason: str = "",
) -> str:
    """The status line: the FORCE mark, mode, cycle, active steps, cycle time, errors,
    halts, and the level pins a command holds; the CPU's state when not RUN, with
    ``reason`` (why it is in STOP) below."""
    mark = force_mark(forces)
    if update is None:
        return f'<div style="font-size:0.85em">{mark}waiting for the CPU…</div>'
    active = ", ".join(f"S{n}" for n in update.active) or "none"
    parts = [
        f"<b>{html.escape(update.mode)}</b>",
        f"cycle {max(update.cycle, cpu_cycle)}",
        f"active: {html.escape(active)}",
    ]
    if stats is not None and stats.max_ms > 0:
        shown = f"cycle time {stats.last_ms:.1f} ms (max {stats.max_ms:.1f})"
        tip = "\n".join(cycle_lines(stats))
        parts.append(f'<span title="{html.escape(tip)}">{shown}</span>' if tip else shown)
    bad = sorted(set(update.disturbed) | set(update.latched))
    if bad:
        errors = ", ".join(f"S{n}" for n in bad)
        parts.append(f'<span style="color:#c00">error: {html.escape(errors)}</span>')
    for flag, text in (
        (update.halted, "HALTED"),
        (not update.il_enabled, "interlocks off"),
        (not update.sv_enabled, "supervisions off"),
    ):
        if flag:
            parts.append(f'<b style="color:#a60">{text}</b>')
    if update.overrides:
        held = ", ".join(f"{pin} = {int(v)}" for pin, v in sorted(update.overrides.items()))
        tip = "held by a command, whatever the pin; kept over a warm or hot restart"
        parts.append(f'<span style="color:#a60" title="{tip}">held: {html.escape(held)}</span>')
    if cpu_state != "RUN":
        parts.insert(0, f'<b style="color:#c00">{html.escape(cpu_state)}</b>')
    why = f'<div style="color:#c00">{html.escape(reason)}</div>' if reason else ""
    return f'<div style="font-size:0.85em">{mark}{" · ".join(parts)}{why}</div>'


def force_mark(forces: int) -> str:
    """The CPU's FRCE LED: a yellow FORCE mark while force jobs are active, else nothing."""
    if forces <= 0:
        return ""
    jobs = f"{forces} force job{'s' if forces != 1 else ''} active"
    style = "background:#fd0;color:#000;font-weight:bold;padding:0 4px;border-radius:3px"
    return f'<span style="{style}" title="{jobs}">FORCE</span> '


def forces_html(forces: ForceList | None) -> str:
    """The active force jobs: address (symbol) = value, and who forced it."""
    if forces is None or not forces.entries:
        return small('<span style="color:#777">no force job active</span>')
    rows = []
    for e in forces.entries:
        name = f' "{html.escape(e.symbol)}"' if e.symbol else ""
        who = f' <span style="color:#777">({html.escape(e.user)})</span>' if e.user else ""
        rows.append(f"<b>{html.escape(e.address)}</b>{name} = {html.escape(e.value)}{who}")
    style = "max-height:12em;overflow:auto"
    return small(f'<div style="{style}">' + "<br>".join(rows) + "</div>")


def banner_html(connected: bool, cpu: str) -> str:
    """Nothing while the CPU is reachable, else a red "disconnected" banner."""
    if connected:
        return ""
    style = "background:#c00;color:#fff;padding:6px;font-weight:bold;border-radius:4px"
    return (
        f'<div style="{style}">disconnected: CPU {html.escape(cpu)} is not reachable '
        "over the bus; the chart shows no live state</div>"
    )


def audit_html(entries: list[AuditEntry]) -> str:
    """The last audit rows, newest first: when, who (role), from where, what, verdict (a
    row of several refusals: how many, ``refused ×1,234``); an unproven sender's row says
    the name it gave only as claimed, as ``s7graph audit`` does."""
    if not entries:
        return small('<span style="color:#777">no commands yet</span>')
    rows = []
    for e in reversed(entries):
        times = f" ×{e.count:,}" if e.count != 1 else ""
        verdict = (
            f'<span style="color:#080">applied{times}</span>'
            if e.outcome == "applied"
            else f'<span style="color:#c00">refused{times}: {html.escape(e.reason)}</span>'
        )
        who = html.escape(e.user) + (f" ({html.escape(e.role)})" if e.role else "")
        if e.claimed:  # a name nobody proved: never shown as the author
            who += f' claiming "{html.escape(e.claimed)}" (unproven)'
        args = "" if e.args in ("", "{}") else " " + html.escape(e.args)
        origin = f" · {html.escape(e.origin)}" if e.origin else ""
        rows.append(f"{clock(e.t_ms)} <b>{who}</b>{origin}: {html.escape(e.op)}{args} — {verdict}")
    style = "max-height:16em;overflow:auto"
    return small(f'<div style="{style}">' + "<br>".join(rows) + "</div>")


def history_html(history: AlarmHistory | None) -> str:
    """The alarm history, newest first: when, came / went / acknowledged by whom, text."""
    if history is None or not history.entries:
        return small('<span style="color:#777">no message events yet</span>')
    words = {"incoming": "came", "outgoing": "went", "acknowledged": "acknowledged"}
    rows = []
    for e in reversed(history.entries):
        what = words.get(e.state, e.state)
        if e.state == "acknowledged":
            what += f" by {e.user or '?'}"
        rows.append(f"{clock(e.t_ms)} <b>{html.escape(what)}</b> {html.escape(e.text)}")
    style = "max-height:16em;overflow:auto"
    return small(f'<div style="{style}">' + "<br>".join(rows) + "</div>")


def followed_step(update: StepStateUpdate | None) -> int:
    """The step *Details* shows when none is chosen: the first disturbed, else the first
    active step (0: none active)."""
    if update is None or not update.active:
        return 0
    return (sorted(set(update.disturbed) & set(update.active)) or update.active)[0]


def detail_html(layout: ChartLayout, update: StepStateUpdate | None, number: int) -> str:
    """The "Step details" of step ``number`` (0: the first disturbed, else the first
    active step): why it does (not) switch."""
    if number == 0:
        number = followed_step(update)
        if number == 0:
            return small("no active step (choose one with <i>Show step</i>)")
    info = layout.step(number)
    if info is None:
        return small(f"no step S{number} in {html.escape(layout.fb)}")
    head = f"<b>{html.escape(title('S', number, info.name, 10_000))}</b>"
    if update is None:
        return small(f"{head}: waiting for the CPU…")
    detail = next((d for d in update.details if d.number == number), None)
    if detail is None:
        rows = [f"{head}: inactive"]
        for t in layout.transitions:
            if number in t.sources:
                cond = html.escape(t.condition or "TRUE")
                name = html.escape(title("T", t.number, t.name, 10_000))
                rows.append(f"{name}: {cond} <i>(evaluated while the step is active)</i>")
        return small("<br>".join(rows))
    return small("<br>".join([head + ": " + step_state(detail), *step_rows(detail)]))


def transition_html(layout: ChartLayout, update: StepStateUpdate | None, number: int) -> str:
    """The details of transition ``number``: its name, its whole condition, where it leads
    and, while a step before it is active, whether it holds and each contact."""
    t = next((x for x in layout.transitions if x.number == number), None)
    if t is None:
        return small(f"no transition T{number} in {html.escape(layout.fb)}")
    head = f"<b>{html.escape(title('T', number, t.name, 10_000))}</b>"
    steps = ", ".join(f"S{n}" for n in t.sources) or "-"
    where = ", ".join(f"S{n}" for n in t.targets) or "STOP (branch stop)"
    cond = html.escape(t.condition) if t.condition else "<i>empty: holds at once</i>"
    rows = [
        head,
        f"from {html.escape(steps)} to {html.escape(where)}",
        f'condition: <span style="font-family:monospace;white-space:pre-wrap;'
        f'word-break:break-all">{cond}</span>',
    ]
    live = None
    if update is not None:
        live = next((c for d in update.details for c in d.transitions if c.number == number), None)
    if live is not None:
        holds = "holds" if live.holds else '<span style="color:#c00">does not hold</span>'
        rows += [f"now: {holds}", *map(mark, live.contacts)]
    elif update is not None:
        rows.append("<i>evaluated while the steps before it are active</i>")
    return small("<br>".join(rows))


PERMANENT_PLACES = {"before": "Before the sequences", "after": "After the sequences"}
"""The headings of S7-GRAPH's permanent pre- and post-instructions in the panel."""


def permanent_html(layout: ChartLayout, update: StepStateUpdate | None) -> str:
    """The FB's permanent instructions (run in every call, before or after its sequences),
    each with the value the operand it writes had after the last scan and a coil's
    contacts marked as the criteria are — fulfilled or not, by the bit each reads and its
    NOT — as S7-GRAPH's status shows the permanent instructions' contacts ("" when the
    chart has none)."""
    if not layout.permanent:
        return ""
    values = update.values if update is not None else {}
    rows: list[str] = []
    for place, heading in PERMANENT_PLACES.items():
        items = [p for p in layout.permanent if p.place == place]
        if items:
            rows.append(f"<b>{heading}</b>")
        for p in items:
            code = f'<span style="font-family:monospace">{html.escape(p.text)}</span>'
            if p.watch and p.watch in values:
                text, (r, g, b) = value_text(values[p.watch])
                chip = f"background:#{r:02x}{g:02x}{b:02x};padding:0 0.3em"
                code += f' <span style="{chip}">{html.escape(text)}</span>'
            rows.append(code)
            rows += [_permanent_contact(c, values) for c in p.contacts]
    return small("<br>".join(rows))


def _permanent_contact(c: PermanentContact, values: Mapping[str, object]) -> str:
    """A coil's contact: ✓ or ✗ from the bit it read (inverted by its NOT), or nothing
    (a comparison, or no value yet)."""
    value = values.get(c.watch) if c.watch else None
    if not isinstance(value, bool | int):
        return f"&nbsp;&nbsp;· {html.escape(c.text)}"
    return mark(Contact(text=c.text, ok=bool(value) != c.negated))


def login_html(user: str, role: str, verified: bool, demo: bool, refused: str = "") -> str:
    """Who this page is logged in as, or how to log in; ``refused``: why the last login
    was refused (a wrong password, a lockout), shown until the next one."""
    if not user and refused:
        return small(f'<span style="color:#c92a2a">login refused: {html.escape(refused)}</span>')
    if not user:
        how = (
            "type your name and <i>Log in</i> (no users file: names are recorded unverified)"
            if demo
            else "log in to command; until then this page only watches"
        )
        return small(f'<span style="color:#777">viewer: {how}</span>')
    shown = html.escape(user) + ("" if verified else " (unverified)")
    return small(f"logged in as <b>{shown}</b> ({html.escape(role)})")


def login_notice(user: str, role: str, verified: bool) -> str:
    """The body of a login's notice, in the words of the Login panel: ``olga (operator)``,
    ``tess (unverified) (engineer)`` without a users file (plain text)."""
    return f"{user}{'' if verified else ' (unverified)'} ({role})"


# ---------------------------------------------------------------- the editor


def diagnostic_line(d: Diagnostic) -> str:
    """``3:14 error[E040] unknown symbol … (transition T2)``: a diagnostic as the editor
    lists it, located by line and column in the source view (plain text)."""
    tail = f" ({d.element})" if d.element else ""
    where = f"{d.loc.line}:{d.loc.col} " if d.loc.line > 0 else ""
    return f"{where}{d.severity}[{d.code}] {d.message}{tail}"


def diagnostic_button(i: int, d: Diagnostic) -> str:
    """The short label of diagnostic ``i``'s button: ``2 · 20:50 E042 · transition T2``."""
    where = f"{d.loc.line}:{d.loc.col} " if d.loc.line > 0 else ""
    tail = f" · {d.element}" if d.element else ""
    return clip(f"{i} · {where}{d.code}{tail}", 60)


def diagnostics_html(diagnostics: Iterable[Diagnostic], refusal: str = "") -> str:
    """The editor's problem list: the refused edit first, then each diagnostic in full,
    numbered as its button (a click on the button selects its element)."""
    items = list(diagnostics)
    rows = []
    if refusal:
        rows.append(f'<b style="color:#c00">not made: {html.escape(refusal)}</b>')
    errors = sum(1 for d in items if d.severity == "error")
    warnings = len(items) - errors
    if not items:
        rows.append('<span style="color:#080">no problems: the chart compiles</span>')
    else:
        head = f"{errors} error{'s' * (errors != 1)}, {warnings} warning{'s' * (warnings != 1)}"
        colour = "#c00" if errors else "#a60"
        rows.append(f'<span style="color:{colour}">{head}</span> (a button selects its element)')
        rows += [f"{i} · {html.escape(diagnostic_line(d))}" for i, d in enumerate(items, 1)]
    return small("<br>".join(rows))


def editor_status_html(
    *,
    editing: bool,
    file: str,
    base: int | None,
    running: int,
    undo: str | None,
    redo: str | None,
    note: str = "",
) -> str:
    """Where the editor stands: the file, the chart version it started from and the one the
    CPU runs, what undo and redo would do, the last outcome."""
    if not editing:
        return small(
            '<span style="color:#777">edit the chart here, then download it into '
            "the running CPU (online change)</span>"
        )
    parts = [f"file <b>{html.escape(file or '(new)')}</b>"]
    if base is not None:
        parts.append(f"edited from version {base}")
    parts.append(f"the CPU runs version {running}")
    rows = [" · ".join(parts)]
    if undo:
        rows.append(f"undo: {html.escape(clip(undo, 80))}")
    if redo:
        rows.append(f"redo: {html.escape(clip(redo, 80))}")
    if note:
        rows.append(html.escape(note))
    return small("<br>".join(rows))


def rows_note(shown: int, total: int = -1, start: int = 0) -> str:
    """The line above a step's table of action rows (``shown`` of ``total`` from row
    ``start``, 0-based)."""
    total = shown if total < 0 else total
    if not shown:
        return small('<span style="color:#777">no action rows: add one below</span>')
    if shown == total:
        return small(f"{shown} action row{'s' if shown != 1 else ''}, run top to bottom")
    return small(f"rows {start + 1}–{start + shown} of {total}, run top to bottom")


def lines_html(lines: Iterable[str], *, heading: str = "") -> str:
    """A list of lines (a change summary, a refusal's diagnostics), escaped."""
    body = "<br>".join(html.escape(line) for line in lines) or "(nothing)"
    head = f"<b>{html.escape(heading)}</b><br>" if heading else ""
    style = "max-height:22em;overflow:auto;font-family:monospace;font-size:0.85em"
    return f'{head}<div style="{style}">{body}</div>'
