"""The live layer of the status view, over a drawn picture: what S7-GRAPH's status view
shows of the active steps beside the colours of the boxes.

- each active step's times, ``T`` (active) and ``U`` (active without disturbance), under
  its box;
- the live value of each operand of an active step's action table, in the table's last
  column (TRUE on green, FALSE on grey, a number as it is);
- the contacts of every valid transition leaving an active step, and of each active step's
  interlock and supervision, coloured where the condition is drawn: green a contact that
  lets the condition through, red one that does not (``web.view.criteria``);
- which transitions hold (their bars green).

The geometry comes with the picture (once per chart); a state update only shows, hides,
moves or recolours nodes. A browser drawing WebGL in software pays dearly for every new
image (decoded, uploaded, its mipmaps made) and little for a node shown or hidden, so a
contact's two colours are two images made once, one of them shown, and the times (the one
text that changes while nothing else does) are redrawn at most every ``TIMES_PERIOD``
seconds. Nodes are pooled: one shown for an element that went is hidden and kept, and the
next element of its kind takes it over (moved, its text replaced) — so a step change sends
a few property updates, not new scene nodes, once the pools are as large as the most
elements shown at once; an element shown again on the node it had keeps its text and
place and is only made visible.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable
from dataclasses import dataclass
from typing import Any

import numpy as np

from s7graph.web.bus.protocol import StepStateUpdate
from s7graph.web.view.criteria import CONTACT_FAILS, CONTACT_PASSES, contact_states
from s7graph.web.view.glyphs import LINE, label_image, text_width

__all__ = [
    "TIMES_PERIOD",
    "TIMES_SIZE",
    "VALUE_FALSE",
    "VALUE_PLAIN",
    "VALUE_TRUE",
    "StatusLayer",
    "value_text",
]

Rgb = tuple[int, int, int]
TIMES_SIZE = 0.15
VALUE_SIZE = 0.14
VALUE_TRUE: Rgb = CONTACT_PASSES
VALUE_FALSE: Rgb = (215, 215, 215)
VALUE_PLAIN: Rgb = (255, 255, 255)
TIMES_BACK: Rgb = (255, 255, 255)
Z_CHIP, Z_LABEL = 0.03, 0.07  # behind the chart's text (0.05), over it
TIMES_PERIOD = 0.5  # s: an active step's T and U are redrawn at most this often
CHIP_COLOURS: tuple[Rgb, ...] = (CONTACT_PASSES, CONTACT_FAILS)


def value_text(value: object) -> tuple[str, Rgb]:
    """A live value as the table shows it, and its cell's colour."""
    if isinstance(value, bool):
        return ("TRUE", VALUE_TRUE) if value else ("FALSE", VALUE_FALSE)
    if isinstance(value, float):
        return f"{value:.6g}", VALUE_PLAIN
    return str(value), VALUE_PLAIN


@dataclass(frozen=True, slots=True)
class _Label:
    """A text shown on the chart: its lines, size, background, place (top-left) and width."""

    lines: tuple[str, ...]
    size: float
    background: Rgb
    x: float
    y: float
    width: float


@dataclass(frozen=True, slots=True)
class _Chip:
    """A coloured rectangle behind a contact: centre, size, colour."""

    cx: float
    cy: float
    w: float
    h: float
    colour: Rgb


MAX_RESERVED = 32  # nodes of a kind made with the chart; more are made when needed


def _needed(pic: Any) -> tuple[int, int]:
    """How many labels and contact pieces one active step per sequence shows at most (the
    step that shows most, in each sequence): the nodes to make with the chart."""
    placement = pic.placement
    pieces: dict[int, int] = {}
    for t in placement.transitions.values():
        count = sum(len(rects) for rects in pic.contacts.get(("T", t.number), ()))
        for s in t.sources:
            pieces[s] = pieces.get(s, 0) + count
    labels: dict[int, int] = {}
    chips: dict[int, int] = {}
    for s in placement.steps.values():
        own = sum(len(r) for k in ("C", "V") for r in pic.contacts.get((k, s.number), ()))
        label = 1 + len(pic.cells.get(s.number, ()))
        labels[s.sequence] = max(labels.get(s.sequence, 0), label)
        chips[s.sequence] = max(chips.get(s.sequence, 0), pieces.get(s.number, 0) + own)
    return min(sum(labels.values()), MAX_RESERVED), min(sum(chips.values()), MAX_RESERVED)


def _label_content(spec: _Label) -> Hashable:
    return spec.lines, spec.size, spec.background, spec.width


def _chip_content(spec: _Chip) -> Hashable:
    return spec.w, spec.h, spec.colour


def _solid(colour: Rgb) -> Any:
    """A small image of one colour (stretched over a contact)."""
    return np.full((2, 2, 3), colour, np.uint8)


class _ChipNodes:
    """The node of a contact piece: one image per colour of ``CHIP_COLOURS``, made once;
    the one of its colour shown while it is visible. Only that one is moved and sized; the
    other takes the place when it is shown."""

    def __init__(self, images: dict[Rgb, Any]) -> None:
        self._images = images
        self._colour = CHIP_COLOURS[0]
        self._visible = False
        self._place: dict[str, Any] = {}  # where the piece is: the props of its image
        self._placed: dict[Rgb, dict[str, Any]] = {c: {} for c in images}

    @property
    def visible(self) -> bool:
        return self._visible

    @visible.setter
    def visible(self, on: bool) -> None:
        if on != self._visible:
            self._visible = on
            self._images[self._colour].visible = on

    def recolour(self, colour: Rgb) -> None:
        if colour == self._colour:
            return
        was, self._colour = self._colour, colour
        self._sync(colour)
        if self._visible:
            self._images[was].visible = False
            self._images[colour].visible = True

    def place(self, **props: Any) -> None:
        self._place.update(props)
        self._sync(self._colour)

    def _sync(self, colour: Rgb) -> None:
        placed, image = self._placed[colour], self._images[colour]
        for key, value in self._place.items():
            if placed.get(key) != value:
                setattr(image, key, value)
                placed[key] = value

    def remove(self) -> None:
        for image in self._images.values():
            image.remove()


class _Pool:
    """Scene nodes of one kind, each showing one element (by key) or hidden, free.

    A node freed is hidden only if no element takes it over in the same update; a node
    taken over is, by preference, the one that last showed the same element, else one that
    showed the same content elsewhere (only moved), else one that showed the same kind of
    element (``key[0]``)."""

    def __init__(
        self,
        make: Callable[[str], Any],
        show: Callable[[Any, Any, Any], None],
        content: Callable[[Any], Hashable],
    ) -> None:
        self._make, self._show, self._content = make, show, content
        self._by_key: dict[Hashable, Any] = {}
        self._spec: dict[int, tuple[Hashable, Any]] = {}  # node id: the key, spec it shows
        self._free: list[Any] = []
        self.nodes: list[Any] = []

    def show(self, wanted: dict[Hashable, Any]) -> None:
        """Show exactly the elements ``wanted`` (key: spec); hide the rest."""
        for key in [k for k in self._by_key if k not in wanted]:
            self._free.append(self._by_key.pop(key))
        for key, spec in wanted.items():
            node = self._by_key.get(key)
            if node is None:
                node = self._by_key[key] = self._take(key, spec)
            shown = self._spec.get(id(node))
            if shown is None or shown[1] != spec:
                self._show(node, spec, None if shown is None else shown[1])
                self._spec[id(node)] = (key, spec)
            if not node.visible:
                node.visible = True
        for node in self._free:
            if node.visible:
                node.visible = False

    def _take(self, key: Hashable, spec: Any) -> Any:
        """A free node, the most alike first; else a new one."""
        content = self._content(spec)
        kind = key[0] if isinstance(key, tuple) else key

        def likeness(node: Any) -> int:
            shown_key, shown = self._spec.get(id(node), (None, None))
            if shown_key == key:
                return 3
            if shown is not None and self._content(shown) == content:
                return 2
            return int(isinstance(shown_key, tuple) and shown_key[0] == kind)

        if self._free:
            best = max(range(len(self._free)), key=lambda i: likeness(self._free[i]))
            return self._free.pop(best)
        node = self._make(f"n{len(self.nodes)}")
        self.nodes.append(node)
        return node

    def reserve(self, count: int) -> None:
        """Make ``count`` nodes now, hidden (drawn with the chart, not at its first update)."""
        while len(self.nodes) < count:
            node = self._make(f"n{len(self.nodes)}")
            self.nodes.append(node)
            self._free.append(node)

    def shown(self) -> dict[Hashable, Any]:
        """What each element shown shows (its spec), by key; safe to call from another
        thread while :meth:`show` runs (an element half placed is left out)."""
        out: dict[Hashable, Any] = {}
        for key, node in list(self._by_key.items()):
            spec = self._spec.get(id(node))
            if spec is not None and spec[0] == key:
                out[key] = spec[1]
        return out


class StatusLayer:
    """The live layer over ``pic`` drawn in ``scene`` under ``root`` at ``offset``."""

    def __init__(
        self,
        scene: Any,
        pic: Any,
        *,
        root: str = "/chart/live",
        offset: tuple[float, float] = (0.0, 0.0),
    ) -> None:
        self.scene, self.picture, self.root, self.offset = scene, pic, root, offset
        self.labels = _Pool(self._new_label, self._show_label, _label_content)
        self.chips = _Pool(self._new_chip, self._show_chip, _chip_content)
        labels, chips = _needed(pic)
        self.labels.reserve(labels)
        self.chips.reserve(chips)
        self._times_due: dict[int, float] = {}  # step: when its times may be redrawn

    # ------------------------------------------------------------ what to show

    def show(
        self, update: StepStateUpdate | None, connected: bool, now: float | None = None
    ) -> set[int]:
        """Show ``update``'s live state (nothing while disconnected); the transitions that
        hold (their bars go green). ``now`` (s, monotonic): a step's times already shown
        are redrawn only ``TIMES_PERIOD`` after they were last (None: always)."""
        if update is None or not connected:
            self.labels.show({})
            self.chips.show({})
            return set()
        self.labels.show(self._labels(update, now))
        chips: dict[Hashable, _Chip] = {}
        contacts = self.picture.contacts
        for key, oks in contact_states(update).items():
            rects = contacts.get(key, ())
            for k, ok in enumerate(oks[: len(rects)]):
                colour = CONTACT_PASSES if ok else CONTACT_FAILS
                for i, (cx, cy, w, h) in enumerate(rects[k]):
                    chips[(key, k, i)] = _Chip(cx, cy, w, h, colour)
        self.chips.show(chips)
        return {t.number for d in update.details for t in d.transitions if t.holds}

    def _labels(self, update: StepStateUpdate, now: float | None) -> dict[Hashable, _Label]:
        pic = self.picture
        out: dict[Hashable, _Label] = {}
        shown = self.labels.shown()
        due = self._times_due
        for d in update.details:
            at = pic.times.get(d.number)
            if at is None:
                continue
            key = ("times", d.number)
            if now is not None and key in shown and now < due.get(d.number, 0.0):
                out[key] = shown[key]  # redrawn at its time
                continue
            lines = (f"T {d.t_ms / 1000:.1f} s", f"U {d.u_ms / 1000:.1f} s")
            width = max(text_width(line, TIMES_SIZE) for line in lines) + 0.1
            x, y = at
            out[key] = _Label(lines, TIMES_SIZE, TIMES_BACK, x, y, width)
            if now is not None and (key not in shown or shown[key] != out[key]):
                due[d.number] = now + TIMES_PERIOD
        values = update.values
        for number in update.active:
            for cell in pic.cells.get(number, ()):
                if cell.key not in values:
                    continue
                text, colour = value_text(values[cell.key])
                top = cell.cy + VALUE_SIZE * LINE / 2
                out[("value", number, cell.row)] = _Label(
                    (text,), VALUE_SIZE, colour, cell.cx - cell.w / 2, top, cell.w
                )
        return out

    def shown_text(self) -> dict[Hashable, tuple[str, ...]]:
        """The texts shown now, by element (``("times", step)``, ``("value", step, row)``)."""
        return {k: spec.lines for k, spec in self.labels.shown().items()}

    def shown_contacts(self) -> dict[Hashable, Rgb]:
        """The colour of each contact piece shown now, by ``(condition, contact, piece)``."""
        return {k: spec.colour for k, spec in self.chips.shown().items()}

    # ------------------------------------------------------------ nodes

    def _hidden_image(self, name: str, image: Any) -> Any:
        """A scene image, hidden until it is shown and sized (``_show_…``)."""
        return self.scene.add_image(
            f"{self.root}/{name}",
            image,
            render_width=0.1,
            render_height=0.1,
            format="png",
            visible=False,
            cast_shadow=False,
            receive_shadow=False,
        )

    def _new_label(self, name: str) -> Any:
        return self._hidden_image(f"label/{name}", label_image([""], VALUE_SIZE, 0.1, VALUE_PLAIN))

    def _show_label(self, node: Any, spec: _Label, before: _Label | None) -> None:
        if before is None or (before.lines, before.background, before.width) != (
            spec.lines,
            spec.background,
            spec.width,
        ):
            node.image = label_image(list(spec.lines), spec.size, spec.width, spec.background)
        height = spec.size * LINE * len(spec.lines)
        size = (spec.width, height)
        if before is None or size != (before.width, before.size * LINE * len(before.lines)):
            node.render_width, node.render_height = size
        if (
            before is None
            or size != (before.width, before.size * LINE * len(before.lines))
            or (
                spec.x,
                spec.y,
            )
            != (before.x, before.y)
        ):
            ox, oy = self.offset
            node.position = (spec.x + spec.width / 2 + ox, spec.y - height / 2 + oy, Z_LABEL)

    def _new_chip(self, name: str) -> _ChipNodes:
        # images, not boxes: an image shows its colour as it is (a box's is tone-mapped)
        return _ChipNodes(
            {
                colour: self._hidden_image(
                    f"contact/{name}/{'ok' if i == 0 else 'no'}", _solid(colour)
                )
                for i, colour in enumerate(CHIP_COLOURS)
            }
        )

    def _show_chip(self, node: _ChipNodes, spec: _Chip, before: _Chip | None) -> None:
        node.recolour(spec.colour)
        if before is None or (before.w, before.h) != (spec.w, spec.h):
            node.place(render_width=spec.w, render_height=spec.h)
        if before is None or (before.cx, before.cy) != (spec.cx, spec.cy):
            ox, oy = self.offset
            node.place(position=(spec.cx + ox, spec.cy + oy, Z_CHIP))

    def remove(self) -> None:
        """Remove every node of the layer (the chart is drawn anew)."""
        for node in [*self.labels.nodes, *self.chips.nodes]:
            try:
                node.remove()
            except Exception:  # a page gone meanwhile
                continue
