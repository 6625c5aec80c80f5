"""The README is a front door: at most 300 lines, its first lines the two commands that work
(``.ci/run`` runs exactly the second), what s7graph is not, and links into ``docs/`` that resolve —
files and the headings they point at; the links of the docs pages and of bench/README.md resolve
too."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from tests.paths import ROOT

README = ROOT / "README.md"
RUN = "pip install -e . && s7graph run examples/drill/drill.s7g --plant examples/drill/demo_plant.py --symbols examples/drill/symbols.txt --web"  # noqa: E501
TEST = "bash .ci/install && python -m pytest"
LINK = re.compile(r"\]\(([^)\s]+)\)")


def slug(heading: str) -> str:
    """GitHub's anchor of a Markdown heading."""
    text = heading.strip().lower()
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def anchors(page: Path) -> set[str]:
    text = page.read_text(encoding="utf-8")
    text = re.sub(r"```.*?```", "", text, flags=re.S)  # no headings inside code blocks
    return {slug(m[1]) for m in re.finditer(r"^#+ (.+)$", text, flags=re.M)}


def broken_links(page: Path) -> list[str]:
    """Relative links of ``page`` whose file, or heading, is not there."""
    text = re.sub(r"```.*?```", "", page.read_text(encoding="utf-8"), flags=re.S)
    broken = []
    for target in LINK.findall(text):
        if re.match(r"[a-z]+:", target):
            continue  # http(s), mailto: not ours to check
        file, _, anchor = target.partition("#")
        path = (page.parent / file).resolve() if file else page
        if not path.exists() or (anchor and path.suffix == ".md" and anchor not in anchors(path)):
            broken.append(target)
    return broken


def test_the_readme_is_at_most_300_lines() -> None:
    lines = README.read_text(encoding="utf-8").splitlines()
    assert len(lines) <= 300, f"README.md has {len(lines)} lines"


def test_the_readme_begins_with_the_two_commands_and_ci_runs_the_second() -> None:
    text = README.read_text(encoding="utf-8")
    blocks = re.findall(r"```bash\n(.*?)\n```", text, flags=re.S)
    assert blocks[:2] == [RUN, TEST]
    assert text.index(TEST) < text.index("\n## ")  # both before the first section
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8").strip().splitlines()
    assert ci[-1] == TEST


def test_every_docs_link_of_the_readme_resolves() -> None:
    text = README.read_text(encoding="utf-8")
    docs = [t for t in LINK.findall(text) if t.startswith("docs/")]
    pages = {t.partition("#")[0] for t in docs if t.partition("#")[0].endswith(".md")}
    assert pages >= {
        f"docs/{name}.md"
        for name in (
            "cli",
            "chart-format",
            "semantics",
            "runtime",
            "online-change",
            "import-export",
            "security",
            "performance",
            "architecture",
            "bus",
            "durability",
            "state-file",
            "supervisor",
        )
    }
    assert broken_links(README) == []
    assert "docs/status-view.png" in docs


PAGES = [*sorted((ROOT / "docs").glob("*.md")), ROOT / "bench" / "README.md"]


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_the_links_of_every_docs_page_resolve(page: Path) -> None:
    assert broken_links(page) == []


def test_the_readme_says_what_s7graph_is_not() -> None:
    text = README.read_text(encoding="utf-8")
    section = text.split("## What s7graph is not")[1].split("\n## ")[0]
    for words in (
        "not a fail-safe controller",
        "no safety function may depend on it",
        "emergency stop",
        "guard interlocks",
        "outside the PLC",
        "safety relay",
        "mixing plant",
    ):
        assert words in section.replace("\n", " ").lower() or words in section, words


# ---- citations a reader can follow -------------------------------------------------------
# Every reference in code, tests and docs points at something in the repository (a docs/
# page and its section, a module) or at a public source named by title. The forbidden
# forms are spelled in pieces so that this file does not match itself.
CITED = (".py", ".md", ".s7g", ".lark", ".toml", ".txt")
FORBIDDEN = {
    "SPEC" + " §": r"SPEC(\.md)? §|§[1-4]\.\d",
    "seed line": r"seed 00\d:|\b00\d_[0-9a-f]{16}\.txt|\[00\d:L\d",
    "seeds" + "-runtime": r"seeds[-]runtime|[Ss]eeds? §\d",
    "graph" + "-semantics": r"graph[-]semantics",
    "DESIGN" + ".md": r"\bDESIGN(\.md)?[ :]",
    "contracts" + ".md": r"contracts\.md",
    "behaviour" + " N": r"\b[Bb]ehaviours? \d",
    "issue" + " N": r"\b[Ii]ssues? #?\d",
}
DOC_SECTION = re.compile(r"(docs/[\w-]+\.md)((?:(?:,| and) \"[^\"\n]+\")*)")
DOTTED = re.compile(r"(?<![\w.])s7graph((?:\.[A-Za-z_]\w*)+)")
QUOTED = re.compile(r"`{1,2}((?:engine|sfb|steps|sequencer|web)(?:\.[A-Za-z_]\w*)+)(?:\(\))?`{1,2}")
FILE = re.compile(
    r"(?<![\w./-])((?:engine|sfb|steps|sequencer|web|tests|docs|examples|bench)/[\w/.-]*"
    r"\.(?:py|md|s7g|txt|lark))\b"
)
PACKAGES = ("engine", "sfb", "steps", "sequencer", "web")


def tracked() -> list[Path]:
    import subprocess

    out = subprocess.run(
        ["git", "ls-files"], cwd=ROOT, capture_output=True, text=True, check=True
    ).stdout.split()
    return [ROOT / f for f in out if f.endswith(CITED) and f != "CHANGELOG.md"]


def headings(page: Path) -> list[str]:
    text = re.sub(r"```.*?```", "", page.read_text(encoding="utf-8"), flags=re.S)
    return [m[1].replace("`", "") for m in re.finditer(r"^#+ (.+)$", text, flags=re.M)]


def resolves(dotted: str) -> bool:
    """``.a.b.c`` after ``s7graph``: a package or module, then at most names in it."""
    parts = dotted.strip(".").split(".")
    if parts[0].startswith("__"):
        return True
    if parts[0] not in PACKAGES:
        return parts[0] in ("__main__", "__version__", "cli", "lazy")
    here = ROOT / parts[0]
    for part in parts[1:]:
        if (here / part).is_dir():
            here = here / part
        elif (here / f"{part}.py").is_file():
            here = here / f"{part}.py"
        else:
            source = here / "__init__.py" if here.is_dir() else here
            text = source.read_text(encoding="utf-8")
            return re.search(rf"\b{re.escape(part)}\b", text) is not None
    return True


def test_no_citation_points_outside_the_repository() -> None:
    """No spec section signs, seed line numbers, outside notes, behaviour or issue numbers."""
    found = []
    for path in tracked():
        if path == Path(__file__).resolve():
            continue
        for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            for name, pattern in FORBIDDEN.items():
                if re.search(pattern, line):
                    found.append(f"{path.relative_to(ROOT)}:{n}: {name}: {line.strip()[:80]}")
    assert not found, "\n".join(found)


def test_every_docs_page_and_section_cited_exists() -> None:
    """A docs page cited exists, and a section cited with it (``, "Section"``) is one of
    its headings."""
    broken = []
    for path in tracked():
        for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            for m in DOC_SECTION.finditer(line):
                page = ROOT / m[1]
                where = f"{path.relative_to(ROOT)}:{n}"
                if not page.is_file():
                    broken.append(f"{where}: {m[1]}")
                    continue
                for title in re.findall(r"\"([^\"]+)\"", m[2]):
                    if not any(title in h for h in headings(page)):
                        broken.append(f'{where}: {m[1]}, "{title}"')
    assert not broken, "\n".join(broken)


def test_every_s7graph_module_cited_exists() -> None:
    """A dotted ``s7graph.`` name, or one of a package in backticks, is a module of the
    tree (or a name in one), and a file path cited is a file; the layer test's made-up
    modules are its fixtures."""
    broken = []
    for path in tracked():
        if path.name in ("test_layers.py", "test_docs.py"):
            continue
        for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            where = f"{path.relative_to(ROOT)}:{n}"
            for m in DOTTED.finditer(line):
                if not resolves(m[1]):
                    broken.append(f"{where}: s7graph{m[1]}")
            for m in QUOTED.finditer(line):
                if not resolves("." + m[1]):
                    broken.append(f"{where}: {m[1]}")
            for m in FILE.finditer(line):
                if not (ROOT / m[1]).exists():
                    broken.append(f"{where}: {m[1]}")
    assert not broken, "\n".join(broken)


def test_the_editor_tooltips_are_written_for_users() -> None:
    """The edit panel's tooltips: plain text, no reStructuredText, no citations."""
    from s7graph.sequencer.change.edit import OPERATIONS

    for op in OPERATIONS:
        assert op.hint and not re.search(r"``|docs/|§|:class:|:func:", op.hint), op.name
