"""Charts written elsewhere: import from TIA Portal SimaticML, PLCopen TC6 XML and IEC
61131-3 textual SFC; export to PLCopen and SimaticML.

``import_chart(data, file)`` detects the format (``detect_format``) and returns an
``Imported``: the chart and the problems worth knowing (each located in the file); when no
chart can be built it raises ``ImportFailed`` with every problem found; the ST bodies it
runs as SCL FCs are in ``Imported.functions`` (their source ``Imported.blocks_scl``), those
the SCL compiler refuses in ``Imported.pending``. ``export_chart`` writes a chart in one
of the XML formats (``export_reported`` also says what the format's other readers do not
see). ``importable_files(directory)`` lists the files of a directory an import can read,
with their format, for a file chooser (the browser editor's *Open*).
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING

from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.checks.diagnostics import Diagnostic, sort_key
from s7graph.sequencer.checks.structure import initial_step_warnings
from s7graph.sequencer.exchange.body_fc import BodyFc, blocks_source
from s7graph.sequencer.exchange.pending import PendingScl
from s7graph.sequencer.exchange.problems import ImportFailed, Problems
from s7graph.sequencer.text.model import Binary, Chart
from s7graph.sequencer.text.walk import rewrite
from s7graph.steps.syntax import CHAIN_OPS, chain, chain_parts

if TYPE_CHECKING:
    from s7graph.sequencer.exchange.iec_model import IecChart
    from s7graph.sequencer.exchange.plcopen import Kept

__all__ = [
    "FORMATS",
    "BodyFc",
    "ImportFailed",
    "Imported",
    "PendingScl",
    "detect_format",
    "export_chart",
    "export_reported",
    "import_chart",
    "import_file",
    "importable_files",
]

FORMATS = {
    "simaticml": "TIA Portal SimaticML (S7-GRAPH)",
    "plcopen": "PLCopen TC6 XML (SFC)",
    "iec-text": "IEC 61131-3 textual SFC",
    "s7g": "s7graph chart",
}
_SUFFIXES = (".xml", ".txt", ".st", ".sfc", ".iec", ".s7g")
_PLCOPEN = re.compile(rb"<(?:[\w.-]+:)?project\b[^>]*plcopen\.org/xml/tc6", re.IGNORECASE)
_GRAPH = re.compile(rb"NetworkSource/Graph/v\d+|<ProgrammingLanguage>\s*GRAPH\s*<", re.IGNORECASE)
_SFC_TEXT = re.compile(rb"\bINITIAL_STEP\b", re.IGNORECASE)
_S7G = re.compile(rb"^\s*(?:\(\*[\s\S]*?\*\)\s*|//[^\n]*\n\s*)*FUNCTION_BLOCK\s+\"", re.IGNORECASE)


@dataclass(frozen=True)
class Imported:
    """An imported chart, its source format and what the import reports about it."""

    chart: Chart
    format: str
    problems: list[Diagnostic] = field(default_factory=list)
    pending: list[PendingScl] = field(default_factory=list)  # bodies the SCL FCs cannot run
    functions: list[BodyFc] = field(default_factory=list)  # bodies run as SCL FCs

    @property
    def blocks_scl(self) -> str:
        """The SCL source of the FCs the chart calls for its ST bodies ("" for none): load
        it with the chart (``s7graph import -o chart.s7g`` writes it to ``chart.scl``)."""
        return blocks_source(self.functions, self.chart.name)


def canonical_chains(chart: Chart) -> Chart:
    """``chart`` with every AND/OR/XOR chain rebuilt as ``steps.syntax.chain`` builds it."""

    def one(node: object) -> object:
        if isinstance(node, Binary) and node.op in CHAIN_OPS:
            return chain(node.op, chain_parts(node))
        return node

    return rewrite(chart, one)


_WIDE = (  # byte order marks, and XML's first "<?" without one (XML 1.0 appendix F)
    (b"\x00\x00\xfe\xff", "utf-32-be"),
    (b"\xff\xfe\x00\x00", "utf-32-le"),
    (b"\xfe\xff", "utf-16-be"),
    (b"\xff\xfe", "utf-16-le"),
    (b"\x00<\x00?", "utf-16-be"),
    (b"<\x00?\x00", "utf-16-le"),
)
_DECLARED = re.compile(
    rb"""^(\s*<\?xml\b[^>]*?\bencoding\s*=\s*["'])(?:utf|ucs)-?(?:16|32|2|4)[\w-]*""", re.I
)


def as_utf8(data: bytes) -> bytes:
    """``data`` in UTF-8: a file saved in UTF-16 or UTF-32 (Windows' "Unicode") is decoded
    by its byte order mark — or, for XML without one, by its ``<?`` — and its XML
    declaration then names UTF-8; lines stay where they were. Other data is unchanged."""
    codec = next((c for bom, c in _WIDE if data.startswith(bom)), None)
    if codec is None:
        return data
    if len(data) % (4 if "32" in codec else 2):  # cut short: decode what is whole
        data = data[: len(data) - len(data) % (4 if "32" in codec else 2)]
    try:
        text = data.decode(codec).removeprefix("\ufeff")
    except UnicodeDecodeError:
        return data
    return _DECLARED.sub(rb"\1utf-8", text.encode("utf-8"), count=1)


def detect_format(data: bytes) -> str | None:
    """``simaticml`` | ``plcopen`` | ``iec-text`` | ``s7g`` | None, from the content."""
    head = as_utf8(data[:200_000]).removeprefix(b"\xef\xbb\xbf")
    if head.lstrip().startswith(b"<"):
        if _PLCOPEN.search(head):
            return "plcopen"
        if _GRAPH.search(head) and re.search(rb"<(?:[\w.-]+:)?Document\b", head):
            return "simaticml"
        return None
    if _S7G.match(head):
        return "s7g"
    if _SFC_TEXT.search(head):
        return "iec-text"
    return None


def _text(data: bytes) -> str:
    raw = data.removeprefix(b"\xef\xbb\xbf")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        text = raw.decode("latin-1")
    return text.replace("\r\n", "\n").replace("\r", "\n")


def import_chart(
    data: bytes,
    file: str = "<input>",
    *,
    pou: str | None = None,
    symbols: SymbolTable | None = None,
) -> Imported:
    """Import one chart from ``data`` (raises ``ImportFailed`` with located problems); its
    AND/OR/XOR chains in the parser's shape (``steps.syntax.chain``), so that the chart is
    the model its ``.s7g`` text parses to. A sequence without an initial step is reported
    as ``s7graph check`` reports it (W103), but for a `.s7g` file."""
    found = _import_chart(data, file, pou=pou, symbols=symbols)
    chart = canonical_chains(found.chart)
    if found.format == "s7g":  # the chart itself: ``check`` says what it says
        return replace(found, chart=chart)
    more = [d for d in initial_step_warnings(chart) if d not in found.problems]
    return replace(found, chart=chart, problems=sorted(found.problems + more, key=sort_key))


def _import_chart(
    data: bytes,
    file: str = "<input>",
    *,
    pou: str | None = None,
    symbols: SymbolTable | None = None,
) -> Imported:
    """Import one chart from ``data`` (raises ``ImportFailed`` with located problems).
    ``pou`` chooses a POU when the file holds several charts; ``symbols`` gives the tag
    table a SimaticML block export refers to."""
    from s7graph.sequencer.exchange.iec_text import read_iec_text
    from s7graph.sequencer.exchange.iec_to_chart import iec_to_chart
    from s7graph.sequencer.exchange.own_data import edited_at
    from s7graph.sequencer.exchange.plcopen import Kept, read_plcopen
    from s7graph.sequencer.exchange.simaticml import read_simaticml
    from s7graph.sequencer.exchange.xmltree import parse_xml
    from s7graph.sequencer.text.parse import ChartSyntaxError, parse_chart

    problems = Problems(file)
    data = as_utf8(data)
    found_fmt = detect_format(data)
    if found_fmt is None:
        looks_xml = data.removeprefix(b"\xef\xbb\xbf").lstrip().startswith(b"<")
        if looks_xml:
            parse_xml(data, file)  # a malformed file says so first
        what = (
            "an XML file that is neither PLCopen TC6 nor a SimaticML GRAPH block"
            if (looks_xml)
            else "no SFC in the file (no INITIAL_STEP, no known XML)"
        )
        problems.error("I001", f"not a chart this import reads: {what}", problems.at(1, 1))
        problems.fail_if_errors()
    fmt: str = found_fmt or ""
    if fmt == "simaticml":
        chart = read_simaticml(parse_xml(data, file), problems, symbols)
        return Imported(chart, "simaticml", sorted(problems.items, key=sort_key))
    if fmt == "s7g":
        try:
            return Imported(parse_chart(_text(data), file), "s7g")
        except ChartSyntaxError as exc:
            raise ImportFailed(exc.diagnostics) from None
    if fmt == "plcopen":
        found: list[IecChart | Kept] = list(read_plcopen(parse_xml(data, file), problems))
    else:
        found = list(read_iec_text(_text(data), file, problems))
    problems.fail_if_errors()
    while isinstance(item := found[_picked(found, pou, problems)], Kept):
        try:  # s7graph's own export: its source, kept in the file
            chart = parse_chart("\n" * (item.line - 1) + item.text, file)
        except ChartSyntaxError as exc:
            raise ImportFailed(exc.diagnostics) from None
        edit = edited_at(item, chart, file)
        if edit is None:
            return Imported(_beside(chart, symbols), fmt, [])
        problems.warn("I024", edit[1], edit[0])  # edited since: read from its SFC
        at = found.index(item)
        found[at : at + 1] = item.sfc()
        problems.fail_if_errors()
    chart, pending, functions = iec_to_chart(item, problems)
    return Imported(chart, fmt, sorted(problems.items, key=sort_key), pending, functions)


def _picked(found: Sequence[IecChart | Kept], pou: str | None, problems: Problems) -> int:
    """The index of the chart to import: the one ``pou`` names (``_pick``), else the only
    one; I004 or I005 (``ImportFailed``) when there is no such chart or more than one."""
    names = [c.name for c in found]
    if not found:
        problems.error("I004", "no POU with an SFC body in the file", problems.at(1, 1))
        problems.fail_if_errors()
    if pou is not None:
        picked = _pick(pou, names)
        if len(picked) != 1:
            what = f"no chart {pou}" if not picked else f"{len(picked)} charts of {pou}"
            problems.error(
                "I005",
                f"{what} in the file; it holds {', '.join(names)}",
                problems.at(1, 1),
            )
            problems.fail_if_errors()
        return picked[0]
    if len(found) > 1:
        problems.error(
            "I005",
            f"the file holds {len(found)} charts ({', '.join(names)}); choose one with --pou",
            problems.at(1, 1),
        )
        raise ImportFailed(problems.items, tuple(names))
    return 0


def _beside(chart: Chart, symbols: SymbolTable | None) -> Chart:
    """The chart s7graph kept in its export, but for the symbols it carries that the
    symbol table given to the import holds already (``db_reads.not_in_table``)."""
    from s7graph.sequencer.exchange.db_reads import not_in_table

    if symbols is None or not chart.symbols:
        return chart
    return replace(chart, symbols=not_in_table(chart.symbols, symbols))


def _pick(pou: str, names: list[str]) -> list[int]:
    """The charts ``--pou`` names: the one of that name; else those of the POU (``Crane``:
    ``Crane.Auto`` …) or of that action (``Auto``: ``Crane.Auto``)."""
    want = pou.upper()
    exact = [i for i, n in enumerate(names) if n.upper() == want]
    if exact:
        return exact
    return [
        i
        for i, n in enumerate(names)
        if n.upper().startswith(want + ".") or n.upper().endswith("." + want)
    ]


def import_file(
    path: Path, *, pou: str | None = None, symbols: SymbolTable | None = None
) -> Imported:
    """``import_chart`` of a file (an unreadable file is ``ImportFailed`` too)."""
    problems = Problems(str(path))
    try:
        data = Path(path).read_bytes()
    except OSError as exc:
        problems.error("I001", f"cannot read the file: {exc.strerror}", problems.at(1, 1))
        raise ImportFailed(problems.items) from None
    return import_chart(data, str(path), pou=pou, symbols=symbols)


def importable_files(directory: Path) -> list[tuple[Path, str]]:
    """The files of ``directory`` (not its subdirectories) that ``import`` reads, sorted by
    name, with their format — what the editor's *Open* offers besides `.s7g` charts."""
    out: list[tuple[Path, str]] = []
    for path in sorted(Path(directory).iterdir()):
        if not path.is_file() or path.suffix.lower() not in _SUFFIXES:
            continue
        try:
            with path.open("rb") as f:
                head = f.read(200_000)
        except OSError:
            continue
        fmt = detect_format(head)
        if fmt is not None:
            out.append((path, fmt))
    return out


def export_chart(chart: Chart, to: str, symbols: SymbolTable | None = None) -> str:
    """``chart`` as a ``plcopen`` or ``simaticml`` document (``ValueError`` for a chart
    part the format cannot hold)."""
    return export_reported(chart, to, symbols)[0]


def export_reported(
    chart: Chart, to: str, symbols: SymbolTable | None = None
) -> tuple[str, list[Diagnostic]]:
    """``export_chart``, and what of the chart the format's other readers do not see or run
    otherwise, each located in the chart (``X01x`` warnings)."""
    if to == "plcopen":
        from s7graph.sequencer.exchange.export_plcopen import export_plcopen

        return export_plcopen(chart, symbols)
    if to == "simaticml":
        from s7graph.sequencer.exchange.export_simaticml import export_simaticml

        return export_simaticml(chart, symbols)
    raise ValueError(f"unknown export format {to!r}: plcopen or simaticml")
