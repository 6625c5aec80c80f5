"""SCRAM-SHA-256 logins (RFC 5802, RFC 7677, through the ``scramp`` library) and the
session key that signs a logged-in client's commands.

**What is stored.** A user's entry in the users file is a SCRAM verifier in PostgreSQL's
form, ``SCRAM-SHA-256$<iterations>:<salt>$<StoredKey>:<ServerKey>`` (base64):
:class:`Verifier`, made by :func:`make_verifier` with ``scramp``'s
``ScramMechanism.make_auth_info``. It lets the CPU check a proof and prove itself, yet
is no password: logging in needs the ClientKey, which only the password gives.

**The exchange.** :class:`ClientLogin` (the shell, the view) and :class:`ServerLogin`
(the CPU) pass the four SCRAM messages: client-first (user, client nonce), server-first
(combined nonce, salt, iterations), client-final (the proof), server-final (the server's
signature). The password never leaves the client; the client checks the server's
signature, so a CPU that does not hold the verifier — a fake one — is found out.

**The session key.** Both ends then derive ``K = HMAC-SHA256(StoredKey, "s7graph
session" + AuthMessage)``: the client from the password, the CPU from the verifier; a
listener on the bus has neither. :class:`Signer` (the client's side of a session) numbers
each command (``seq``) and signs it with ``mac = HMAC-SHA256(K, command_bytes(command))``;
the CPU recomputes it (``web.access.login.Authenticator.verify``).

**Iterations.** :data:`DEFAULT_ITERATIONS` is 100,000 PBKDF2-HMAC-SHA256 rounds. The
CPU never runs them (SCRAM's server side is a few HMACs), so the count is no lever on
the CPU; the client pays them twice per login (the proof, then the session key: about
45 ms on one core of the test machine, as the scrypt check it replaces), and so does
anyone who guesses passwords against a copied users file or a captured exchange. PostgreSQL's
default of 4,096 is cheap to attack offline; OWASP's 600,000 would make every shell
command wait a quarter of a second. Tests make users with :data:`MIN_ITERATIONS` (the
RFC's minimum, which ``scramp`` enforces) to stay fast.
"""

from __future__ import annotations

import base64
import binascii
import hashlib
import hmac
import threading
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Final, Protocol, TypeVar

import msgspec
from msgspec import UNSET
from scramp import ScramClient, ScramException, ScramMechanism

from s7graph.web.commands import Command

__all__ = [
    "DEFAULT_ITERATIONS",
    "MAX_ITERATIONS",
    "MECHANISM",
    "MIN_ITERATIONS",
    "ClientLogin",
    "LoginError",
    "ServerLogin",
    "Signer",
    "Verifier",
    "command_bytes",
    "fake_verifier",
    "log_in",
    "logout_bytes",
    "make_verifier",
    "password_matches",
    "sign",
]

MECHANISM: Final = "SCRAM-SHA-256"
DEFAULT_ITERATIONS: Final = 100_000
MIN_ITERATIONS: Final = 4096  # RFC 7677's minimum; scramp refuses fewer
MAX_ITERATIONS: Final = 1_000_000  # more is refused: a fake CPU must not stall a client
_SESSION: Final = b"s7graph session"
_COMMAND: Final = b"s7graph command\n"
_LOGOUT: Final = b"s7graph logout\n"
_PREFIX: Final = f"{MECHANISM}$"


class LoginError(ValueError):
    """A login message that is malformed, or a proof or signature that is wrong."""


def _b64(data: bytes) -> str:
    return base64.b64encode(data).decode()


def _unb64(text: str) -> bytes:
    return base64.b64decode(text, validate=True)


@dataclass(frozen=True, slots=True)
class Verifier:
    """What the users file keeps of a password: salt, iterations, StoredKey, ServerKey."""

    iterations: int
    salt: bytes
    stored_key: bytes
    server_key: bytes

    @property
    def text(self) -> str:
        """PostgreSQL's form: ``SCRAM-SHA-256$i:salt$StoredKey:ServerKey``."""
        head = f"{self.iterations}:{_b64(self.salt)}"
        return f"{_PREFIX}{head}${_b64(self.stored_key)}:{_b64(self.server_key)}"

    @classmethod
    def parse(cls, text: str) -> Verifier:
        """The verifier ``text`` holds; ``ValueError`` saying why it is none."""
        try:
            scheme, head, keys = text.split("$")
            count, salt = head.split(":")
            stored, server = keys.split(":")
            made = cls(int(count), _unb64(salt), _unb64(stored), _unb64(server))
        except (ValueError, binascii.Error):
            raise ValueError("not a SCRAM-SHA-256 verifier") from None
        if scheme != MECHANISM or not MIN_ITERATIONS <= made.iterations <= MAX_ITERATIONS:
            raise ValueError(f"not a {MECHANISM} verifier of {MIN_ITERATIONS}+ iterations")
        if len(made.salt) < 12 or len(made.stored_key) != 32 or len(made.server_key) != 32:
            raise ValueError("a SCRAM-SHA-256 verifier with keys of the wrong size")
        return made


def make_verifier(
    password: str, *, iterations: int = DEFAULT_ITERATIONS, salt: bytes | None = None
) -> Verifier:
    """The verifier of ``password`` (``scramp``'s ``make_auth_info``); ``LoginError`` for a
    password SASLprep refuses (control characters, unassigned code points)."""
    if not MIN_ITERATIONS <= iterations <= MAX_ITERATIONS:
        raise LoginError(f"iterations: {MIN_ITERATIONS} to {MAX_ITERATIONS}")
    try:
        info: Any = ScramMechanism(MECHANISM).make_auth_info(
            password, iteration_count=iterations, salt=salt
        )
    except ScramException as exc:
        raise LoginError(f"this password cannot be used: {_plain(exc)}") from None
    made_salt, stored_key, server_key, count = info
    return Verifier(int(count), bytes(made_salt), bytes(stored_key), bytes(server_key))


def password_matches(password: str, verifier: Verifier) -> bool:
    """Whether ``password`` gives ``verifier`` (a local check; logins use the exchange)."""
    try:
        again = make_verifier(password, iterations=verifier.iterations, salt=verifier.salt)
    except LoginError:
        return False
    return hmac.compare_digest(again.stored_key, verifier.stored_key)


def fake_verifier(secret: bytes, user: str) -> Verifier:
    """A verifier for a name nobody has: the same salt for the same name at every try, so
    the answer does not tell an unknown name from a known one; no proof matches it."""

    def part(label: bytes) -> bytes:
        return hmac.new(secret, label + b"\0" + user.encode(), hashlib.sha256).digest()

    return Verifier(DEFAULT_ITERATIONS, part(b"salt"), part(b"stored"), part(b"server"))


# ---------------------------------------------------------------- signing


def sign(key: bytes, message: bytes) -> str:
    """``HMAC-SHA256(key, message)`` as 64 hex digits."""
    return hmac.new(key, message, hashlib.sha256).hexdigest()


def command_bytes(command: Command) -> bytes:
    """What a command's ``mac`` signs: its JSON without ``mac`` and with ``origin`` "". The
    origin is the sender's note for the audit (the CPU may set it from the transport);
    everything the CPU acts on — op, FB, user, token, ``seq``, arguments — is signed."""
    return _COMMAND + msgspec.json.encode(msgspec.structs.replace(command, mac=UNSET, origin=""))


def logout_bytes(token: str) -> bytes:
    """What a logout's ``mac`` signs: a listener who saw a token cannot log it out."""
    return _LOGOUT + token.encode()


def _session_key(stored_key: bytes, auth_message: str) -> bytes:
    return hmac.new(stored_key, _SESSION + auth_message.encode(), hashlib.sha256).digest()


def _auth_message(client_first: str, server_first: str, client_final: str) -> str:
    """RFC 5802's AuthMessage: client-first-bare, server-first, client-final without proof."""
    bare = client_first.split(",", 2)[2]
    without_proof = client_final.rpartition(",p=")[0]
    return f"{bare},{server_first},{without_proof}"


def _attributes(message: str) -> dict[str, str]:
    return dict(part.split("=", 1) for part in message.split(",") if "=" in part)


def _plain(exc: ScramException) -> str:
    return str(exc.args[0]) if exc.args else "the SCRAM exchange failed"


class Signer:
    """A logged-in client's side of one session: numbers and signs its commands.

    ``seq`` starts at 1 and grows under a lock, so threads sharing a session (a page's
    buttons) never send one number twice. Without a key (the demo) commands are numbered
    and left unsigned."""

    def __init__(self, user: str, token: str, key: bytes = b"") -> None:
        self.user = user
        self.token = token
        self._key = key
        self._seq = 0
        self._lock = threading.Lock()

    def __repr__(self) -> str:  # never the key
        return f"Signer({self.user!r}, seq={self._seq})"

    def sign(self, command: Command) -> Command:
        """``command`` with the next ``seq`` and, with a key, its ``mac``: :meth:`numbered`
        with the command's bytes, the one signing path."""

        def at(seq: int) -> Command:
            return msgspec.structs.replace(command, seq=seq, mac=UNSET)

        seq, mac = self.numbered(lambda seq: command_bytes(at(seq)))
        return msgspec.structs.replace(at(seq), mac=mac or UNSET)

    def numbered(self, message: Callable[[int], bytes]) -> tuple[int, str]:
        """The next ``seq`` and, with a key, the ``mac`` of ``message(seq)`` ("" in the
        demo): a request other than a command signed by this session (a watch)."""
        with self._lock:
            self._seq += 1
            seq = self._seq
        return seq, sign(self._key, message(seq)) if self._key else ""

    def logout_mac(self) -> str:
        """The ``mac`` of this session's logout ("" in the demo)."""
        return sign(self._key, logout_bytes(self.token)) if self._key else ""


# ---------------------------------------------------------------- the two ends


MAX_PASSWORD: Final = 1024
"""The longest password (a users file's rule too): a longer one is refused before its key
derivation, whose time grows with its length."""


class ClientLogin:
    """The client's end of one SCRAM exchange: :meth:`first`, :meth:`final` with the
    CPU's challenge, :meth:`verify` with its answer (the session key)."""

    def __init__(self, user: str, password: str) -> None:
        if len(password) > MAX_PASSWORD:  # refused before any work: no client holds a face up
            raise LoginError(f"a password has at most {MAX_PASSWORD:,} characters")
        try:
            self._client: Any = ScramClient([MECHANISM], user, password)
        except ScramException as exc:
            raise LoginError(f"this password cannot be used: {_plain(exc)}") from None
        self._password = password
        self._first = ""
        self._key = b""

    def first(self) -> str:
        """The client-first message: ``n,,n=<user>,r=<client nonce>``."""
        self._first = str(self._client.get_client_first())
        return self._first

    def final(self, server_first: str) -> str:
        """The client-final message (the proof) for the CPU's ``server_first``."""
        fields = _attributes(server_first)
        try:
            iterations = int(fields.get("i", ""))
            salt = _unb64(fields.get("s", ""))
        except (ValueError, binascii.Error):
            raise LoginError("the CPU's challenge is unreadable") from None
        if not MIN_ITERATIONS <= iterations <= MAX_ITERATIONS:
            raise LoginError(
                f"the CPU asks for {iterations} iterations ({MIN_ITERATIONS} to "
                f"{MAX_ITERATIONS} are taken)"
            )
        try:
            self._client.set_server_first(server_first)
            final = str(self._client.get_client_final())
        except ScramException as exc:
            raise LoginError(f"the CPU's challenge is refused: {_plain(exc)}") from None
        stored = make_verifier(self._password, iterations=iterations, salt=salt).stored_key
        self._password = ""
        self._key = _session_key(stored, _auth_message(self._first, server_first, final))
        return final

    def verify(self, server_final: str) -> bytes:
        """The session key, once ``server_final`` proves the CPU holds the verifier."""
        try:
            self._client.set_server_final(server_final)
        except ScramException:
            raise LoginError(
                "the CPU did not prove it knows the password (wrong server signature): "
                "not the CPU of this users file; its token is not used"
            ) from None
        return self._key


class ServerLogin:
    """The CPU's end of one SCRAM exchange against ``verifier`` (a real or a fake one)."""

    def __init__(self, user: str, verifier: Verifier) -> None:
        self.user = user
        self._verifier = verifier
        self._named = ""
        self._first = ""
        self._server_first = ""
        self._server: Any = ScramMechanism(MECHANISM).make_server(self._lookup)

    def _lookup(self, name: str) -> tuple[bytes, bytes, bytes, int]:
        self._named = name
        v = self._verifier
        return v.salt, v.stored_key, v.server_key, v.iterations

    def first(self, client_first: str) -> str:
        """The server-first message for ``client_first`` (which must name :attr:`user`)."""
        try:
            self._server.set_client_first(client_first)
            server_first = str(self._server.get_server_first())
        except ScramException as exc:
            raise LoginError(f"unreadable login message: {_plain(exc)}") from None
        if self._named != self.user:
            raise LoginError("the login message names another user")
        self._first, self._server_first = client_first, server_first
        return server_first

    def final(self, client_final: str) -> tuple[str, bytes]:
        """The server-final message and the session key, if ``client_final``'s proof is
        right; ``LoginError`` if not."""
        try:
            self._server.set_client_final(client_final)
            server_final = str(self._server.get_server_final())
        except ScramException as exc:
            raise LoginError(_plain(exc)) from None
        message = _auth_message(self._first, self._server_first, client_final)
        return server_final, _session_key(self._verifier.stored_key, message)


class _Answer(Protocol):
    """One step's answer, from the CPU's ``LoginReply`` or an in-process ``LoginResult``."""

    @property
    def ok(self) -> bool: ...
    @property
    def token(self) -> str: ...
    @property
    def verified(self) -> bool: ...
    @property
    def login_id(self) -> str: ...
    @property
    def scram(self) -> str: ...


A = TypeVar("A", bound=_Answer)


def log_in(user: str, password: str, ask: Callable[[str, str], A]) -> tuple[A | str, Signer | None]:
    """Drive one login as the client: ``ask(scram, login_id)`` sends one step (``login_id``
    "" for the first) and gives the CPU's answer. Returns the last answer and, once logged
    in, the session's :class:`Signer`; or, instead of an answer, why the client itself
    gave up (a password SASLprep refuses, an unreadable challenge, a wrong server
    signature — then the token is not used). Without a password the first step is the
    whole login (the demo)."""
    if not password:
        answer = ask("", "")
        return answer, (Signer(user, answer.token) if answer.ok else None)
    try:
        client = ClientLogin(user, password)
    except LoginError as exc:
        return str(exc), None
    first = ask(client.first(), "")
    if first.ok:  # a CPU without users file takes the name alone: unverified
        if first.verified:
            return "the CPU logged in without checking the password: not a real CPU", None
        return first, Signer(user, first.token)
    if not first.login_id:
        return first, None
    try:
        final = client.final(first.scram)
    except LoginError as exc:
        return str(exc), None
    answer = ask(final, first.login_id)
    if not answer.ok:
        return answer, None
    try:
        key = client.verify(answer.scram)
    except LoginError as exc:
        return str(exc), None
    return answer, Signer(user, answer.token, key)
