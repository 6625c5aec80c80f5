"""Read an XML file safely into a small tree that knows where each element was written.

The standard library's expat parser, configured the way ``defusedxml`` does it: a DTD or an
entity declaration is refused (no entity expansion, internal or external, so no "billion
laughs" and no file or network access), and nothing is fetched. Every element keeps its
line and column, and the place of its first non-blank character data, so that an
importer can locate a problem in the file (``file:line:col``). A UTF-8 byte order mark,
CRLF line ends and any namespace prefix are handled; merge-conflict markers (``<<<<<<<``,
``=======``, ``>>>>>>>`` at the start of a line), malformed XML and elements nested deeper
than ``MAX_DEPTH`` are one clear error, at their line and column.
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from dataclasses import dataclass, field
from xml.parsers import expat

from s7graph.engine.errors import SourceLocation
from s7graph.sequencer.exchange.problems import ImportFailed, Problems

__all__ = [
    "MAX_DEPTH",
    "MAX_WIRE_DEPTH",
    "ElementError",
    "Node",
    "check_wire_depth",
    "is_true",
    "parse_xml",
]

_CONFLICT = re.compile(rb"^(<{7}|={7}|>{7})(?:[ \t].*)?\r?$", re.MULTILINE)
MAX_DEPTH = 100
"""Elements nested in an imported file, at most: TIA's and PLCopen's own files nest fewer
than 20, and the readers walk the tree recursively (Python stops at about 1,000 calls)."""
MAX_WIRE_DEPTH = 100
"""Elements of a LAD/FBD network a value flows through one after another, at most (a
rung's contacts in series count as one): the networks are read recursively, up to six
Python calls an element."""


@dataclass(eq=False)
class Node:
    """One element: ``tag`` without namespace, ``ns`` its namespace URI."""

    tag: str
    ns: str
    attrib: dict[str, str]
    line: int
    col: int
    children: list[Node] = field(default_factory=list)
    parent: Node | None = None
    text: str = ""  # the element's own character data (children's not included)
    text_line: int = 0  # where its first non-blank character is
    text_col: int = 0

    def get(self, name: str, default: str = "") -> str:
        return self.attrib.get(name, default)

    def flag(self, name: str) -> bool:
        """An ``xsd:boolean`` attribute: true for ``true`` and ``1`` (absent: false)."""
        return is_true(self.get(name))

    def child(self, tag: str) -> Node | None:
        return next((c for c in self.children if c.tag == tag), None)

    def all(self, tag: str) -> list[Node]:
        return [c for c in self.children if c.tag == tag]

    def iter(self, tag: str | None = None) -> Iterator[Node]:
        if tag is None or self.tag == tag:
            yield self
        for c in self.children:
            yield from c.iter(tag)

    def find(self, *path: str) -> Node | None:
        """The first descendant along ``path`` (each a child tag)."""
        node: Node | None = self
        for tag in path:
            node = node.child(tag) if node is not None else None
        return node

    def deep_text(self) -> tuple[str, int, int]:
        """The character data of this element or, when it has none, of its first
        descendant that has some (``<ST><xhtml:p>…</xhtml:p></ST>``), with its place."""
        for n in self.iter():
            if n.text.strip():
                return n.text, n.text_line, n.text_col
        return "", self.line, self.col

    def loc(self, file: str) -> SourceLocation:
        return SourceLocation(file, self.line, self.col)


def is_true(value: str) -> bool:
    """An ``xsd:boolean`` value (XML Schema part 2, 3.2.2): ``true`` or ``1`` — both schemas
    (TC6, SimaticML) declare their flags so; surrounding blanks collapse."""
    return value.strip().lower() in ("true", "1")


class ElementError(Exception):
    """An element of a file that an importer cannot read, with the element (its place)."""

    def __init__(self, message: str, node: Node) -> None:
        super().__init__(message)
        self.message = message
        self.node = node


def check_wire_depth(depth: int, at: Node) -> None:
    """An ElementError at ``at``, the element a value reaches after ``depth`` others one
    after another, when that is ``MAX_WIRE_DEPTH`` or more (both network readers)."""
    if depth >= MAX_WIRE_DEPTH:
        raise ElementError(
            f"a value that flows through more than {MAX_WIRE_DEPTH} elements one after "
            f"another (an import reads at most {MAX_WIRE_DEPTH})",
            at,
        )


class _Refused(Exception):
    pass


class _TooDeep(Exception):
    """An element deeper than ``MAX_DEPTH``, at (line, column)."""

    def __init__(self, line: int, col: int) -> None:
        super().__init__(line, col)
        self.line, self.col = line, col


_ENCODING = re.compile(rb"""^(?:\xef\xbb\xbf)?\s*<\?xml\b[^>]*?\bencoding\s*=\s*["']([^"']*)""")


def _bad_encoding(data: bytes, problems: Problems) -> None:
    """Report the encoding of the XML declaration that expat cannot decode (an unknown
    name, or a multi-byte encoding other than UTF-8/UTF-16) as I001 at its name."""
    m = _ENCODING.match(data)
    if m is None:
        problems.error("I001", "the file's encoding cannot be decoded", problems.at(1, 1))
        return
    line = data.count(b"\n", 0, m.start(1)) + 1
    col = m.start(1) - (data.rfind(b"\n", 0, m.start(1)) + 1) + 1
    name = m.group(1).decode("latin-1")
    problems.error(
        "I001",
        f"the XML declaration names the encoding {name!r}, which this import cannot decode: "
        "save the file as UTF-8",
        problems.at(line, col),
    )


def parse_xml(data: bytes, file: str) -> Node:
    """The root element of ``data``; raises ``ImportFailed`` with one located diagnostic
    for conflict markers, a DTD or entity declaration, or malformed XML."""
    problems = Problems(file)
    m = _CONFLICT.search(data)
    if m is not None:
        line = data.count(b"\n", 0, m.start()) + 1
        problems.error(
            "I003",
            f"merge-conflict marker {m.group(1).decode()!r}: resolve the conflict before importing",
            problems.at(line, 1),
        )
        problems.fail_if_errors()
    parser = expat.ParserCreate(namespace_separator=" ")
    parser.buffer_text = False
    parser.SetParamEntityParsing(expat.XML_PARAM_ENTITY_PARSING_NEVER)
    stack: list[Node] = []
    root: list[Node] = []

    def place() -> tuple[int, int]:
        return parser.CurrentLineNumber, parser.CurrentColumnNumber + 1

    def start(name: str, attrs: dict[str, str]) -> None:
        line, col = place()
        if len(stack) == MAX_DEPTH:
            raise _TooDeep(line, col)
        ns, _, tag = name.rpartition(" ")
        node = Node(tag, ns, {k.rpartition(" ")[2]: v for k, v in attrs.items()}, line, col)
        if stack:
            node.parent = stack[-1]
            stack[-1].children.append(node)
        else:
            root.append(node)
        stack.append(node)

    def end(name: str) -> None:
        stack.pop()

    def chars(data: str) -> None:
        if not stack:
            return
        node = stack[-1]
        if not node.text.strip() and data.strip():
            line, col = place()
            lead = data[: len(data) - len(data.lstrip())]
            if "\n" in lead:
                line += lead.count("\n")
                col = len(lead) - lead.rfind("\n")
            else:
                col += len(lead)
            node.text_line, node.text_col = line, col
        node.text += data

    def refuse(*_: object) -> None:
        raise _Refused

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.CharacterDataHandler = chars
    parser.StartDoctypeDeclHandler = refuse
    parser.EntityDeclHandler = refuse
    parser.UnparsedEntityDeclHandler = refuse
    parser.ExternalEntityRefHandler = refuse  # type: ignore[assignment]
    try:
        parser.Parse(data, True)
    except _Refused:
        line, col = place()
        problems.error(
            "I002",
            "the file declares a DTD or entities; they are refused (no entity expansion)",
            problems.at(line, col),
        )
    except _TooDeep as exc:
        problems.error(
            "I001",
            f"elements nest deeper than {MAX_DEPTH} levels here (an import reads at most "
            f"{MAX_DEPTH}; TIA and PLCopen files nest fewer than 20)",
            problems.at(exc.line, exc.col),
        )
    except expat.ExpatError as exc:
        message = expat.errors.messages.get(exc.code, str(exc)) if exc.code else str(exc)
        problems.error(
            "I001", f"not well-formed XML: {message}", problems.at(exc.lineno, exc.offset + 1)
        )
    except (LookupError, ValueError):  # an encoding Python does not know, or a multi-byte one
        _bad_encoding(data, problems)
    problems.fail_if_errors()
    if not root:
        problems.error("I001", "no XML element in the file", problems.at(1, 1))
        raise ImportFailed(problems.items)
    return root[0]
