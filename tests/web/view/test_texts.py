"""The panel's texts (``web.view.texts``): the permanent instructions with their values."""

from __future__ import annotations

from s7graph.web.bus.protocol import ChartLayout, PermanentInfo, StepStateUpdate
from s7graph.web.commands import (
    Ack,
    AckMsg,
    EnIl,
    Halt,
    Init,
    MessageArgs,
    ModeArgs,
    Mres,
    Off,
    OnArgs,
    SetMode,
    SetSteps,
    Start,
    StepArgs,
    StepOn,
    StepsArgs,
    Stop,
    TPush,
)
from s7graph.web.view.status_layer import VALUE_FALSE, VALUE_TRUE
from s7graph.web.view.texts import command_words, login_html, login_notice, permanent_html


def layout(*permanent: PermanentInfo) -> ChartLayout:
    return ChartLayout(fb="FB", steps=[], transitions=[], sequences=[], permanent=list(permanent))


def hex_of(rgb: tuple[int, int, int]) -> str:
    return "#{:02x}{:02x}{:02x}".format(*rgb)


def test_the_permanent_instructions_are_listed_under_their_place_with_their_values() -> None:
    chart = layout(
        PermanentInfo(place="after", text='S "Lamp" := "Trip";', watch="Lamp"),
        PermanentInfo(place="before", text="low := level < 10;", watch="low"),
        PermanentInfo(place="after", text="CALL FC 3;"),
        PermanentInfo(place="after", text="n := n + 1;", watch="n"),
    )
    update = StepStateUpdate(
        cycle=1, t_ms=10, mode="AUTO", active=[], values={"low": True, "Lamp": False, "n": 7}
    )
    html = permanent_html(chart, update)
    order = ["Before the sequences", "low := level &lt; 10;", "After the sequences", "Lamp"]
    assert [html.index(part) for part in order] == sorted(html.index(part) for part in order)
    assert f'background:{hex_of(VALUE_TRUE)};padding:0 0.3em">TRUE' in html  # low
    assert f'background:{hex_of(VALUE_FALSE)};padding:0 0.3em">FALSE' in html  # Lamp
    assert '">7</span>' in html
    waiting = permanent_html(chart, None)  # before the first scan: the texts, no values
    assert "low := level &lt; 10;" in waiting and "TRUE" not in waiting and "FALSE" not in waiting


def test_a_chart_without_permanent_instructions_has_no_list() -> None:
    assert permanent_html(layout(), None) == ""


def test_a_commands_notice_names_it_as_its_button_does_never_by_its_wire_op() -> None:
    words = [
        command_words(AckMsg(fb="F", args=MessageArgs(msg_id=7))),
        command_words(SetMode(fb="F", args=ModeArgs(mode="MAN"))),
        command_words(StepOn(fb="F", args=StepArgs(step=3))),
        command_words(SetSteps(fb="F", args=StepsArgs(steps=[3, 5]))),
        command_words(Halt(fb="F", args=OnArgs(on=False))),
        command_words(EnIl(fb="F", args=OnArgs(on=False))),
        command_words(Init(fb="F")),
        command_words(Stop(fb="F")),
    ]
    assert words == [
        "acknowledge message",
        "mode MAN",
        "activate step 3",
        "set steps 3, 5",
        "resume",
        "interlocks off",
        "initialize",
        "CPU to STOP",
    ]
    plain = [command_words(kind(fb="F")) for kind in (Ack, Off, TPush, Mres, Start)]
    assert plain == [
        "acknowledge",
        "disable (OFF)",
        "T_PUSH (continue)",
        "memory reset (MRES)",
        "CPU to RUN",
    ]


def test_a_logins_notice_says_unverified_as_the_login_panel_does() -> None:
    assert login_notice("olga", "operator", True) == "olga (operator)"
    assert "olga</b> (operator)" in login_html("olga", "operator", True, False)
    assert login_notice("tess", "engineer", False) == "tess (unverified) (engineer)"
    assert "tess (unverified)</b> (engineer)" in login_html("tess", "engineer", False, True)


def test_every_command_has_words_for_its_notice() -> None:
    from s7graph.web.commands import COMMAND_TYPES, op_of

    assert [op_of(c) for c in COMMAND_TYPES if not c.words] == []
