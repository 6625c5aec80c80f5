"""Who an OPC UA client is, and what one session may ask of the face (docs/opcua.md,
"Security").

:class:`BusUsers` is the server's user manager: a user name and password are checked by
logging that user in at the CPU over the bus (``BusClient.login``: the CPU checks the
password against its users file and audits the login), so the face never reads a password
hash; each OPC UA session keeps the bus token of its own login in its
:class:`FaceUser`, logged out when the session closes. An anonymous session is a viewer
(read, browse, subscribe) or refused. :class:`FaceSession` bounds what one request and
one session may ask for (:class:`Limits`) — more operations, subscriptions or monitored
items than that are answered with a bad status code, never served — and paces them
(:class:`Pace`: a request asked faster than its session's or the server's share waits
before it is served); :class:`FaceServer` makes every session one of them and serves no
RegisterServer. :class:`FaceRules` lets no client change the address space's structure.
"""

from __future__ import annotations

import asyncio
import contextvars
import copy
import dataclasses
import logging
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Final

from asyncua import ua
from asyncua.common.utils import ServiceError
from asyncua.crypto.permission_rules import USER_TYPES, PermissionRuleset, User, UserRole
from asyncua.server.internal_server import InternalServer
from asyncua.server.internal_session import InternalSession
from asyncua.server.user_managers import UserManager

from s7graph.web.access.lockout import Lockout
from s7graph.web.opcua.model import INT_VARIANTS
from s7graph.web.opcua.paging import Pages, masked
from s7graph.web.opcua.ranges import follow_ranges, item_problem, read_ranges, write_problem
from s7graph.web.opcua.statuses import call_problem, fix_browse, fix_translate, missing
from s7graph.web.opcua.typed import (
    AttributeIds,
    ObjectIds,
    StatusCodes,
    data_value,
    ua_id,
    ua_status,
)

__all__ = [
    "CALLER",
    "BusUsers",
    "FaceRules",
    "FaceServer",
    "FaceSession",
    "FaceUser",
    "Limits",
    "Pace",
    "caller",
]

_log = logging.getLogger("s7graph.web.opcua")


@dataclass
class FaceUser(User):
    """A session's user logged in at the CPU: the role the CPU gave, the token its
    commands carry, whether the name was verified (a users file), the bus client of this
    session's own login, and where the session came from (for the audit)."""

    role: UserRole = UserRole.User
    bus_role: str = ""
    token: str = field(default="", repr=False)
    verified: bool = True
    client: Any = field(default=None, repr=False)
    origin: str = ""


CALLER: Final[contextvars.ContextVar[User | None]] = contextvars.ContextVar(
    "s7graph_opcua_caller", default=None
)
"""The user of the session whose call is being served (set around a Call request)."""
_ACTIVATING: Final[contextvars.ContextVar[str]] = contextvars.ContextVar(
    "s7graph_opcua_peer", default=""
)


def caller() -> User:
    """The user of the call being served (anonymous when none)."""
    return CALLER.get() or User(role=UserRole.Anonymous)


Login = Callable[[str, str, str], "FaceUser | str"]
"""``login(user, password, origin)``: the user logged in at the CPU, or why not."""


HOST_FAILURES: Final = 10
"""Wrong logins from one host before the face refuses its next ones unchecked for a while
(:data:`HOST_LOCKOUT_S`, doubling up to :data:`HOST_LONGEST_S`)."""
HOST_LOCKOUT_S: Final = 10.0
HOST_LONGEST_S: Final = 300.0
_NOT_A_GUESS: Final = ("no answer", "bus error", "answered with an error", "unreadable answer")
"""Words of a login refused by the bus, not by the CPU: not counted against the host."""


class BusUsers(UserManager):
    """User name and password checked by the CPU (``login``); anonymous sessions allowed
    read-only (``anonymous``) or refused.

    asyncua activates a session without yielding, and a login with a password the face
    has not seen costs its SCRAM key derivation (tens of ms): a host that sends
    :data:`HOST_FAILURES` wrong logins is refused unchecked for a while, whatever user it
    names, so that nobody holds up the face's other clients by guessing passwords."""

    def __init__(self, login: Login, *, anonymous: bool) -> None:
        self._login = login
        self.anonymous = anonymous
        self.hosts = Lockout(
            max_failures=HOST_FAILURES, lockout_s=HOST_LOCKOUT_S, longest_s=HOST_LONGEST_S
        )

    def get_user(
        self,
        iserver: InternalServer,
        username: str | None = None,
        password: str | None = None,
        certificate: Any = None,
    ) -> User | None:
        peer = _ACTIVATING.get()
        if username is None:
            if self.anonymous:
                return User(role=UserRole.Anonymous)
            _log.info("opcua: anonymous session from %s refused", peer or "?")
            return None
        origin = f"opcua {peer}".strip()[:160]
        host = peer.rsplit(":", 1)[0] if peer else "?"
        wait = self.hosts.locked_for("", host)
        if wait:
            why = f"{HOST_FAILURES} wrong logins from this host: try again in {math.ceil(wait)} s"
            _log.info("opcua: login of %r from %s refused: %s", username[:32], peer, why)
            return None
        try:
            result = self._login(username, password or "", origin)
        except Exception:  # the bus went away: refused, never a crash, and not a guess
            _log.info("opcua: login of %r from %s refused: no answer", username[:32], peer)
            return None
        if isinstance(result, str):
            if not any(w in result for w in _NOT_A_GUESS):  # the CPU's "no", not the bus's
                self.hosts.failed("", host)
            _log.info("opcua: login of %r from %s refused: %s", username[:32], peer, result)
            return None
        self.hosts.succeeded("", host)
        return result


class FaceRules(PermissionRuleset):
    """Every user may use the session services (read, browse, subscribe, write, call —
    what a write or a call may do is the CPU's gate's to decide); nobody may add or
    delete nodes or references, or register servers."""

    def __init__(self) -> None:
        browse_next = ObjectIds.BrowseNextRequest_Encoding_DefaultBinary  # web.opcua.paging
        self._allowed = frozenset(ua_id(t) for t in (*USER_TYPES, browse_next))

    def check_validity(self, user: Any, action_type_id: Any, body: Any) -> bool:
        return action_type_id in self._allowed


@dataclass(frozen=True, slots=True)
class Limits:
    """What one request and one session may ask for; past it, a bad status code. And
    how fast requests are served: ``pace`` units of work a second for one session (a
    value read, browsed or written: 1; a monitored item made: 5; a method call or a
    subscription made or deleted: 50), ``server_pace`` for all of them together, each with
    a second's worth at once; a request asked faster waits before it is served, so no
    client can take the face from the others or from the bus, and a flood of them leaves
    the event loop time to carry the CPU's changes to the subscriptions."""

    operations: int = 1000  # nodes to read, browse, write, methods to call per request
    subscriptions: int = 20  # per session
    monitored_items: int = 5000  # per session
    sessions: int = 64  # activated sessions of the server
    connections: int = 128  # TCP connections, activated or not
    min_publishing_ms: float = 10.0
    max_publishing_ms: float = 3_600_000.0
    pace: float = 5000.0
    server_pace: float = 20_000.0


COST_CALL: Final = 50
COST_ITEM: Final = 5
COST_SUBSCRIPTION: Final = 50
MAX_WAIT_S: Final = 1.0


class Pace:
    """A token bucket: ``rate`` units a second, at most ``burst`` saved up."""

    def __init__(self, rate: float, burst: float) -> None:
        self.rate = rate
        self.burst = burst
        self._tokens = burst
        self._at = time.monotonic()

    def wait(self, cost: float) -> float:
        """Take ``cost`` units; the seconds to wait first (0: none)."""
        now = time.monotonic()
        self._tokens = min(self.burst, self._tokens + (now - self._at) * self.rate) - cost
        self._at = now
        return 0.0 if self._tokens >= 0 else min(-self._tokens / self.rate, MAX_WAIT_S)


def _bounded(count: int, limit: int) -> None:
    """``BadTooManyOperations`` for a request of more than ``limit`` operations."""
    if count > limit:
        raise ServiceError(StatusCodes.BadTooManyOperations)


class FaceSession(InternalSession):
    """An OPC UA session of the face: bounded and paced requests, the caller known to
    methods, the bus token logged out when it closes."""

    _pace: Pace | None = None
    _pages: Pages | None = None

    @property
    def limits(self) -> Limits:
        server = self.iserver
        return server.limits if isinstance(server, FaceServer) else Limits()

    async def _serve(self, count: int, cost: float) -> None:
        """A request of ``count`` operations costing ``cost``: refused when it has too
        many, served after a wait when this session asks faster than its pace."""
        _bounded(count, self.limits.operations)
        limits = self.limits
        if self._pace is None:
            self._pace = Pace(limits.pace, limits.pace)
        delay = self._pace.wait(cost)
        server = self.iserver
        if isinstance(server, FaceServer):
            if server.pace is None:
                server.pace = Pace(limits.server_pace, limits.server_pace)
            delay = max(delay, server.pace.wait(cost))
        if delay:
            await asyncio.sleep(delay)

    def activate_session(
        self, params: ua.ActivateSessionParameters, peer_certificate: bytes | None
    ) -> ua.ActivateSessionResult:
        before = self.user
        peer = self.name
        shown = f"{peer[0]}:{peer[1]}" if isinstance(peer, tuple) and len(peer) >= 2 else ""
        mark = _ACTIVATING.set(shown)
        try:
            result = super().activate_session(params, peer_certificate)
        finally:
            _ACTIVATING.reset(mark)
        if before is not self.user and isinstance(before, FaceUser):
            self._closed(before)  # the session changed its user: the old login ends
        return result

    async def close_session(self, delete_subs: bool = True) -> None:
        await super().close_session(delete_subs)
        self._closed(self.user)

    def _closed(self, user: User) -> None:
        server = self.iserver
        hook = server.on_close if isinstance(server, FaceServer) else None
        if hook is not None and isinstance(user, FaceUser):
            hook(user)

    async def read(self, params: ua.ReadParameters) -> list[ua.DataValue]:
        await self._serve(len(params.NodesToRead), len(params.NodesToRead))
        values = read_ranges(params.NodesToRead, await super().read(params))
        values = [
            data_value(code=StatusCodes.BadNodeIdInvalid) if _null(asked.NodeId) else value
            for asked, value in zip(params.NodesToRead, values, strict=False)
        ]
        if not isinstance(self.user, FaceUser):  # anonymous: nothing to write or call
            values = [
                _read_only(asked.AttributeId, value)
                for asked, value in zip(params.NodesToRead, values, strict=False)
            ]
        return values

    async def write(self, params: ua.WriteParameters) -> list[ua.StatusCode]:
        await self._serve(len(params.NodesToWrite), len(params.NodesToWrite))
        problems = [
            StatusCodes.BadNodeIdInvalid if _null(w.NodeId) else write_problem(w)
            for w in params.NodesToWrite
        ]
        if not any(problems):
            return await super().write(params)
        fitting = copy.copy(params)
        fitting.NodesToWrite = [
            w for w, p in zip(params.NodesToWrite, problems, strict=True) if p is None
        ]
        done = iter(await super().write(fitting) if fitting.NodesToWrite else [])
        return [next(done) if p is None else ua_status(p) for p in problems]

    async def browse(self, params: ua.BrowseParameters) -> list[ua.BrowseResult]:
        await self._serve(len(params.NodesToBrowse), len(params.NodesToBrowse))
        results = await super().browse(params)
        fix_browse(self.aspace, params.NodesToBrowse, results)
        masked(params.NodesToBrowse, results)
        self.pages.browsed(params.RequestedMaxReferencesPerNode, results)
        return results

    async def browse_next(self, parameters: ua.BrowseNextParameters) -> list[ua.BrowseResult]:
        """The next pages of a Browse, or the points released (``web.opcua.paging``)."""
        points = parameters.ContinuationPoints or []
        await self._serve(len(points), len(points))
        return self.pages.next(parameters)

    @property
    def pages(self) -> Pages:
        """This session's continuation points."""
        if self._pages is None:
            self._pages = Pages()
        return self._pages

    async def translate_browsepaths_to_nodeids(
        self, params: list[ua.BrowsePath]
    ) -> list[ua.BrowsePathResult]:
        await self._serve(len(params), len(params))
        results = await super().translate_browsepaths_to_nodeids(params)
        fix_translate(self.aspace, params, results)
        return results

    async def register_nodes(self, nodes: list[ua.NodeId]) -> list[ua.NodeId]:
        await self._serve(len(nodes), len(nodes))
        return await super().register_nodes(nodes)

    async def history_read(self, params: ua.HistoryReadParameters) -> list[ua.HistoryReadResult]:
        raise ServiceError(StatusCodes.BadHistoryOperationUnsupported)

    async def call(self, params: list[ua.CallMethodRequest]) -> list[ua.CallMethodResult]:
        """The calls of a request; one naming no object or no method is answered here
        (``web.opcua.statuses.call_problem``), the others by their methods."""
        await self._serve(len(params), len(params) * COST_CALL)
        problems = [self._call_problem(request) for request in params]
        served = [r for r, p in zip(params, problems, strict=True) if p is None]
        mark = CALLER.set(self.user)
        try:
            done = iter(await super().call(served) if served else [])
        finally:
            CALLER.reset(mark)
        return [next(done) if p is None else p for p in problems]

    def _call_problem(self, request: ua.CallMethodRequest) -> ua.CallMethodResult | None:
        """The answer to a call refused here (None: its method answers)."""
        problem = call_problem(self.aspace, request)
        if problem is not None:
            return ua.CallMethodResult(StatusCode=ua_status(problem))
        return self._refresh_problem(request)

    def _refresh_problem(self, request: ua.CallMethodRequest) -> ua.CallMethodResult | None:
        """Why a ``ConditionRefresh`` (or ``…2``) is refused (None: asyncua replays). Its
        arguments first, as the face's other methods (OPC UA Part 4, "Call"): a
        SubscriptionId or MonitoredItemId that is no integer is ``BadTypeMismatch`` in the
        ``InputArgumentResults`` and ``BadInvalidArgument`` (asyncua looked a String up as
        an id), too few or too many ``BadArgumentsMissing`` or ``BadTooManyArguments``.
        Then ``BadSubscriptionIdInvalid`` for a subscription of another session: the server
        verifies that the subscription is the calling session's (Part 9, "ConditionRefresh
        Method") — asyncua replayed every retained condition into any session's
        subscription for whoever asked."""
        wanted = _REFRESH.get(request.MethodId)
        if wanted is None:
            return None
        inputs = list(request.InputArguments or [])
        if len(inputs) > wanted:
            return ua.CallMethodResult(StatusCode=ua_status(StatusCodes.BadTooManyArguments))
        ids = [v.Value if isinstance(v, ua.Variant) else v for v in inputs]
        codes = [
            ua_status(StatusCodes.Good if _an_id(v) else StatusCodes.BadTypeMismatch)
            for v in inputs
        ]
        if any(not c.is_good() for c in codes):
            bad = ua_status(StatusCodes.BadInvalidArgument)
            return ua.CallMethodResult(StatusCode=bad, InputArgumentResults=codes)
        if len(inputs) < wanted or None in ids:
            return ua.CallMethodResult(StatusCode=ua_status(StatusCodes.BadArgumentsMissing))
        ours = {s.data.SubscriptionId for s in self._subscriptions()}
        if ids[0] in ours:
            return None
        return ua.CallMethodResult(StatusCode=ua_status(StatusCodes.BadSubscriptionIdInvalid))

    def _subscriptions(self) -> list[Any]:
        subs = self.subscription_service.subscriptions.values()
        return [s for s in subs if s.session_id == self.session_id]

    async def create_subscription(
        self,
        params: ua.CreateSubscriptionParameters,
        callback: Callable[..., Any],
        request_callback: Callable[..., Any] | None = None,
    ) -> ua.CreateSubscriptionResult:
        await self._serve(1, COST_SUBSCRIPTION)
        if len(self._subscriptions()) >= self.limits.subscriptions:
            raise ServiceError(StatusCodes.BadTooManySubscriptions)
        interval = params.RequestedPublishingInterval
        lo, hi = self.limits.min_publishing_ms, self.limits.max_publishing_ms
        if not isinstance(interval, float | int) or not math.isfinite(interval):
            interval = lo
        params.RequestedPublishingInterval = float(min(max(interval, lo), hi))
        return await super().create_subscription(params, callback, request_callback)

    async def delete_subscriptions(self, ids: list[int]) -> list[ua.StatusCode]:
        await self._serve(len(ids), len(ids) * COST_SUBSCRIPTION)
        return await super().delete_subscriptions(ids)

    async def create_monitored_items(
        self, params: ua.CreateMonitoredItemsParameters
    ) -> list[ua.MonitoredItemCreateResult]:
        asked = len(params.ItemsToCreate)
        await self._serve(asked, asked * COST_ITEM)
        held = sum(len(s.monitored_item_srv._monitored_items) for s in self._subscriptions())
        if held + asked > self.limits.monitored_items:
            refused = ua.MonitoredItemCreateResult()
            refused.StatusCode = ua_status(StatusCodes.BadTooManyMonitoredItems)
            return [refused for _ in range(asked)]
        problems = [self._item_problem(item) for item in params.ItemsToCreate]
        subscription = self.subscription_service.subscriptions.get(params.SubscriptionId)
        if subscription is not None and any(
            i.ItemToMonitor.IndexRange for i in params.ItemsToCreate
        ):
            follow_ranges(subscription.monitored_item_srv)
        if not any(problems):
            return await super().create_monitored_items(params)
        # the items that fit, in a request of their own (the one given stays as sent)
        fitting = copy.copy(params)
        fitting.ItemsToCreate = [
            i for i, p in zip(params.ItemsToCreate, problems, strict=True) if p is None
        ]
        made = iter(await super().create_monitored_items(fitting) if fitting.ItemsToCreate else [])
        return [
            next(made) if p is None else ua.MonitoredItemCreateResult(StatusCode=ua_status(p))
            for p in problems
        ]

    def _item_problem(self, item: ua.MonitoredItemCreateRequest) -> int | None:
        """Why a monitored item is not made (None: asyncua makes it): no such node (an
        event item of no node was asyncua's ``BadServiceUnsupported``), a range of another
        syntax than Part 4's (``web.opcua.ranges``), or a filter that does not go with its
        attribute."""
        problem = missing(self.aspace, item.ItemToMonitor.NodeId) or item_problem(item)
        if problem is not None:
            return problem
        return None if _filter_fits(item) else StatusCodes.BadFilterNotAllowed


def _null(nid: object) -> bool:
    """Whether ``nid`` is the null node id (or no node id): ``BadNodeIdInvalid`` to a Read
    or a Write, as to a Browse (asyncua: ``BadNodeIdUnknown``)."""
    return not isinstance(nid, ua.NodeId) or nid.is_null()


_REFRESH: Final = {  # the method: how many arguments (SubscriptionId, MonitoredItemId)
    ua_id(ObjectIds.ConditionType_ConditionRefresh): 1,
    ua_id(ObjectIds.ConditionType_ConditionRefresh2): 2,
}
_CURRENT_WRITE: Final = 0x02  # AccessLevel's CurrentWrite bit


def _an_id(given: object) -> bool:
    """Whether ``given`` is an IntegerId's value (an integer variant), or Null: left out."""
    if not isinstance(given, ua.Variant):
        return False
    if given.VariantType is ua.VariantType.Null or given.Value is None:
        return True
    value = given.Value
    return (
        given.VariantType in INT_VARIANTS and isinstance(value, int) and not isinstance(value, bool)
    )


def _read_only(attribute: int, value: ua.DataValue) -> ua.DataValue:
    """``value`` of ``attribute`` as an anonymous session's: a variable's
    ``UserAccessLevel`` without CurrentWrite, a method's ``UserExecutable`` false — what a
    client greys out, as the face refuses those writes and calls (OPC UA Part 3, "User
    access level"). A copy: ``value`` is the one the address space holds (asyncua's read
    hands it out), which every other session reads."""
    held = value.Value.Value if value.Value is not None else None
    if attribute == AttributeIds.UserAccessLevel and isinstance(held, int):
        shown = ua.Variant(held & ~_CURRENT_WRITE, ua.VariantType.Byte)
    elif attribute == AttributeIds.UserExecutable and isinstance(held, bool):
        shown = ua.Variant(False, ua.VariantType.Boolean)
    else:
        return value
    return dataclasses.replace(value, Value=shown)


def _filter_fits(item: ua.MonitoredItemCreateRequest) -> bool:
    """Whether an item's filter goes with its attribute (Part 4, 7.22): no EventFilter or
    AggregateFilter on a value, no DataChangeFilter or AggregateFilter on an event
    notifier — asyncua answered those with a BadInternalError for the whole request."""
    given = type(item.RequestedParameters.Filter).__name__  # asyncua decodes a filter
    # into a class of the same name, not always the one ``ua`` exports
    if item.ItemToMonitor.AttributeId == AttributeIds.EventNotifier:
        return given not in ("DataChangeFilter", "AggregateFilter")
    return given not in ("EventFilter", "AggregateFilter")


class FaceServer(InternalServer):
    """The internal server whose sessions are :class:`FaceSession` s, with their
    ``limits`` and what happens when one closes (``on_close``: its login ends)."""

    limits: Limits = Limits()
    on_close: Callable[[FaceUser], None] | None = None
    pace: Pace | None = None  # all sessions' requests together

    def register_server(self, server: Any, conf: Any = None) -> None:
        """No discovery server: a client registering one is refused (asyncua serves
        RegisterServer before any session, so no permission rule can)."""
        raise ServiceError(StatusCodes.BadServiceUnsupported)

    def register_server2(self, params: ua.RegisterServer2Parameters) -> None:
        raise ServiceError(StatusCodes.BadServiceUnsupported)

    def create_session(
        self,
        name: str,
        user: User = User(role=UserRole.Anonymous),  # noqa: B008  (asyncua's own default)
        external: bool = False,
    ) -> InternalSession:
        return FaceSession(
            self, self.aspace, self.subscription_service, name, user=user, external=external
        )
