"""Log a user in at a :class:`~s7graph.web.bus.gate.Gate` in this process, as a client
does over the bus: the whole SCRAM exchange through ``Gate.login``."""

from __future__ import annotations

from s7graph.web.access.scram import Signer, log_in
from s7graph.web.bus.gate import Gate
from s7graph.web.bus.protocol import LoginReply, LoginRequest


def gate_login(
    gate: Gate, user: str, password: str, *, origin: str = ""
) -> tuple[LoginReply, Signer | None]:
    """The gate's last answer and, once logged in, the session's signer (the client
    giving up — a wrong server signature — fails the test)."""

    def ask(scram: str, login_id: str) -> LoginReply:
        op = "proof" if login_id else "login"
        request = LoginRequest(op=op, user=user, scram=scram, login_id=login_id, origin=origin)
        return gate.login(request)

    answer, signer = log_in(user, password, ask)
    assert not isinstance(answer, str), answer
    return answer, signer
