"""Adding and changing the face's nodes in bulk: :class:`Nodes` batches the nodes of a
subtree into one ``AddNodes`` of the server's own session (thousands of steps and
symbols in well under a second), remembers which it added under which root (to delete a
subtree again at an online change) and writes a value only when it or its status changed.

Every node it adds gets the node id it is given (``web.opcua.model.node_id``): the
properties of a method and the engineering units of a variable too, so a client's
stored node ids stay valid across restarts.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from datetime import UTC, datetime
from typing import Any, Final

from asyncua import ua
from asyncua.server.internal_session import InternalSession

from s7graph.web.opcua.bulk import Refused, insert, remove
from s7graph.web.opcua.model import UaType, eu_information
from s7graph.web.opcua.typed import (
    AttributeIds,
    ObjectIds,
    Server,
    StatusCodes,
    child_id,
    data_value,
    ua_id,
    ua_status,
    ua_uint,
)

__all__ = ["GOOD", "Nodes"]

GOOD: Final = StatusCodes.Good
_READ: Final = ua.AccessLevel.CurrentRead.mask
_READ_WRITE: Final = ua.AccessLevel.CurrentRead.mask | ua.AccessLevel.CurrentWrite.mask


def _ref(oid: int) -> ua.NodeId:
    return ua_id(oid)


class Nodes:
    """The face's nodes in the server ``server``'s address space."""

    def __init__(self, server: Server, ns: int) -> None:
        self.server = server
        self.ns = ns
        self._session: InternalSession = server.iserver.isession
        self._items: list[ua.AddNodesItem] = []
        self._refs: list[ua.AddReferencesItem] = []
        self._methods: list[tuple[ua.NodeId, Callable[..., Any]]] = []
        self._waiting: list[ua.NodeId] = []  # variables added, waiting for a first value
        self._owner: list[ua.NodeId] = []  # the root the nodes being added belong to
        self.under: dict[ua.NodeId, list[ua.NodeId]] = {}
        """Per root of a subtree, the nodes added under it (itself first)."""
        self._written: dict[ua.NodeId, tuple[Any, int]] = {}
        self._names: dict[tuple[ua.NodeId, AttributeIds], str] = {}

    # ------------------------------------------------------------ adding

    def root(self, nid: ua.NodeId) -> None:
        """The nodes added from now on (``nid`` included) form the subtree of ``nid``."""
        self._owner.append(nid)
        self.under.setdefault(nid, [])

    def end_root(self) -> None:
        self._owner.pop()

    def _add(self, item: ua.AddNodesItem) -> ua.NodeId:
        self._items.append(item)
        nid: ua.NodeId = item.RequestedNewNodeId
        for owner in self._owner:
            self.under[owner].append(nid)
        return nid

    @staticmethod
    def _item(
        parent: ua.NodeId,
        nid: ua.NodeId,
        name: str,
        node_class: ua.NodeClass,
        ref: int,
        type_def: int | None,
    ) -> ua.AddNodesItem:
        item = ua.AddNodesItem()
        item.RequestedNewNodeId = nid
        item.BrowseName = ua.QualifiedName(name, nid.NamespaceIndex)
        item.ParentNodeId = parent
        item.ReferenceTypeId = _ref(ref)
        item.NodeClass = node_class
        if type_def is not None:
            item.TypeDefinition = _ref(type_def)
        return item

    def obj(
        self,
        parent: ua.NodeId,
        nid: ua.NodeId,
        name: str,
        *,
        display: str = "",
        description: str = "",
        type_def: int = ObjectIds.BaseObjectType,
        ref: int = ObjectIds.HasComponent,
        notifier: bool = False,
    ) -> ua.NodeId:
        """An object (a folder with ``type_def=FolderType, ref=Organizes``)."""
        item = self._item(parent, nid, name, ua.NodeClass.Object, ref, type_def)
        attrs = ua.ObjectAttributes()
        attrs.DisplayName = ua.LocalizedText(display or name)
        attrs.Description = ua.LocalizedText(description or display or name)
        attrs.EventNotifier = 1 if notifier else 0
        item.NodeAttributes = attrs
        self._names[(nid, AttributeIds.DisplayName)] = attrs.DisplayName.Text or ""
        self._names[(nid, AttributeIds.Description)] = attrs.Description.Text or ""
        return self._add(item)

    def folder(self, parent: ua.NodeId, nid: ua.NodeId, name: str, description: str) -> ua.NodeId:
        return self.obj(
            parent,
            nid,
            name,
            description=description,
            type_def=ObjectIds.FolderType,
            ref=ObjectIds.Organizes,
        )

    def var(
        self,
        parent: ua.NodeId,
        nid: ua.NodeId,
        name: str,
        t: UaType,
        *,
        description: str = "",
        writable: bool = False,
        array: bool = False,
        data_type: int | None = None,
        display: str = "",
    ) -> ua.NodeId:
        """A variable of type ``t``, its value waiting for the CPU's first answer
        (``BadWaitingForInitialData``), and its engineering units when ``t`` has one."""
        item = self._item(
            parent,
            nid,
            name,
            ua.NodeClass.Variable,
            ObjectIds.HasComponent,
            ObjectIds.BaseDataVariableType,
        )
        attrs = ua.VariableAttributes()
        attrs.DisplayName = ua.LocalizedText(display or name)
        attrs.Description = ua.LocalizedText(description or name)
        attrs.DataType = ua_id(data_type) if data_type is not None else t.data_type
        attrs.ValueRank = ua.ValueRank.OneDimension if array else ua.ValueRank.Scalar
        if array:
            attrs.ArrayDimensions = [ua_uint(0)]
        attrs.Value = ua.Variant(None, ua.VariantType.Null)
        level = _READ_WRITE if writable else _READ
        attrs.AccessLevel = level
        attrs.UserAccessLevel = level
        attrs.MinimumSamplingInterval = 0.0
        item.NodeAttributes = attrs
        self._add(item)
        self._waiting.append(nid)
        if t.unit is not None:
            self.prop(
                nid,
                "EngineeringUnits",
                ua.Variant(eu_information(t.unit)),
                ObjectIds.EUInformation,
            )
        return nid

    def prop(
        self,
        parent: ua.NodeId,
        name: str,
        value: ua.Variant,
        data_type: int,
        *,
        array: bool = False,
        type_def: int = ObjectIds.PropertyType,
    ) -> ua.NodeId:
        """A property ``name`` of ``parent`` (its node id: the parent's, then ``/name``;
        its browse name in namespace 0), read only, holding ``value``; with another
        ``type_def`` (a ``TwoStateVariableType``) a component variable of that type."""
        nid = child_id(parent, name)
        prop = type_def == ObjectIds.PropertyType
        ref = ObjectIds.HasProperty if prop else ObjectIds.HasComponent
        item = self._item(parent, nid, name, ua.NodeClass.Variable, ref, type_def)
        item.BrowseName = ua.QualifiedName(name, 0)
        attrs = ua.VariableAttributes()
        attrs.DisplayName = ua.LocalizedText(name)
        attrs.Description = ua.LocalizedText(name)
        attrs.DataType = ua_id(data_type)
        attrs.ValueRank = ua.ValueRank.OneDimension if array else ua.ValueRank.Scalar
        if array:
            attrs.ArrayDimensions = [ua_uint(0)]
        attrs.Value = value
        attrs.AccessLevel = _READ
        attrs.UserAccessLevel = _READ
        item.NodeAttributes = attrs
        return self._add(item)

    def method(
        self,
        parent: ua.NodeId,
        nid: ua.NodeId,
        name: str,
        callback: Callable[..., Any],
        *,
        description: str,
        inputs: Sequence[ua.Argument],
        outputs: Sequence[ua.Argument],
    ) -> ua.NodeId:
        item = self._item(parent, nid, name, ua.NodeClass.Method, ObjectIds.HasComponent, None)
        attrs = ua.MethodAttributes()
        attrs.DisplayName = ua.LocalizedText(name)
        attrs.Description = ua.LocalizedText(description)
        attrs.Executable = True
        attrs.UserExecutable = True
        item.NodeAttributes = attrs
        self._add(item)
        for label, args in (("InputArguments", inputs), ("OutputArguments", outputs)):
            if args:
                value = ua.Variant(list(args), ua.VariantType.ExtensionObject)
                self.prop(nid, label, value, ObjectIds.Argument, array=True)
        self._methods.append((nid, _owned(parent, callback)))
        return nid

    def reference(
        self,
        source: ua.NodeId,
        target: ua.NodeId,
        ref: int,
        *,
        target_class: ua.NodeClass = ua.NodeClass.Object,
        inverse: bool = True,
    ) -> None:
        """A forward reference ``ref`` from object ``source`` to ``target`` (of class
        ``target_class``), and its inverse unless ``inverse`` is false."""
        for forward in (True, False) if inverse else (True,):
            item = ua.AddReferencesItem()
            item.SourceNodeId = source if forward else target
            item.TargetNodeId = target if forward else source
            item.ReferenceTypeId = _ref(ref)
            item.IsForward = forward
            item.TargetNodeClass = target_class if forward else ua.NodeClass.Object
            self._refs.append(item)

    async def flush(self) -> None:
        """Add what was batched (``web.opcua.bulk.insert``: its variables waiting for
        their first value); ``RuntimeError`` naming the first node refused."""
        items, self._items = self._items, []
        refs, self._refs = self._refs, []
        methods, self._methods = self._methods, []
        waiting, self._waiting = self._waiting, []
        if items:
            try:
                insert(self.server.iserver.aspace, items, frozenset(waiting))
            except Refused as exc:
                raise RuntimeError(str(exc)) from None
        if refs:
            await self._session.add_references(refs)
        for nid, callback in methods:
            self._session.add_method_callback(nid, callback)

    async def delete(self, root: ua.NodeId) -> None:
        """Delete the subtree added under ``root``, ``root`` itself included (and every
        subtree inside it)."""
        nids = self.under.pop(root, [])
        if not nids:
            return
        gone = set(nids)
        for sub in [k for k in self.under if k in gone]:
            del self.under[sub]
        for other in self.under.values():  # a subtree this one was inside
            other[:] = [nid for nid in other if nid not in gone]
        for nid in nids:
            self._written.pop(nid, None)
        for key in [k for k in self._names if k[0] in gone]:
            del self._names[key]
        remove(self.server.iserver.aspace, list(reversed(nids)))

    # ------------------------------------------------------------ values

    async def set(
        self,
        nid: ua.NodeId,
        value: ua.Variant | None,
        status: int = GOOD,
        when: datetime | None = None,
    ) -> bool:
        """Write ``value`` with ``status`` to ``nid`` unless both are what it holds (a bad
        status keeps the last value); whether it wrote."""
        seen = self._written.get(nid)
        shown = value.Value if value is not None else None
        if seen is not None and seen == (shown, status):
            return False
        if value is None:
            held = self.server.read_attribute_value(nid)
            value = held.Value if held.Value is not None else ua.Variant(None)
        data = data_value(value, status, when or datetime.now(UTC))
        await self.server.write_attribute_value(nid, data)
        self._written[nid] = (shown, status)
        return True

    async def rename(self, nid: ua.NodeId, shown: str, description: str = "") -> None:
        """Give ``nid`` the display name ``shown`` (and ``description``, or ``shown``)
        unless it has them already."""
        for attr, text in (
            (AttributeIds.DisplayName, shown),
            (AttributeIds.Description, description or shown),
        ):
            if self._names.get((nid, attr)) == text:
                continue
            value = data_value(ua.Variant(ua.LocalizedText(text), ua.VariantType.LocalizedText))
            await self.server.write_attribute_value(nid, value, attr)
            self._names[(nid, attr)] = text

    def known(self, nid: ua.NodeId) -> bool:
        return nid in self._written

    def written(self) -> list[ua.NodeId]:
        """The variables written so far (to mark them stale)."""
        return list(self._written)


def _owned(owner: ua.NodeId, callback: Callable[..., Any]) -> Callable[..., Any]:
    """``callback`` for calls on the object that has the method only: a call naming
    another object (``Halt`` of one FB through the CPU's ``Symbols`` folder) is
    ``BadMethodInvalid``, as OPC UA's Call service says (Part 4, 5.11.2), never carried
    out."""

    async def call(parent: ua.NodeId, *inputs: Any) -> Any:
        if parent != owner:
            return ua.CallMethodResult(StatusCode=ua_status(StatusCodes.BadMethodInvalid))
        return await callback(parent, *inputs)

    return call
