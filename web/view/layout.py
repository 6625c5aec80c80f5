"""Place a chart the way S7-GRAPH draws it; a pure function from a chart to grid positions.

Sequences are columns side by side. Within a sequence, a depth-first walk from the initial
step (transitions in written order, i.e. by priority) lays out the main path top-down in
the leftmost lane; alternative branches (several transitions leaving one step) and
simultaneous branches (one transition with several targets) open lanes to the right.
Rows are the longest path from the top, so a convergence or a join sits below every branch
that reaches it. An edge back to a step already on the path, or to another sequence, is a
jump: an arrow under the transition with the target number. ``TO STOP`` is a branch stop.

At an alternative divergence the branches that go on come first (left), those that only
jump back or stop after them: a chart whose first branch at every step jumps back (as
imported PLCopen charts often are) keeps its path in one lane.

A long sequence wraps into several columns side by side (at most ``FOLD_ROWS`` rows each,
a column always starting with a step row), so a 250-step chart stays readable: a line that
would cross from one column into the next ends in a :class:`Continuation` arrow naming
where it goes, and the next column starts with one naming where it comes from.

Coordinates are grid units: ``x`` is a lane (0, 1, 2 …), ``y`` a row growing downward;
steps and transitions alternate rows. Views scale them.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from s7graph.sequencer.text.model import Chart
from s7graph.web.bus.protocol import ChartLayout, SequenceInfo, StepInfo, TransitionInfo

__all__ = [
    "FOLD_ROWS",
    "Continuation",
    "IncomingJump",
    "Jump",
    "Link",
    "PlacedSequence",
    "PlacedStep",
    "PlacedTransition",
    "Placement",
    "Stop",
    "place",
]

Point = tuple[float, float]


@dataclass(frozen=True, slots=True)
class PlacedStep:
    number: int
    name: str
    x: float
    y: float
    initial: bool
    interlock: bool
    supervision: bool
    sequence: int
    info: StepInfo | None = None  # its action table and conditions, as the CPU described them


@dataclass(frozen=True, slots=True)
class PlacedTransition:
    number: int
    name: str
    x: float
    y: float
    condition: str
    sequence: int
    contacts: tuple[tuple[int, int], ...] = ()  # where each contact stands in the condition
    sources: tuple[int, ...] = ()  # the steps before it


@dataclass(frozen=True, slots=True)
class Link:
    """A polyline from a step to a transition or back; ``double`` marks the horizontal
    part of a simultaneous divergence or join (S7-GRAPH's double line)."""

    points: tuple[Point, ...]
    double: bool = False
    transition: int = 0


@dataclass(frozen=True, slots=True)
class Jump:
    """A jump arrow under ``transition`` (at ``x, y``) to step ``target``."""

    transition: int
    target: int
    x: float
    y: float


@dataclass(frozen=True, slots=True)
class IncomingJump:
    """The mark beside step ``step`` saying transition ``transition`` jumps here."""

    step: int
    transition: int
    x: float
    y: float


@dataclass(frozen=True, slots=True)
class Stop:
    """A branch stop (``TO STOP``) under ``transition``."""

    transition: int
    x: float
    y: float


@dataclass(frozen=True, slots=True)
class Continuation:
    """Where a line leaves one column of a wrapped sequence (``incoming`` False: an arrow
    down at ``x, y`` under ``source``, labelled with the element it leads to) or enters the
    next (``incoming`` True: an arrow from above into ``target``, labelled with where it
    comes from). ``source`` and ``target`` are ``("S"|"T", number)``."""

    x: float
    y: float
    source: tuple[str, int]
    target: tuple[str, int]
    incoming: bool

    @property
    def text(self) -> str:
        kind, n = self.source if self.incoming else self.target
        return f"{'from' if self.incoming else 'to'} {kind}{n}"


@dataclass(frozen=True, slots=True)
class PlacedSequence:
    number: int
    name: str
    x0: float
    x1: float


@dataclass(frozen=True, slots=True)
class Placement:
    steps: dict[int, PlacedStep]
    transitions: dict[int, PlacedTransition]
    links: tuple[Link, ...]
    jumps: tuple[Jump, ...]
    incoming_jumps: tuple[IncomingJump, ...]
    stops: tuple[Stop, ...]
    sequences: tuple[PlacedSequence, ...]
    width: float
    height: float
    continuations: tuple[Continuation, ...] = ()


# Graph nodes: ("S", n) for a step, ("T", n) for a transition.
Node = tuple[str, int]
MARK_OFFSET = 0.55  # how far below a transition a jump arrow or stop is drawn
SEQUENCE_GAP = 0.5  # empty lanes between two sequence columns
FOLD_ROWS = 16  # rows of one column of a long sequence (8 steps and their transitions)
FOLD_GAP = 0.25  # empty lanes between two columns of one sequence


def place(chart: Chart | ChartLayout, *, fold: int = FOLD_ROWS) -> Placement:
    """Grid positions of every step, transition, line, jump and stop of ``chart``; a
    sequence longer than ``fold`` rows wraps into columns of ``fold`` rows (even, ≥ 4)."""
    layout = chart if isinstance(chart, ChartLayout) else ChartLayout.from_chart(chart)
    fold = max(4, fold - fold % 2)
    parts = []
    x0 = 0.0
    for seq in layout.sequences:
        part = _fold(_place_sequence(layout, seq, x0), fold)
        parts.append(part)
        x0 = part.width_end + SEQUENCE_GAP
    steps = {s.number: s for p in parts for s in p.steps}
    transitions = {t.number: t for p in parts for t in p.transitions}
    jumps = tuple(j for p in parts for j in p.jumps)
    incoming = []
    for j in jumps:
        target = steps.get(j.target)
        if target is not None:
            incoming.append(IncomingJump(j.target, j.transition, target.x - 0.6, target.y))
    height = max((p.height for p in parts), default=0.0)
    return Placement(
        steps=steps,
        transitions=transitions,
        links=tuple(link for p in parts for link in p.links),
        jumps=jumps,
        incoming_jumps=tuple(incoming),
        stops=tuple(s for p in parts for s in p.stops),
        sequences=tuple(p.column for p in parts),
        width=max(x0 - SEQUENCE_GAP, 0.0),
        height=height,
        continuations=tuple(c for p in parts for c in p.continuations),
    )


@dataclass(slots=True)
class _Part:
    steps: list[PlacedStep]
    transitions: list[PlacedTransition]
    links: list[Link]
    jumps: list[Jump]
    stops: list[Stop]
    column: PlacedSequence
    width_end: float
    height: float
    continuations: list[Continuation] = field(default_factory=list)


def _place_sequence(layout: ChartLayout, seq: SequenceInfo, x0: float) -> _Part:
    return _SequencePlacer(layout, seq).place(x0)


class _SequencePlacer:
    """One sequence's graph, walked depth first from its initial step: rows, lanes, lines."""

    def __init__(self, layout: ChartLayout, seq: SequenceInfo) -> None:
        self.seq = seq
        self.step_info = {s.number: s for s in layout.steps if s.number in set(seq.steps)}
        self.trans = {t.number: t for t in layout.transitions if t.number in set(seq.transitions)}
        self.own_steps = [n for n in seq.steps if n in self.step_info]
        self.out: dict[int, list[TransitionInfo]] = {n: [] for n in self.own_steps}
        for number in seq.transitions:
            found = self.trans.get(number)
            if found is None:
                continue
            for s in found.sources:
                if s in self.out:
                    self.out[s].append(found)
        # Depth-first walk: classify edges (tree / forward / back), record discovery order.
        self.tree_children: dict[Node, list[Node]] = {}
        self.dag_preds: dict[Node, list[Node]] = {}
        self.back_edges: set[tuple[Node, Node]] = set()
        self.postorder: list[Node] = []
        self.roots: list[Node] = []
        self._state: dict[Node, int] = {}  # 1 on the stack, 2 finished
        self.lane: dict[Node, float] = {}
        self.jump_lane: dict[tuple[int, int], float] = {}

    def place(self, x0: float) -> _Part:
        seq, trans = self.seq, self.trans
        self._walk()
        row = self._rows()
        self._lanes(x0, row)
        lane = self.lane
        placed_steps = [
            PlacedStep(
                number=n,
                name=self.step_info[n].name,
                x=lane[("S", n)],
                y=float(row[("S", n)]),
                initial=self.step_info[n].initial,
                interlock=self.step_info[n].interlock,
                supervision=self.step_info[n].supervision,
                sequence=seq.number,
                info=self.step_info[n],
            )
            for n in self.own_steps
        ]
        placed_trans = [
            PlacedTransition(
                number=n,
                name=trans[n].name,
                x=lane[("T", n)],
                y=float(row[("T", n)]),
                condition=trans[n].condition,
                sequence=seq.number,
                contacts=tuple((a, b) for a, b in trans[n].contacts),
                sources=tuple(trans[n].sources),
            )
            for n in seq.transitions
            if n in trans
        ]
        links, jumps, stops = self._lines(placed_steps, placed_trans)
        lanes_used = [*lane.values(), *self.jump_lane.values()]
        x_end = max(lanes_used, default=x0) + 1
        height = max((float(r) for r in row.values()), default=0.0) + 1
        return _Part(
            steps=placed_steps,
            transitions=placed_trans,
            links=links,
            jumps=jumps,
            stops=stops,
            column=PlacedSequence(seq.number, seq.name, x0, x_end - 1),
            width_end=x_end,
            height=height,
        )

    def _successors(self, node: Node) -> list[Node]:
        kind, n = node
        if kind == "S":
            return [("T", t.number) for t in self.out.get(n, [])]
        return [("S", s) for s in self.trans[n].targets if s in self.step_info]

    def _walk(self) -> None:
        seq, own_steps = self.seq, self.own_steps
        starts = [("S", n) for n in own_steps if self.step_info[n].initial]
        starts += [("S", n) for n in own_steps]
        starts += [("T", n) for n in seq.transitions if n in self.trans]
        for node in starts:
            if node not in self._state:
                self.roots.append(node)
                self._visit(node)

    def _visit(self, root: Node) -> None:
        state, tree_children = self._state, self.tree_children
        state[root] = 1
        tree_children[root] = []
        stack: list[tuple[Node, list[Node]]] = [(root, self._successors(root))]
        while stack:
            node, todo = stack[-1]
            if not todo:
                state[node] = 2
                self.postorder.append(node)
                stack.pop()
                continue
            nxt = todo.pop(0)
            if state.get(nxt) == 1:
                self.back_edges.add((node, nxt))
                continue
            self.dag_preds.setdefault(nxt, []).append(node)
            if nxt not in state:
                state[nxt] = 1
                tree_children[node].append(nxt)
                tree_children[nxt] = []
                stack.append((nxt, self._successors(nxt)))

    def _rows(self) -> dict[Node, int]:
        """Rows: longest path over the DAG (reverse postorder is a topological order)."""
        row: dict[Node, int] = {}
        for node in reversed(self.postorder):
            preds = self.dag_preds.get(node, [])
            row[node] = max((row[p] + 1 for p in preds if p in row), default=0)
            if node[0] == "T" and row[node] % 2 == 0:
                row[node] += 1  # transitions always sit on odd rows, steps on even rows
            elif node[0] == "S" and row[node] % 2 == 1:
                row[node] += 1
        return row

    def _jump_targets(self, node: Node) -> list[int]:
        if node[0] != "T":
            return []
        t = self.trans[node[1]]
        return [
            s for s in t.targets if s not in self.step_info or (node, ("S", s)) in self.back_edges
        ]

    def _is_divergence(self, node: Node) -> bool:
        return node[0] == "T" and len(self.trans[node[1]].targets) > 1

    def _only_jumps(self, node: Node) -> bool:
        """Whether transition ``node`` leads nowhere on the page below it: every target a
        jump (back, or to another sequence), or a branch stop (one target at most)."""
        if node[0] != "T" or len(self.trans[node[1]].targets) > 1:
            return False
        return set(self._jump_targets(node)) == set(self.trans[node[1]].targets)

    def _split(self, node: Node) -> tuple[list[Node], list[Node]]:
        """The tree children of ``node`` that take lanes side by side, and at an alternative
        divergence the branches that only jump back or stop: those are placed afterwards
        in the first lane right of their step that is free at their rows
        (:meth:`_side_branches`), so the path that goes on keeps its lane instead of
        stepping one lane right at every step whose first branch jumps back."""
        children = self.tree_children[node]
        if node[0] != "S" or len(children) < 2:
            return children, []
        main = [c for c in children if not self._only_jumps(c)]
        side = [c for c in children if self._only_jumps(c)]
        if not main:
            main.append(side.pop(0))
        return main, side

    def _lanes(self, x0: float, row: dict[Node, int]) -> None:
        """Lanes: tree children side by side; jumps in a simultaneous divergence take a
        lane; branches that only jump or stop go where their rows are free."""
        width: dict[Node, int] = {}
        for node in self.postorder:
            own = sum(width[c] for c in self._split(node)[0])
            if self._is_divergence(node):
                own += len(self._jump_targets(node))
            width[node] = max(1, own)
        lane = self.lane
        sides: list[tuple[Node, Node]] = []
        next_lane = x0
        for root in self.roots:
            lane[root] = next_lane
            stack = [root]
            while stack:
                node = stack.pop()
                x = lane[node]
                if self._is_divergence(node):
                    # Keep written target order across real steps and jumps.
                    tree = {c[1]: c for c in self.tree_children[node]}
                    jumped = set(self._jump_targets(node))
                    for target in self.trans[node[1]].targets:
                        if target in tree:
                            lane[tree[target]] = x
                            stack.append(tree[target])
                            x += width[tree[target]]
                        elif target in jumped:
                            self.jump_lane[(node[1], target)] = x
                            x += 1
                    continue
                main, side = self._split(node)
                for child in main:
                    lane[child] = x
                    stack.append(child)
                    x += width[child]
                sides += [(node, child) for child in side]
            next_lane += width[root]
        if sides:
            self._side_branches(sides, row)

    def _side_branches(self, sides: list[tuple[Node, Node]], row: dict[Node, int]) -> None:
        """Place each branch that only jumps or stops in the first lane right of its step
        where nothing is drawn from the line under the step down to its jump arrow."""
        taken = _Occupancy()
        for node, preds in self.dag_preds.items():
            if node in self.lane:
                for pred in preds:
                    if pred in self.lane:
                        self._occupy_edge(taken, pred, node, row)
        for node in self.lane:
            taken.add(self.lane[node], row[node] - 0.45, row[node] + 0.45)
        for (t, _), x in self.jump_lane.items():
            taken.add(x, row[("T", t)] + 0.5, row[("T", t)] + 1.0)
        for step, branch in sorted(sides, key=lambda sb: (row[sb[0]], sb[0][1])):
            x, top = self.lane[step], row[step] + 0.25
            bottom = row[branch] + 1.0
            lane = x + 1  # the step's divergence line runs across to it: shared, not taken
            while taken.hit(lane, top, bottom):
                lane += 1
            self.lane[branch] = lane
            taken.add(lane, top, bottom)

    def _occupy_edge(self, taken: _Occupancy, a: Node, b: Node, row: dict[Node, int]) -> None:
        """Mark where the line from ``a`` down to ``b`` runs (as ``_lines`` draws it)."""
        xa, xb, ra, rb = self.lane[a], self.lane[b], float(row[a]), float(row[b])
        if xa == xb:
            taken.add(xa, ra, rb)
            return
        fans_out = (a[0] == "S" and len(self.out.get(a[1], [])) > 1) or self._is_divergence(a)
        mid = ra + 0.5 if fans_out else rb - 0.5
        taken.add(xa, ra, mid)
        taken.add(xb, mid, rb)
        for lane in range(int(min(xa, xb)), int(max(xa, xb)) + 1):
            taken.add(lane, mid - 0.25, mid + 0.25)

    def _lines(
        self, placed_steps: list[PlacedStep], placed_trans: list[PlacedTransition]
    ) -> tuple[list[Link], list[Jump], list[Stop]]:
        pos = {("S", s.number): (s.x, s.y) for s in placed_steps}
        pos.update({("T", t.number): (t.x, t.y) for t in placed_trans})
        links: list[Link] = []
        jumps: list[Jump] = []
        stops: list[Stop] = []
        for t in placed_trans:
            info = self.trans[t.number]
            links += self._lines_in(t, info, pos)
            if not info.targets:
                stops.append(Stop(t.number, t.x, t.y + MARK_OFFSET))
            jumps_here = set(self._jump_targets(("T", t.number)))
            for target in info.targets:
                if target in jumps_here:
                    jx = self.jump_lane.get((t.number, target), t.x)
                    if jx != t.x:
                        links.append(_elbow((t.x, t.y), (jx, t.y + 1), t.y + 0.5, True, t.number))
                        jumps.append(Jump(t.number, target, jx, t.y + 1 - 0.45))
                    else:
                        jumps.append(Jump(t.number, target, t.x, t.y + MARK_OFFSET))
                    continue
                tx, ty = pos[("S", target)]
                if len(info.targets) > 1:  # simultaneous divergence: double line under the bar
                    links.append(_elbow((t.x, t.y), (tx, ty), t.y + 0.5, True, t.number))
                else:  # a plain line, or an alternative convergence just above the step
                    links.append(_elbow((t.x, t.y), (tx, ty), ty - 0.5, False, t.number))
        return links, jumps, stops

    def _lines_in(
        self, t: PlacedTransition, info: TransitionInfo, pos: dict[Node, Point]
    ) -> list[Link]:
        """The lines from the steps before transition ``t`` into it."""
        links: list[Link] = []
        node = ("T", t.number)
        for s in info.sources:
            src: Node = ("S", s)
            if src not in pos or (src, node) in self.back_edges:
                continue
            sx, sy = pos[src]
            if len(info.sources) > 1:  # simultaneous join: double line just above the bar
                links.append(_elbow((sx, sy), (t.x, t.y), t.y - 0.5, True, t.number))
            elif len(self.out.get(s, [])) > 1:  # alternative divergence: line under the step
                links.append(_elbow((sx, sy), (t.x, t.y), sy + 0.5, False, t.number))
            else:
                links.append(_elbow((sx, sy), (t.x, t.y), t.y - 0.5, False, t.number))
        return links


class _Occupancy:
    """Which rows of each lane something is drawn on (intervals of grid rows)."""

    def __init__(self) -> None:
        self._spans: dict[int, list[tuple[float, float]]] = {}

    def add(self, lane: float, top: float, bottom: float) -> None:
        lo, hi = min(top, bottom), max(top, bottom)
        self._spans.setdefault(int(lane), []).append((lo, hi))

    def hit(self, lane: float, top: float, bottom: float) -> bool:
        return any(lo < bottom and top < hi for lo, hi in self._spans.get(int(lane), ()))


def _elbow(a: Point, b: Point, y_mid: float, double: bool, transition: int) -> Link:
    """Down from ``a`` to ``y_mid``, across to ``b``'s lane, down to ``b``."""
    (ax, ay), (bx, by) = a, b
    if ax == bx:
        return Link(((ax, ay), (bx, by)), False, transition)
    return Link(((ax, ay), (ax, y_mid), (bx, y_mid), (bx, by)), double, transition)


def _fold(part: _Part, rows: int) -> _Part:
    """``part`` wrapped into columns of ``rows`` rows, side by side (a column of the
    sequence: its lanes, then ``FOLD_GAP``); a link between two columns becomes a
    :class:`Continuation` pair."""
    if part.height <= rows:
        return part
    x0 = part.column.x0
    pitch = part.width_end - x0 + FOLD_GAP

    def column(y: float) -> int:
        return max(int(y // rows), 0)

    def moved(x: float, y: float, k: int) -> Point:
        return x + k * pitch, y - k * rows

    steps = [
        replace(s, x=moved(s.x, s.y, column(s.y))[0], y=s.y - column(s.y) * rows)
        for s in part.steps
    ]
    transitions = [
        replace(t, x=moved(t.x, t.y, column(t.y))[0], y=t.y - column(t.y) * rows)
        for t in part.transitions
    ]
    where: dict[tuple[float, float], tuple[str, int]] = {}
    for s in part.steps:
        where[(s.x, s.y)] = ("S", s.number)
    for t in part.transitions:
        where[(t.x, t.y)] = ("T", t.number)
    links: list[Link] = []
    continuations: list[Continuation] = []
    for link in part.links:
        (ax, ay), (bx, by) = link.points[0], link.points[-1]
        ka, kb = column(ay), column(by)
        if ka == kb:
            pts = tuple(moved(x, y, ka) for x, y in link.points)
            links.append(Link(pts, link.double, link.transition))
            continue
        source, target = where.get((ax, ay), ("S", 0)), where.get((bx, by), ("S", 0))
        sx, sy = moved(ax, ay, ka)
        tx, ty = moved(bx, by, kb)
        links.append(Link(((sx, sy), (sx, sy + 0.55)), False, link.transition))
        links.append(Link(((tx, ty - 0.55), (tx, ty)), False, link.transition))
        continuations.append(Continuation(sx, sy + 0.55, source, target, False))
        continuations.append(Continuation(tx, ty - 0.55, source, target, True))
    jumps = [
        replace(j, x=j.x + column(j.y) * pitch, y=j.y - column(j.y) * rows) for j in part.jumps
    ]
    stops = [
        replace(s, x=s.x + column(s.y) * pitch, y=s.y - column(s.y) * rows) for s in part.stops
    ]
    columns = column(part.height - 1) + 1
    return _Part(
        steps=steps,
        transitions=transitions,
        links=links,
        jumps=jumps,
        stops=stops,
        column=replace(part.column, x1=part.column.x1 + (columns - 1) * pitch),
        width_end=x0 + columns * pitch - FOLD_GAP,
        height=float(rows),
        continuations=continuations,
    )
