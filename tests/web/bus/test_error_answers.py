"""What a client makes of an answer that is not the message it asked for (docs/bus.md,
"Answers that are not messages"): a peer on a real zenoh session answers every query of CPU
``odd`` with zenoh's error reply, or with bytes that are no message. The client says so,
naming the key and — for an error reply — the answerer's reason on one printable line;
the shell prints that as one error line (never "internal error" and an exception's class),
a command or a login is refused with it, a view or an OPC UA face that cannot get its
chart says why, and a chart whose parts change under the reader is read again from its
head."""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterator

import pytest
import zenoh

from s7graph.web.bus.client import REASON_CHARS, BusClient, ErrorReply, find_cpus, unread_note
from s7graph.web.bus.protocol import (
    ActionInfo,
    ChartLayout,
    Command,
    CpuStatus,
    ProtocolError,
    StepInfo,
    encode,
    split_layout,
)
from s7graph.web.bus.session import open_session
from s7graph.web.cli import main
from tests.web.helpers import free_port

pytestmark = pytest.mark.timeout(120)

Answer = Callable[[zenoh.Query], None]


@pytest.fixture
def odd() -> Iterator[tuple[str, list[Answer]]]:
    """A peer listening on loopback that answers queries of ``s7graph/odd/**`` with the
    answer in the list (replace it to change how it answers); its endpoint."""
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    how: list[Answer] = [lambda q: q.reply_err(b"no")]
    with open_session(listen=[endpoint]) as peer:
        peer.declare_queryable("s7graph/odd/**", lambda q: how[0](q))
        yield endpoint, how


@pytest.fixture
def client(odd: tuple[str, list[Answer]]) -> Iterator[BusClient]:
    with open_session(connect=[odd[0]]) as session, BusClient(session, "odd") as c:
        yield c


def _refuse(reason: bytes) -> Answer:
    return lambda q: q.reply_err(reason)


def test_an_error_reply_names_the_key_and_gives_the_reason_on_one_line(
    odd: tuple[str, list[Answer]], client: BusClient
) -> None:
    odd[1][0] = _refuse(b"out of\x1b[31m order\n\tnow")
    with pytest.raises(ErrorReply) as got:
        client.status()
    assert (
        str(got.value)
        == "s7graph/odd/status: the CPU answered with an error: out of [31m order now"
    )
    with pytest.raises(ErrorReply, match=r"^s7graph/odd/diag: .*out of"):  # no ?n= in the key
        client.diag(5)
    odd[1][0] = _refuse(b"x" * 100_000)
    with pytest.raises(ErrorReply) as long:
        client.alarms()
    assert str(long.value).endswith("x…")
    assert len(str(long.value).partition("error: ")[2]) == REASON_CHARS


def test_an_answer_that_is_no_message_names_the_key(
    odd: tuple[str, list[Answer]], client: BusClient
) -> None:
    odd[1][0] = lambda q: q.reply(q.key_expr, b'{"cpu": ')
    with pytest.raises(ProtocolError, match=r"^s7graph/odd/status: unreadable answer: malformed"):
        client.status()
    with pytest.raises(ProtocolError, match=r"^s7graph/odd/fb/F/state: unreadable answer"):
        client.state("F")
    reply = client.send(Command(op="init", fb="F", user="u", token="t"))
    assert not reply.applied and reply.op == "init"
    assert reply.reason.startswith("s7graph/odd/cmd: unreadable answer: malformed JSON")
    login = client.login("olga", "secret")
    assert login.reason.startswith("s7graph/odd/login: unreadable answer: malformed JSON")
    assert client.watch(["M0.0"]).error.startswith("s7graph/odd/watch: unreadable answer")


def test_a_command_a_login_a_watch_refused_by_an_error_reply_carry_its_reason(
    odd: tuple[str, list[Answer]], client: BusClient
) -> None:
    odd[1][0] = _refuse(b"busy")
    reply = client.send(Command(op="init", fb="F", user="u", token="t"))
    assert not reply.applied and reply.op == "init" and reply.fb == "F"
    assert reply.reason == "s7graph/odd/cmd: the CPU answered with an error: busy"
    login = client.login("olga", "secret")
    assert not login.ok and login.reason.endswith("the CPU answered with an error: busy")
    assert "ErrorReply" not in login.reason
    assert client.watch(["M0.0"]).error == "s7graph/odd/watch: the CPU answered with an error: busy"
    assert client.synchronization("F").error.endswith(": busy")


@pytest.mark.parametrize(
    ("answer", "said"),
    [
        (_refuse(b"go away"), "the CPU answered with an error: go away"),
        (lambda q: q.reply(q.key_expr, b'{"cpu": '), "unreadable answer: malformed JSON"),
    ],
    ids=["error reply", "no message"],
)
def test_the_shell_prints_one_error_line_naming_the_key(
    odd: tuple[str, list[Answer]],
    answer: Answer,
    said: str,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    odd[1][0] = answer
    monkeypatch.setenv("S7GRAPH_BUS_PASSWORD", "x")
    asked = {"status": "status", "diag": "diag", "sync": "status", "mode": "status"}
    for command, key in asked.items():
        more = ["MAN", "--user", "op"] if command == "mode" else []
        assert main([command, *more, "--connect", odd[0], "--cpu", "odd"]) == 2
        err = capsys.readouterr().err
        assert err.startswith(f"s7graph: error: s7graph/odd/{key}: {said}"), err
        assert err.count("\n") == 1 and "internal error" not in err, err


def test_a_chart_whose_parts_change_while_read_is_read_again_from_its_head(
    odd: tuple[str, list[Answer]], client: BusClient
) -> None:
    row = ActionInfo(qualifier="N", operand="M0.0" + " " * 4000)
    steps = [StepInfo(number=n, name=f"S{n}", actions=[row] * 10) for n in range(1, 50)]
    first = ChartLayout(fb="F", version=1, steps=steps, transitions=[], sequences=[])
    head, parts = split_layout(first, limit=100_000)
    assert len(parts) > 1
    second = ChartLayout(fb="F", version=2, steps=steps[:1], transitions=[], sequences=[])
    heads = [encode(head), encode(second)]  # the chart as asked the first time, the second
    lock = threading.Lock()

    def answer(q: zenoh.Query) -> None:
        key = str(q.key_expr)
        if key.endswith("/chart"):
            with lock:
                data = heads.pop(0) if len(heads) > 1 else heads[0]
            q.reply(q.key_expr, data)
        elif key.endswith("/chart/part"):
            k = int(zenoh.Parameters(str(q.parameters)).get("k") or 0)
            if k == 0:
                q.reply(q.key_expr, encode(parts[0]))
            else:  # the CPU runs version 2 now: one part only, none at all
                q.reply_err(b"?k=1: give a part, 0 to 0")

    odd[1][0] = answer
    assert client.chart("F") == second
    assert len(heads) == 1  # the head in parts was read first, then the new one


def test_a_peer_that_keeps_silent_is_no_answer_not_an_error_reply(
    odd: tuple[str, list[Answer]],
) -> None:
    """zenoh ends a query whose wait is up with an error reply of its own ("Timeout", from
    no replier): that stays *no answer*."""
    held: list[zenoh.Query] = []
    odd[1][0] = held.append
    with open_session(connect=[odd[0]]) as session, BusClient(session, "odd", timeout=0.3) as c:
        assert c.status() is None and held
        reply = c.send(Command(op="init", fb="F", user="u", token="t"))
        assert reply.reason == "no answer from CPU 'odd' within 0.3 s"


def _a_cpu_whose_chart_is_refused(q: zenoh.Query) -> None:
    if str(q.key_expr).endswith("/status"):
        q.reply(q.key_expr, encode(CpuStatus(cpu="odd", fbs=["F"])))
    else:
        q.reply_err(b"not now")


def test_a_view_and_an_opcua_face_of_a_cpu_whose_chart_is_refused_say_why(
    odd: tuple[str, list[Answer]], capsys: pytest.CaptureFixture[str]
) -> None:
    pytest.importorskip("asyncua")
    odd[1][0] = _a_cpu_whose_chart_is_refused
    why = "s7graph/odd/fb/F/chart: the CPU answered with an error: not now"
    face = ["opcua", "--listen", f"opc.tcp://127.0.0.1:{free_port()}", "--duration-s", "1"]
    assert main([*face, "--connect", odd[0], "--cpu", "odd"]) == 2
    assert capsys.readouterr().err == f"s7graph: error: cannot serve OPC UA of CPU odd: {why}\n"
    view = ["web", "--port", "0", "--duration-s", "1", "--connect", odd[0], "--cpu", "odd"]
    assert main(view) == 2
    err = capsys.readouterr().err
    assert err.endswith(f"within 5 s (last answer: {why})\n") and "internal error" not in err


def test_looking_for_cpus_says_which_answers_it_could_not_read(
    odd: tuple[str, list[Answer]],
) -> None:
    """``s7graph web`` and ``s7graph opcua`` end their "no CPU answers" with it."""
    with open_session(connect=[odd[0]]) as session:
        for answer, said in (
            (lambda q: q.reply("s7graph/odd/status", b"{"), "s7graph/odd/status: unreadable"),
            (_refuse(b"no\\tstatus"), "an error reply: no\\tstatus"),
        ):
            odd[1][0] = answer
            unreadable: list[str] = []
            assert find_cpus(session, timeout=1, unreadable=unreadable) == []
            assert len(unreadable) == 1 and unreadable[0].startswith(said), unreadable
            assert unread_note(unreadable) == f"; an answer could not be read: {unreadable[0]}"
        odd[1][0] = lambda q: q.reply("s7graph/odd/status", encode(CpuStatus(cpu="odd")))
        unreadable = []
        assert [s.cpu for s in find_cpus(session, unreadable=unreadable)] == ["odd"]
        assert unreadable == [] and unread_note(unreadable) == ""
    assert unread_note(["a", "b", "c"]) == "; an answer could not be read: a (and 2 more)"


def test_a_read_the_cpu_cannot_answer_is_an_error_reply_with_the_reason(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A CPU whose audit cannot be read (its disk fails) answers ``audit/list`` with an error
    reply naming the key and SQLite's words — the asker hears why, not a silence."""
    import sqlite3

    from s7graph.web.bus.cpu_side import CpuSide

    side = CpuSide({}, cpu="cpu1")
    try:

        def broken() -> object:
            raise sqlite3.OperationalError("disk I/O error")

        monkeypatch.setattr(side.publisher.gate, "audit_list", broken)
        with open_session(connect=[side.endpoint]) as session, pytest.raises(ErrorReply) as got:
            BusClient(session, "cpu1").audit()
        assert "cannot read s7graph/cpu1/audit/list: disk I/O error" in str(got.value)
    finally:
        side.close()


def test_a_bus_that_fails_under_a_question_is_said_in_words() -> None:
    """zenoh's own error (here: the session closed under the client) names the key asked
    and what the bus said, never the exception's class name."""
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    with open_session(listen=[endpoint]) as session:
        client = BusClient(session, "cpu1")
        session.close()
        answer = client.watch(["MW0"], timeout=1)
    assert answer.error == "s7graph/cpu1/watch: bus error: session closed"
